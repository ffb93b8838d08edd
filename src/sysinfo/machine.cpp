#include "robotperf/sysinfo/machine.hpp"

#include <sys/utsname.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cstdio>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string_view>
#include <system_error>
#include <utility>

namespace robotperf::sysinfo {
namespace {

namespace fs = std::filesystem;

std::string_view trim(std::string_view text) {
  // Device-tree strings end in NUL; sysfs and procfs values end in a newline.
  constexpr std::string_view kTrimmed = std::string_view(" \t\r\n\0", 5);
  const auto first = text.find_first_not_of(kTrimmed);
  if (first == std::string_view::npos) return {};
  const auto last = text.find_last_not_of(kTrimmed);
  return text.substr(first, last - first + 1);
}

bool starts_with(std::string_view text, std::string_view prefix) {
  return text.substr(0, prefix.size()) == prefix;
}

// The whole file, or nullopt when it cannot be read.
std::optional<std::string> read_file(const fs::path& path) {
  std::ifstream stream(path, std::ios::binary);
  if (!stream) return std::nullopt;
  std::ostringstream content;
  content << stream.rdbuf();
  if (stream.bad()) return std::nullopt;
  return std::move(content).str();
}

// The trimmed file content, or nullopt when the file is unreadable or blank.
std::optional<std::string> read_value(const fs::path& path) {
  const auto content = read_file(path);
  if (!content) return std::nullopt;
  const std::string_view value = trim(*content);
  if (value.empty()) return std::nullopt;
  return std::string(value);
}

template <typename Integer>
std::optional<Integer> parse_integer(std::string_view text) {
  text = trim(text);
  Integer value{};
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size()) return std::nullopt;
  return value;
}

template <typename Integer>
std::optional<Integer> read_integer(const fs::path& path) {
  const auto value = read_value(path);
  if (!value) return std::nullopt;
  return parse_integer<Integer>(*value);
}

// Kernel CPU list syntax: "0-3,8,10-11".
std::optional<std::vector<unsigned>> parse_cpu_list(std::string_view text) {
  std::vector<unsigned> cpus;
  text = trim(text);
  while (!text.empty()) {
    const auto comma = text.find(',');
    const std::string_view range = text.substr(0, comma);
    text = comma == std::string_view::npos ? std::string_view() : text.substr(comma + 1);
    const auto dash = range.find('-');
    const auto first = parse_integer<unsigned>(range.substr(0, dash));
    const auto last =
        dash == std::string_view::npos ? first : parse_integer<unsigned>(range.substr(dash + 1));
    if (!first || !last || *last < *first) return std::nullopt;
    for (unsigned cpu = *first; cpu <= *last; ++cpu) cpus.push_back(cpu);
  }
  if (cpus.empty()) return std::nullopt;
  return cpus;
}

// /proc/cpuinfo as blank-line separated blocks of "key : value" lines. On x86 every block is a
// processor; ARM kernels may add a trailing block with "Hardware", "Revision", "Model".
using CpuinfoBlock = std::map<std::string, std::string, std::less<>>;

std::vector<CpuinfoBlock> parse_cpuinfo(const std::string& content) {
  std::vector<CpuinfoBlock> blocks(1);
  std::istringstream lines(content);
  std::string line;
  while (std::getline(lines, line)) {
    if (trim(line).empty()) {
      if (!blocks.back().empty()) blocks.emplace_back();
      continue;
    }
    const auto colon = line.find(':');
    if (colon == std::string::npos) continue;
    const std::string_view key = trim(std::string_view(line).substr(0, colon));
    const std::string_view value = trim(std::string_view(line).substr(colon + 1));
    blocks.back().emplace(std::string(key), std::string(value));
  }
  if (blocks.back().empty()) blocks.pop_back();
  return blocks;
}

std::optional<std::string> first_value(const std::vector<CpuinfoBlock>& blocks,
                                       std::string_view key) {
  for (const auto& block : blocks) {
    const auto found = block.find(key);
    if (found != block.end() && !found->second.empty()) return found->second;
  }
  return std::nullopt;
}

// Names of common ARM cores by (implementer, part), as the kernel prints them in /proc/cpuinfo.
std::optional<std::string> arm_core_name(std::string_view implementer, std::string_view part) {
  struct KnownCore {
    std::string_view implementer;
    std::string_view part;
    std::string_view name;
  };
  static constexpr KnownCore kKnownCores[] = {
      {"0x41", "0xd03", "ARM Cortex-A53"},    {"0x41", "0xd04", "ARM Cortex-A35"},
      {"0x41", "0xd05", "ARM Cortex-A55"},    {"0x41", "0xd07", "ARM Cortex-A57"},
      {"0x41", "0xd08", "ARM Cortex-A72"},    {"0x41", "0xd09", "ARM Cortex-A73"},
      {"0x41", "0xd0a", "ARM Cortex-A75"},    {"0x41", "0xd0b", "ARM Cortex-A76"},
      {"0x41", "0xd0c", "ARM Neoverse-N1"},   {"0x41", "0xd0d", "ARM Cortex-A77"},
      {"0x41", "0xd40", "ARM Neoverse-V1"},   {"0x41", "0xd41", "ARM Cortex-A78"},
      {"0x41", "0xd42", "ARM Cortex-A78AE"},  {"0x41", "0xd44", "ARM Cortex-X1"},
      {"0x41", "0xd46", "ARM Cortex-A510"},   {"0x41", "0xd47", "ARM Cortex-A710"},
      {"0x41", "0xd48", "ARM Cortex-X2"},     {"0x41", "0xd49", "ARM Neoverse-N2"},
      {"0x41", "0xd4b", "ARM Cortex-A78C"},   {"0x41", "0xd4d", "ARM Cortex-A715"},
      {"0x41", "0xd4e", "ARM Cortex-X3"},     {"0x41", "0xd4f", "ARM Neoverse-V2"},
      {"0x41", "0xd80", "ARM Cortex-A520"},   {"0x41", "0xd81", "ARM Cortex-A720"},
      {"0x41", "0xd82", "ARM Cortex-X4"},     {"0x4e", "0x004", "NVIDIA Carmel"},
      {"0x61", "0x022", "Apple M1 Icestorm"}, {"0x61", "0x023", "Apple M1 Firestorm"},
  };
  for (const auto& core : kKnownCores) {
    if (core.implementer == implementer && core.part == part) return std::string(core.name);
  }
  return std::nullopt;
}

// Distinct decoded core names in order of first appearance, e.g. "ARM Cortex-A76 + ARM
// Cortex-A55" on big.LITTLE. Nullopt when any core is unknown, so that a partial list is never
// presented as the whole CPU.
std::optional<std::string> decode_arm_cores(const std::vector<CpuinfoBlock>& blocks) {
  std::vector<std::string> names;
  for (const auto& block : blocks) {
    const auto implementer = block.find("CPU implementer");
    const auto part = block.find("CPU part");
    if (implementer == block.end() || part == block.end()) continue;
    const auto name = arm_core_name(implementer->second, part->second);
    if (!name) return std::nullopt;
    if (std::find(names.begin(), names.end(), *name) == names.end()) names.push_back(*name);
  }
  if (names.empty()) return std::nullopt;
  std::string joined = names.front();
  for (std::size_t i = 1; i < names.size(); ++i) joined += " + " + names[i];
  return joined;
}

std::vector<unsigned> processor_numbers(const std::vector<CpuinfoBlock>& blocks) {
  std::vector<unsigned> cpus;
  for (const auto& block : blocks) {
    const auto processor = block.find("processor");
    if (processor == block.end()) continue;
    if (const auto number = parse_integer<unsigned>(processor->second)) cpus.push_back(*number);
  }
  return cpus;
}

// Numbers of the cpuN directories in a sysfs cpu directory, ascending.
std::vector<unsigned> cpu_directories(const fs::path& cpu_root) {
  std::vector<unsigned> cpus;
  std::error_code error;
  for (const auto& entry : fs::directory_iterator(cpu_root, error)) {
    const std::string name = entry.path().filename().string();
    if (!starts_with(name, "cpu")) continue;
    if (const auto number = parse_integer<unsigned>(std::string_view(name).substr(3))) {
      cpus.push_back(*number);
    }
  }
  std::sort(cpus.begin(), cpus.end());
  return cpus;
}

struct Topology {
  unsigned cores = 0;
  unsigned sockets = 0;
};

// From sysfs: a core is a distinct set of thread siblings, a socket a distinct package id.
std::optional<Topology> topology_from_sysfs(const fs::path& cpu_root,
                                            const std::vector<unsigned>& cpus) {
  std::set<std::string> cores;
  std::set<long> packages;
  for (const unsigned cpu : cpus) {
    const fs::path topology = cpu_root / ("cpu" + std::to_string(cpu)) / "topology";
    auto siblings = read_value(topology / "core_cpus_list");
    if (!siblings) siblings = read_value(topology / "thread_siblings_list");
    const auto package = read_integer<long>(topology / "physical_package_id");
    // Some ARM firmware reports package id -1, meaning "not known".
    if (!siblings || !package || *package < 0) return std::nullopt;
    cores.insert(*siblings);
    packages.insert(*package);
  }
  if (cores.empty()) return std::nullopt;
  return Topology{static_cast<unsigned>(cores.size()), static_cast<unsigned>(packages.size())};
}

// From /proc/cpuinfo: a core is a distinct (physical id, core id), a socket a distinct physical id.
std::optional<Topology> topology_from_cpuinfo(const std::vector<CpuinfoBlock>& blocks) {
  std::set<std::pair<std::string, std::string>> cores;
  std::set<std::string> packages;
  for (const auto& block : blocks) {
    if (!block.contains("processor")) continue;
    const auto package = block.find("physical id");
    const auto core = block.find("core id");
    if (package == block.end() || core == block.end()) return std::nullopt;
    cores.emplace(package->second, core->second);
    packages.insert(package->second);
  }
  if (cores.empty()) return std::nullopt;
  return Topology{static_cast<unsigned>(cores.size()), static_cast<unsigned>(packages.size())};
}

void collect_cpu(const fs::path& root, MachineInfo& info) {
  const fs::path cpu_root = root / "sys/devices/system/cpu";
  const auto cpuinfo_text = read_file(root / "proc/cpuinfo");
  const std::vector<CpuinfoBlock> cpuinfo =
      cpuinfo_text ? parse_cpuinfo(*cpuinfo_text) : std::vector<CpuinfoBlock>{};

  info.cpu_model = first_value(cpuinfo, "model name");
  // The cores before the SoC line: Raspberry Pi kernels say "BCM2835" on every Pi.
  if (!info.cpu_model) info.cpu_model = decode_arm_cores(cpuinfo);
  if (!info.cpu_model) info.cpu_model = first_value(cpuinfo, "Hardware");
  if (!info.cpu_model) info.cpu_model = first_value(cpuinfo, "Model");

  std::vector<unsigned> online;
  if (const auto list = read_value(cpu_root / "online")) {
    online = parse_cpu_list(*list).value_or(std::vector<unsigned>{});
  }
  if (online.empty()) online = processor_numbers(cpuinfo);
  if (!online.empty()) info.logical_cpus = static_cast<unsigned>(online.size());

  auto topology = topology_from_sysfs(cpu_root, online);
  if (!topology) topology = topology_from_cpuinfo(cpuinfo);
  if (topology) {
    info.physical_cores = topology->cores;
    info.sockets = topology->sockets;
  }

  if (const auto active = read_integer<int>(cpu_root / "smt/active")) {
    info.smt_enabled = *active != 0;
  } else if (info.logical_cpus && info.physical_cores) {
    info.smt_enabled = *info.logical_cpus > *info.physical_cores;
  }

  const std::vector<unsigned> frequency_cpus = online.empty() ? cpu_directories(cpu_root) : online;
  std::set<std::string> governors;
  for (const unsigned cpu : frequency_cpus) {
    const fs::path cpufreq = cpu_root / ("cpu" + std::to_string(cpu)) / "cpufreq";
    CpuFrequency frequency;
    frequency.cpu = cpu;
    frequency.current_khz = read_integer<std::uint64_t>(cpufreq / "scaling_cur_freq");
    frequency.min_khz = read_integer<std::uint64_t>(cpufreq / "cpuinfo_min_freq");
    frequency.max_khz = read_integer<std::uint64_t>(cpufreq / "cpuinfo_max_freq");
    frequency.governor = read_value(cpufreq / "scaling_governor");
    if (!frequency.current_khz && !frequency.min_khz && !frequency.max_khz && !frequency.governor) {
      continue;
    }
    const auto lower = [](std::optional<std::uint64_t>& summary, std::optional<std::uint64_t> v) {
      if (v) summary = summary ? std::min(*summary, *v) : *v;
    };
    const auto upper = [](std::optional<std::uint64_t>& summary, std::optional<std::uint64_t> v) {
      if (v) summary = summary ? std::max(*summary, *v) : *v;
    };
    lower(info.current_frequency_min_khz, frequency.current_khz);
    upper(info.current_frequency_max_khz, frequency.current_khz);
    lower(info.frequency_min_khz, frequency.min_khz);
    upper(info.frequency_max_khz, frequency.max_khz);
    if (frequency.governor) governors.insert(*frequency.governor);
    info.cpu_frequencies.push_back(std::move(frequency));
  }
  info.governors.assign(governors.begin(), governors.end());

  // Only x86 reports the hypervisor flag; elsewhere the flags cannot tell a VM from bare metal.
  if (const auto flags = first_value(cpuinfo, "flags")) {
    std::istringstream tokens(*flags);
    std::string flag;
    bool hypervisor = false;
    while (tokens >> flag) hypervisor = hypervisor || flag == "hypervisor";
    info.virtual_machine = hypervisor;
  }
}

std::optional<std::uint64_t> read_memory_total_bytes(const fs::path& root) {
  const auto meminfo = read_file(root / "proc/meminfo");
  if (!meminfo) return std::nullopt;
  std::istringstream lines(*meminfo);
  std::string line;
  while (std::getline(lines, line)) {
    if (!starts_with(line, "MemTotal:")) continue;
    std::istringstream fields(line.substr(9));
    std::uint64_t amount = 0;
    std::string unit;
    if (!(fields >> amount)) return std::nullopt;
    fields >> unit;
    // The kernel always prints kB (meaning KiB); a bare number would be bytes.
    if (unit == "kB") return amount * 1024;
    if (unit.empty()) return amount;
    return std::nullopt;
  }
  return std::nullopt;
}

std::optional<std::string> read_os_name(const fs::path& root) {
  auto os_release = read_file(root / "etc/os-release");
  if (!os_release) os_release = read_file(root / "usr/lib/os-release");
  if (!os_release) return std::nullopt;
  std::istringstream lines(*os_release);
  std::string line;
  while (std::getline(lines, line)) {
    if (!starts_with(line, "PRETTY_NAME=")) continue;
    std::string_view value = trim(std::string_view(line).substr(12));
    if (value.size() >= 2 && (value.front() == '"' || value.front() == '\'') &&
        value.back() == value.front()) {
      value = value.substr(1, value.size() - 2);
    }
    if (value.empty()) return std::nullopt;
    return std::string(value);
  }
  return std::nullopt;
}

void collect_kernel(const fs::path& root, MachineInfo& info) {
  info.kernel_release = read_value(root / "proc/sys/kernel/osrelease");
  info.kernel_version = read_value(root / "proc/sys/kernel/version");
  if (const auto realtime = read_integer<int>(root / "sys/kernel/realtime")) {
    info.preempt_rt = *realtime == 1;
    return;
  }
  auto version = read_value(root / "proc/version");
  if (!version) version = info.kernel_version;
  if (version) {
    // Kernels before 5.x print "PREEMPT RT", later ones "PREEMPT_RT".
    info.preempt_rt = version->find("PREEMPT_RT") != std::string::npos ||
                      version->find("PREEMPT RT") != std::string::npos;
  }
}

void collect_container(const fs::path& root, MachineInfo& info) {
  const auto cgroup = read_file(root / "proc/1/cgroup").value_or("");
  const auto cgroup_mentions = [&cgroup](std::string_view word) {
    return cgroup.find(word) != std::string::npos;
  };
  std::optional<std::string> runtime;
  std::error_code error;
  if (cgroup_mentions("kubepods")) {
    runtime = "kubernetes";
  } else if (fs::exists(root / "run/.containerenv", error)) {
    runtime = "podman";
  } else if (fs::exists(root / ".dockerenv", error)) {
    runtime = "docker";
  } else if (const auto systemd = read_value(root / "run/systemd/container")) {
    runtime = systemd;
  } else if (cgroup_mentions("libpod")) {
    runtime = "podman";
  } else if (cgroup_mentions("docker")) {
    runtime = "docker";
  } else if (cgroup_mentions("containerd")) {
    runtime = "containerd";
  } else if (cgroup_mentions("lxc")) {
    runtime = "lxc";
  }
  info.in_container = runtime.has_value();
  info.container_runtime = std::move(runtime);
}

bool is_virtual_machine_vendor(const std::optional<std::string>& vendor,
                               const std::optional<std::string>& product) {
  // Vendors that only make virtual hardware; cloud vendors also sell bare metal.
  static constexpr std::string_view kVirtualVendors[] = {"QEMU", "VMware", "innotek",
                                                         "Xen",  "Bochs",  "Parallels"};
  if (vendor) {
    for (const auto name : kVirtualVendors) {
      if (starts_with(*vendor, name)) return true;
    }
  }
  return product && (*product == "KVM" || *product == "VirtualBox" ||
                     (*product == "Virtual Machine" && vendor == "Microsoft Corporation"));
}

std::optional<std::string> pci_vendor_name(std::string_view vendor_id) {
  static constexpr std::pair<std::string_view, std::string_view> kVendors[] = {
      {"0x10de", "NVIDIA"}, {"0x1002", "AMD"},    {"0x8086", "Intel"},  {"0x1a03", "ASPEED"},
      {"0x102b", "Matrox"}, {"0x1af4", "virtio"}, {"0x15ad", "VMware"}, {"0x1234", "QEMU"},
  };
  for (const auto& [id, name] : kVendors) {
    if (id == vendor_id) return std::string(name);
  }
  return std::nullopt;
}

// Value of a "Key: value" line, as in the NVIDIA information file and uevent files ("KEY=value").
std::optional<std::string> keyed_line_value(const std::string& text, std::string_view key,
                                            char separator) {
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    const auto split = line.find(separator);
    if (split == std::string::npos || trim(std::string_view(line).substr(0, split)) != key) {
      continue;
    }
    const std::string_view value = trim(std::string_view(line).substr(split + 1));
    if (value.empty()) return std::nullopt;
    return std::string(value);
  }
  return std::nullopt;
}

// "NVRM version: NVIDIA UNIX x86_64 Kernel Module  535.104.05  Sat Aug 19 ..." → "535.104.05".
std::optional<std::string> nvidia_driver_version(const fs::path& root) {
  const auto version = read_file(root / "proc/driver/nvidia/version");
  if (!version) return std::nullopt;
  std::istringstream tokens(version->substr(0, version->find('\n')));
  std::string token;
  while (tokens >> token) {
    const bool dotted_number = token.find('.') != std::string::npos &&
                               std::isdigit(static_cast<unsigned char>(token[0])) &&
                               token.find_first_not_of("0123456789.") == std::string::npos;
    if (dotted_number) return token;
  }
  return std::nullopt;
}

// Directory entries sorted so that "card10" follows "card9".
std::vector<fs::path> sorted_entries(const fs::path& directory) {
  std::vector<fs::path> entries;
  std::error_code error;
  for (const auto& entry : fs::directory_iterator(directory, error))
    entries.push_back(entry.path());
  std::sort(entries.begin(), entries.end(), [](const fs::path& a, const fs::path& b) {
    const std::string a_name = a.filename().string();
    const std::string b_name = b.filename().string();
    if (a_name.size() != b_name.size()) return a_name.size() < b_name.size();
    return a_name < b_name;
  });
  return entries;
}

void collect_gpus(const fs::path& root, MachineInfo& info) {
  const auto driver_version = nvidia_driver_version(root);
  for (const auto& directory : sorted_entries(root / "proc/driver/nvidia/gpus")) {
    const auto information = read_file(directory / "information");
    if (!information) continue;
    GpuInfo gpu;
    gpu.source = "nvidia";
    gpu.model = keyed_line_value(*information, "Model", ':');
    gpu.pci_address = keyed_line_value(*information, "Bus Location", ':');
    if (!gpu.pci_address) gpu.pci_address = directory.filename().string();
    gpu.vendor_id = "0x10de";
    gpu.vendor_name = pci_vendor_name(*gpu.vendor_id);
    gpu.driver = "nvidia";
    gpu.driver_version = driver_version;
    info.gpus.push_back(std::move(gpu));
  }

  const auto already_listed = [&info](const std::optional<std::string>& pci_address) {
    return pci_address && std::any_of(info.gpus.begin(), info.gpus.end(), [&](const GpuInfo& gpu) {
             return gpu.pci_address == pci_address;
           });
  };
  for (const auto& card : sorted_entries(root / "sys/class/drm")) {
    const std::string name = card.filename().string();
    // cardN only: cardN-HDMI-A-1 are connectors and renderDN duplicate the card.
    if (!starts_with(name, "card") || !parse_integer<unsigned>(std::string_view(name).substr(4))) {
      continue;
    }
    const fs::path device = card / "device";
    GpuInfo gpu;
    gpu.source = "drm";
    gpu.vendor_id = read_value(device / "vendor");
    if (!gpu.vendor_id) continue;  // Not a PCI device (SoC display engines).
    gpu.device_id = read_value(device / "device");
    gpu.vendor_name = pci_vendor_name(*gpu.vendor_id);
    const auto uevent = read_file(device / "uevent").value_or("");
    gpu.pci_address = keyed_line_value(uevent, "PCI_SLOT_NAME", '=');
    gpu.driver = keyed_line_value(uevent, "DRIVER", '=');
    if (already_listed(gpu.pci_address)) continue;
    if (gpu.driver == "nvidia") gpu.driver_version = driver_version;
    info.gpus.push_back(std::move(gpu));
  }
}

template <typename T>
nlohmann::json or_null(const std::optional<T>& value) {
  if (!value) return nullptr;
  return *value;
}

}  // namespace

MachineInfo collect_machine_info(const fs::path& root) {
  MachineInfo info;
  info.hostname = read_value(root / "proc/sys/kernel/hostname");
  info.architecture = read_value(root / "proc/sys/kernel/arch");
  // Kernels before 6.1 have no kernel.arch; uname says the same of the machine it runs on.
  if (!info.architecture && root == fs::path("/")) {
    utsname name{};
    if (uname(&name) == 0) info.architecture = name.machine;
  }
  info.os_name = read_os_name(root);
  info.board_model = read_value(root / "proc/device-tree/model");
  if (!info.board_model) info.board_model = read_value(root / "sys/firmware/devicetree/base/model");
  info.system_vendor = read_value(root / "sys/class/dmi/id/sys_vendor");
  info.system_product = read_value(root / "sys/class/dmi/id/product_name");

  collect_cpu(root, info);
  if (is_virtual_machine_vendor(info.system_vendor, info.system_product)) {
    info.virtual_machine = true;
  }
  info.memory_total_bytes = read_memory_total_bytes(root);
  collect_kernel(root, info);
  collect_container(root, info);
  collect_gpus(root, info);
  return info;
}

nlohmann::json to_json(const MachineInfo& info) {
  nlohmann::json per_cpu = nlohmann::json::array();
  for (const auto& frequency : info.cpu_frequencies) {
    per_cpu.push_back({{"cpu", frequency.cpu},
                       {"current_khz", or_null(frequency.current_khz)},
                       {"min_khz", or_null(frequency.min_khz)},
                       {"max_khz", or_null(frequency.max_khz)},
                       {"governor", or_null(frequency.governor)}});
  }
  nlohmann::json gpus = nlohmann::json::array();
  for (const auto& gpu : info.gpus) {
    gpus.push_back({{"source", gpu.source},
                    {"model", or_null(gpu.model)},
                    {"pci_address", or_null(gpu.pci_address)},
                    {"vendor_id", or_null(gpu.vendor_id)},
                    {"device_id", or_null(gpu.device_id)},
                    {"vendor_name", or_null(gpu.vendor_name)},
                    {"driver", or_null(gpu.driver)},
                    {"driver_version", or_null(gpu.driver_version)}});
  }
  return {
      {"hostname", or_null(info.hostname)},
      {"architecture", or_null(info.architecture)},
      {"os", or_null(info.os_name)},
      {"board_model", or_null(info.board_model)},
      {"system_vendor", or_null(info.system_vendor)},
      {"system_product", or_null(info.system_product)},
      {"cpu",
       {{"model", or_null(info.cpu_model)},
        {"logical_cpus", or_null(info.logical_cpus)},
        {"physical_cores", or_null(info.physical_cores)},
        {"sockets", or_null(info.sockets)},
        {"smt_enabled", or_null(info.smt_enabled)},
        {"frequency",
         {{"current_min_khz", or_null(info.current_frequency_min_khz)},
          {"current_max_khz", or_null(info.current_frequency_max_khz)},
          {"min_khz", or_null(info.frequency_min_khz)},
          {"max_khz", or_null(info.frequency_max_khz)},
          {"governors", info.governors},
          {"per_cpu", std::move(per_cpu)}}}}},
      {"memory_total_bytes", or_null(info.memory_total_bytes)},
      {"kernel",
       {{"release", or_null(info.kernel_release)},
        {"version", or_null(info.kernel_version)},
        {"preempt_rt", or_null(info.preempt_rt)}}},
      {"container",
       {{"detected", info.in_container}, {"runtime", or_null(info.container_runtime)}}},
      {"virtual_machine", or_null(info.virtual_machine)},
      {"gpus", std::move(gpus)},
  };
}

std::string summary_line(const MachineInfo& info) {
  std::vector<std::string> parts;
  parts.push_back(info.cpu_model.value_or("unknown CPU"));
  if (info.logical_cpus) {
    std::string cpus = std::to_string(*info.logical_cpus) + " CPUs";
    if (info.physical_cores) {
      cpus += " (" + std::to_string(*info.physical_cores) + " cores";
      if (info.sockets && *info.sockets > 1)
        cpus += ", " + std::to_string(*info.sockets) + " sockets";
      cpus += ")";
    }
    parts.push_back(std::move(cpus));
  }
  if (info.memory_total_bytes) {
    char memory[32];
    std::snprintf(memory, sizeof(memory), "%.1f GiB",
                  static_cast<double>(*info.memory_total_bytes) / (1024.0 * 1024.0 * 1024.0));
    parts.emplace_back(memory);
  }
  if (info.kernel_release) {
    parts.push_back("Linux " + *info.kernel_release +
                    (info.preempt_rt.value_or(false) ? " PREEMPT_RT" : ""));
  }
  for (const auto& gpu : info.gpus) {
    if (gpu.model) {
      parts.push_back(*gpu.model);
    } else {
      // Without a model name, the PCI ids are what identifies the GPU, e.g. "AMD GPU 0x73bf".
      std::string label = gpu.vendor_name.value_or(gpu.vendor_id.value_or("unknown")) + " GPU";
      if (gpu.device_id) label += " " + *gpu.device_id;
      parts.push_back(std::move(label));
    }
  }
  std::string line = parts.front();
  for (std::size_t i = 1; i < parts.size(); ++i) line += " · " + parts[i];
  return line;
}

}  // namespace robotperf::sysinfo
