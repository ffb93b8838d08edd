// Description of the machine a benchmark ran on (docs/design.md §3.7 provenance), read from the
// Linux pseudo-filesystems. Every value that could not be read is left empty (std::nullopt / JSON
// null): a result must never state a guess as a fact.
#pragma once

#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace robotperf::sysinfo {

// cpufreq state of one logical CPU (/sys/devices/system/cpu/cpuN/cpufreq).
struct CpuFrequency {
  unsigned cpu = 0;
  std::optional<std::uint64_t> current_khz;  // scaling_cur_freq
  std::optional<std::uint64_t> min_khz;      // cpuinfo_min_freq (hardware limit)
  std::optional<std::uint64_t> max_khz;      // cpuinfo_max_freq (hardware limit)
  std::optional<std::string> governor;       // scaling_governor
};

struct GpuInfo {
  // Where the entry came from: "nvidia" (/proc/driver/nvidia/gpus) or "drm" (/sys/class/drm).
  std::string source;
  std::optional<std::string> model;           // NVIDIA "Model:" line
  std::optional<std::string> pci_address;     // e.g. "0000:01:00.0"
  std::optional<std::string> vendor_id;       // PCI vendor id, e.g. "0x10de"
  std::optional<std::string> device_id;       // PCI device id
  std::optional<std::string> vendor_name;     // from vendor_id, for well-known vendors only
  std::optional<std::string> driver;          // kernel driver, e.g. "nvidia", "amdgpu", "i915"
  std::optional<std::string> driver_version;  // NVIDIA kernel module version
};

struct MachineInfo {
  std::optional<std::string> hostname;
  std::optional<std::string> architecture;  // /proc/sys/kernel/arch, e.g. "x86_64", "aarch64"
  std::optional<std::string> os_name;       // PRETTY_NAME of /etc/os-release
  // Device-tree model of ARM boards, e.g. "NVIDIA Jetson AGX Orin Developer Kit".
  std::optional<std::string> board_model;
  std::optional<std::string> system_vendor;   // /sys/class/dmi/id/sys_vendor
  std::optional<std::string> system_product;  // /sys/class/dmi/id/product_name

  // /proc/cpuinfo "model name", else "Hardware", else "Model", else the ARM core names decoded
  // from "CPU implementer"/"CPU part" (e.g. "ARM Cortex-A78AE"; big.LITTLE parts joined by " + ").
  std::optional<std::string> cpu_model;
  std::optional<unsigned> logical_cpus;  // online CPUs
  std::optional<unsigned> physical_cores;
  std::optional<unsigned> sockets;
  std::optional<bool> smt_enabled;  // simultaneous multithreading (Hyper-Threading) active

  std::vector<CpuFrequency> cpu_frequencies;  // one entry per CPU that has cpufreq
  // Summary over cpu_frequencies: range of current frequencies, lowest hardware minimum, highest
  // hardware maximum, and the distinct governors in sorted order.
  std::optional<std::uint64_t> current_frequency_min_khz;
  std::optional<std::uint64_t> current_frequency_max_khz;
  std::optional<std::uint64_t> frequency_min_khz;
  std::optional<std::uint64_t> frequency_max_khz;
  std::vector<std::string> governors;

  std::optional<std::uint64_t> memory_total_bytes;  // /proc/meminfo MemTotal

  std::optional<std::string> kernel_release;  // /proc/sys/kernel/osrelease
  std::optional<std::string> kernel_version;  // /proc/sys/kernel/version, e.g. "#1 SMP PREEMPT_RT"
  std::optional<bool> preempt_rt;             // /sys/kernel/realtime or "PREEMPT_RT" in version

  // True when a container hint was found (/.dockerenv, /run/.containerenv,
  // /run/systemd/container, container names in /proc/1/cgroup). Without a hint the machine may
  // still be a container whose runtime leaves no trace.
  bool in_container = false;
  std::optional<std::string> container_runtime;  // "docker", "podman", "kubernetes", "lxc", ...
  // From the x86 "hypervisor" CPU flag or a DMI vendor that only makes virtual machines; empty
  // when neither source can tell.
  std::optional<bool> virtual_machine;

  std::vector<GpuInfo> gpus;
};

// Reads everything from files under `root` (normally "/"; tests pass a fixture tree). Never throws
// for missing or unreadable files.
MachineInfo collect_machine_info(const std::filesystem::path& root = "/");

nlohmann::json to_json(const MachineInfo& info);

// One line for a results table, e.g.
// "Intel(R) Xeon(R) Gold 6230 · 2 CPUs (2 cores) · 23.4 GiB · Linux 6.1.0-18-amd64 · Tesla T4".
std::string summary_line(const MachineInfo& info);

}  // namespace robotperf::sysinfo
