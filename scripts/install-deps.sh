#!/usr/bin/env bash
# Installs the Debian 12 packages robotperf needs to build and test.
# Idempotent: returns at once when every package is already installed.
# --cuda: also a CUDA toolkit, for the perception kernels' cuda backend (skipped when nvcc is
# already there, e.g. NVIDIA's own toolkit in /usr/local/cuda).
set -euo pipefail

cuda=false
for arg in "$@"; do
  case "$arg" in
    --cuda) cuda=true ;;
    *) echo "install-deps: unknown argument $arg (known: --cuda)" >&2; exit 2 ;;
  esac
done

packages=(
  g++ cmake make pkg-config git
  iproute2  # ip and tc: --netns (n3, n4)
  wireguard-go  # the userspace WireGuard of --netns tunnels (n5-n8): no kernel module needed
  wireguard-tools  # wg: the tunnels' keys and peers (n5-n8)
  procps  # sysctl: forwarding in the router namespace of routed --netns paths (n7, n8)
  libfastrtps-dev libfastcdr-dev cyclonedds-dev cyclonedds-tools  # cyclonedds-tools: idlc, for bench_transport
  libssl-dev  # DDS Security keystores (security init)
  libopencv-dev
  pocl-opencl-icd clinfo  # an OpenCL CPU device: the opencl backend runs and is tested everywhere
  libyaml-cpp-dev nlohmann-json3-dev libcli11-dev
  libsqlite3-dev ros2-test-interface-files
  libpq-dev  # results push and --from: a lab's shared PostgreSQL results database
  postgresql  # its server binaries, which the PostgreSQL tests and bench start themselves
  libzstd-dev liblz4-dev libdeflate-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libboost-context-dev  # fibers: the cuda emulation's kernels whose threads wait for each other
  liblttng-ust-dev lttng-tools babeltrace2
  chromium  # headless, for the report rendering test
  liborocos-kdl-dev liburdfdom-dev libfcl-dev libbullet-dev libompl-dev libeigen3-dev  # manipulation (d1-d6)
  libapriltag-dev  # localization b3
  help2man  # the man page, made from --help
  mkdocs  # the manual (docs/), built by scripts/docs.sh
  zsh  # to test the zsh completion script
)

# Debian's CUDA toolkit is in the non-free component, which a default sources.list leaves out.
cuda_package=nvidia-cuda-toolkit
if $cuda && ! command -v nvcc >/dev/null && [[ ! -x /usr/local/cuda/bin/nvcc ]]; then
  packages+=("$cuda_package")
fi

missing=()
for p in "${packages[@]}"; do
  status=$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null || true)
  [[ "$status" == "install ok installed" ]] || missing+=("$p")
done
[[ ${#missing[@]} -eq 0 ]] && exit 0

echo "install-deps: installing ${missing[*]}" >&2
sudo=()
if [[ $(id -u) -ne 0 ]]; then
  command -v sudo >/dev/null || { echo "install-deps: not root and no sudo; install as root: ${missing[*]}" >&2; exit 1; }
  sudo=(sudo)
fi
export DEBIAN_FRONTEND=noninteractive
"${sudo[@]}" apt-get update -qq
if [[ " ${missing[*]} " == *" $cuda_package "* ]]; then
  candidate=$(apt-cache policy "$cuda_package" | sed -n 's/^ *Candidate: *//p')
  if [[ -z "$candidate" || "$candidate" == "(none)" ]]; then
    echo "install-deps: apt has no $cuda_package: enable Debian's non-free component (add non-free to the components in /etc/apt/sources.list) or install NVIDIA's CUDA toolkit" >&2
    exit 1
  fi
fi
"${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
