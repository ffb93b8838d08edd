// The power sources robotperf can read, and their discovery.
#include <dlfcn.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <map>
#include <sstream>
#include <stdexcept>
#include <system_error>

#include "robotperf/metrics/power.hpp"

extern char** environ;

namespace robotperf::metrics {
namespace {

namespace fs = std::filesystem;

const std::set<std::string> kSourceTypes = {"rapl", "hwmon", "nvml", "jetson", "external"};

std::string trim(std::string text) {
  const auto first = text.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return {};
  const auto last = text.find_last_not_of(" \t\r\n");
  return text.substr(first, last - first + 1);
}

// `text` for a one-line message: line breaks and other control characters written as escapes.
std::string one_line(const std::string& text) {
  std::string line;
  for (const char c : text) {
    if (c == '\n') {
      line += "\\n";
    } else if (c == '\r') {
      line += "\\r";
    } else if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) {
      char escape[5];
      std::snprintf(escape, sizeof escape, "\\x%02x", static_cast<unsigned char>(c));
      line += escape;
    } else {
      line += c;
    }
  }
  return line;
}

// A sysfs value: the trimmed first line. Nullopt with `error` set when unreadable.
std::optional<std::string> read_text(const fs::path& path, std::string& error) {
  // Plain POSIX reads: sysfs attributes are small, and this runs up to a thousand times a second.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    error = path.string() + ": " + std::strerror(errno);
    if (errno == EACCES) error += " (readable by root only; run as root or grant read access)";
    return std::nullopt;
  }
  char buffer[128];
  const ssize_t n = ::read(fd, buffer, sizeof buffer - 1);
  const int read_errno = errno;
  ::close(fd);
  if (n < 0) {
    error = path.string() + ": " + std::strerror(read_errno);
    return std::nullopt;
  }
  return trim(std::string(buffer, static_cast<std::size_t>(n)));
}

std::optional<std::string> read_text(const fs::path& path) {
  std::string ignored;
  return read_text(path, ignored);
}

std::optional<double> parse_number(const std::string& text) {
  double value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || end != text.data() + text.size() || !std::isfinite(value)) {
    return std::nullopt;
  }
  return value;
}

std::optional<double> read_number(const fs::path& path, std::string& error) {
  const auto text = read_text(path, error);
  if (!text) return std::nullopt;
  const auto value = parse_number(*text);
  if (!value) error = path.string() + ": not a number: '" + *text + "'";
  return value;
}

bool file_exists(const fs::path& path) {
  std::error_code ec;
  return fs::exists(path, ec);
}

// Directory entries sorted by name, with numbers in names ordered numerically ("x2" < "x10").
std::vector<fs::path> entries(const fs::path& directory) {
  std::vector<fs::path> out;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(directory, ec)) out.push_back(e.path());
  std::sort(out.begin(), out.end(), [](const fs::path& a, const fs::path& b) {
    const std::string x = a.filename().string(), y = b.filename().string();
    return x.size() != y.size() ? x.size() < y.size() : x < y;
  });
  return out;
}

// A sysfs attribute times a scale: RAPL and hwmon energy (µJ), hwmon power (µW).
// A sysfs attribute kept open and re-read from offset 0 (sysfs regenerates the value on every
// read from the start): one pread per reading instead of open, read and close.
class SysfsNumber {
 public:
  explicit SysfsNumber(fs::path path) : path_(std::move(path)) {}
  ~SysfsNumber() {
    if (fd_ >= 0) ::close(fd_);
  }
  SysfsNumber(const SysfsNumber&) = delete;
  SysfsNumber& operator=(const SysfsNumber&) = delete;

  std::optional<double> read(std::string& error) {
    if (fd_ < 0) {
      fd_ = ::open(path_.c_str(), O_RDONLY | O_CLOEXEC);
      if (fd_ < 0) return read_number(path_, error);  // gives the reason
    }
    char buffer[64];
    const ssize_t n = ::pread(fd_, buffer, sizeof buffer, 0);
    if (n <= 0) {
      error = path_.string() + ": " + (n < 0 ? std::strerror(errno) : "empty");
      ::close(fd_);
      fd_ = -1;  // opened again next time: the device may come back
      return std::nullopt;
    }
    const std::string text = trim(std::string(buffer, static_cast<std::size_t>(n)));
    const auto value = parse_number(text);
    if (!value) error = path_.string() + ": not a number: '" + text + "'";
    return value;
  }

 private:
  fs::path path_;
  int fd_ = -1;
};

// A sysfs attribute times a scale: RAPL and hwmon energy (µJ), hwmon power (µW).
class SysfsSource : public PowerSource {
 public:
  SysfsSource(PowerSourceInfo info, fs::path file, double scale)
      : PowerSource(std::move(info)), file_(std::move(file)), scale_(scale) {}
  std::optional<double> read(std::string& error) override {
    const auto value = file_.read(error);
    if (!value) return std::nullopt;
    return *value * scale_;
  }

 private:
  SysfsNumber file_;
  double scale_;
};

// An INA3221 channel of the hwmon driver (L4T 34+): bus voltage (mV) times current (mA).
class VoltageCurrentSource : public PowerSource {
 public:
  VoltageCurrentSource(PowerSourceInfo info, fs::path millivolts, fs::path milliamps)
      : PowerSource(std::move(info)), mv_(std::move(millivolts)), ma_(std::move(milliamps)) {}
  std::optional<double> read(std::string& error) override {
    const auto mv = mv_.read(error);
    if (!mv) return std::nullopt;
    const auto ma = ma_.read(error);
    if (!ma) return std::nullopt;
    return *mv * *ma * 1e-6;
  }

 private:
  SysfsNumber mv_, ma_;
};

// ---- RAPL (powercap) ----

void discover_rapl(const fs::path& root, PowerDiscovery& out) {
  const fs::path powercap = root / "sys/class/powercap";
  struct Zone {
    fs::path dir;
    std::string name;
    std::string parent;  // package name for subzones
  };
  std::vector<Zone> zones;
  std::map<std::string, std::string> names;  // "intel-rapl:0" -> "package-0"
  for (const auto& dir : entries(powercap)) {
    const std::string id = dir.filename().string();
    // intel-rapl-mmio:* repeats package zones through MMIO; reading both would count twice.
    if (id.rfind("intel-rapl:", 0) != 0) continue;
    const auto name = read_text(dir / "name");
    if (!name) continue;
    names[id] = *name;
    zones.push_back({dir, *name, {}});
  }
  // Each package followed by its subzones: intel-rapl:0, intel-rapl:0:0, ..., intel-rapl:1.
  const auto indices = [](const Zone& z) {
    std::vector<int> numbers;
    std::istringstream parts(z.dir.filename().string().substr(std::strlen("intel-rapl:")));
    for (std::string part; std::getline(parts, part, ':');)
      numbers.push_back(std::atoi(part.c_str()));
    return numbers;
  };
  std::sort(zones.begin(), zones.end(),
            [&](const Zone& a, const Zone& b) { return indices(a) < indices(b); });
  if (zones.empty()) {
    out.notes.push_back("rapl: no RAPL zones in " + powercap.string() +
                        " (not an Intel/AMD CPU, or the intel_rapl driver is not loaded)");
    return;
  }
  bool has_package = false;
  for (auto& z : zones) {
    const std::string id = z.dir.filename().string();
    const auto second_colon = id.find(':', id.find(':') + 1);
    if (second_colon != std::string::npos) z.parent = names[id.substr(0, second_colon)];
    if (z.parent.empty() && z.name.rfind("package", 0) == 0) has_package = true;
  }
  std::string first_error;
  const std::size_t before = out.sources.size();
  for (const auto& z : zones) {
    std::string error;
    if (!read_number(z.dir / "energy_uj", error)) {
      if (first_error.empty()) first_error = error;
      continue;
    }
    PowerSourceInfo info;
    info.type = "rapl";
    info.name = "rapl:" + (z.parent.empty() ? z.name : z.parent + "/" + z.name);
    info.location = (z.dir / "energy_uj").string();
    info.kind = PowerSourceKind::kEnergyCounter;
    std::string range_error;
    if (const auto range = read_number(z.dir / "max_energy_range_uj", range_error)) {
      info.wrap_j = *range * 1e-6;
    }
    // Packages and DRAM (outside the package on servers) add up; core and uncore are inside
    // their package; psys covers the whole platform and stands alone only without packages.
    if (z.parent.empty()) {
      info.in_total = z.name.rfind("package", 0) == 0 || (z.name == "psys" && !has_package);
    } else {
      info.in_total = z.name == "dram";
    }
    out.sources.push_back(
        std::make_unique<SysfsSource>(std::move(info), z.dir / "energy_uj", 1e-6));
  }
  if (out.sources.size() == before) out.notes.push_back("rapl: " + first_error);
}

// ---- hwmon ----

void discover_hwmon(const fs::path& root, bool rapl_found, PowerDiscovery& out) {
  const fs::path hwmon = root / "sys/class/hwmon";
  const std::size_t before = out.sources.size();
  struct Device {
    fs::path dir, base;  // its attributes in base: dir, or dir/device for older drivers
    std::optional<std::string> name;
  };
  std::vector<Device> devices;
  for (const auto& dir : entries(hwmon)) {
    const auto own = read_text(dir / "name");
    const auto name = own ? own : read_text(dir / "device/name");
    devices.push_back({dir, !own && name ? dir / "device" : dir, name});
  }
  for (const auto& [dev, base, name] : devices) {
    // Two devices of one driver (two GPUs, two INA chips) are told apart by their hwmon folder.
    std::string label_prefix = "hwmon:" + name.value_or(dev.filename().string());
    if (name && std::ranges::count(devices, name, &Device::name) > 1)
      label_prefix += "[" + dev.filename().string() + "]";
    // CPU energy drivers repeat what RAPL already counts.
    const bool repeats_rapl = rapl_found && name && (*name == "amd_energy" || *name == "zenpower");
    for (int channel = 1; channel <= 32; ++channel) {
      const std::string n = std::to_string(channel);
      PowerSourceInfo info;
      info.type = "hwmon";
      info.in_total = !repeats_rapl;
      // The ACPI power meter reads the machine's input power, of which the rest is a part.
      info.whole_machine = name == "power_meter";
      fs::path file;
      double scale = 1e-6;
      // Prefer the energy counter of a channel over its power reading.
      if (file_exists(base / ("energy" + n + "_input"))) {
        file = base / ("energy" + n + "_input");
        info.kind = PowerSourceKind::kEnergyCounter;
        info.name =
            label_prefix + "/" + read_text(base / ("energy" + n + "_label")).value_or("energy" + n);
      } else if (file_exists(base / ("power" + n + "_input")) ||
                 file_exists(base / ("power" + n + "_average"))) {
        file = base / ("power" + n +
                       (file_exists(base / ("power" + n + "_input")) ? "_input" : "_average"));
        info.kind = PowerSourceKind::kPowerGauge;
        info.name =
            label_prefix + "/" + read_text(base / ("power" + n + "_label")).value_or("power" + n);
      } else {
        continue;
      }
      std::string error;
      if (!read_number(file, error)) {
        out.notes.push_back("hwmon: " + error);
        continue;
      }
      info.location = file.string();
      out.sources.push_back(std::make_unique<SysfsSource>(std::move(info), file, scale));
    }
  }
  if (out.sources.size() == before) {
    out.notes.push_back("hwmon: no power*_input or energy*_input channels in " + hwmon.string());
  }
}

// ---- Jetson INA3221 rails ----

void discover_jetson(const fs::path& root, PowerDiscovery& out) {
  std::vector<PowerSourceInfo> infos;
  std::vector<std::function<std::unique_ptr<PowerSource>(PowerSourceInfo)>> makers;
  const auto add = [&](std::string rail, fs::path location, auto make) {
    if (rail.empty() || rail == "NC") return;  // unconnected channel
    PowerSourceInfo info;
    info.type = "jetson";
    info.name = "jetson:" + rail;
    info.location = location.string();
    info.kind = PowerSourceKind::kPowerGauge;
    infos.push_back(std::move(info));
    makers.push_back(make);
  };
  // L4T 32 and older: the ina3221x IIO driver, power in mW, rail names in rail_name_<k>.
  for (const auto& dev : entries(root / "sys/bus/i2c/drivers/ina3221x")) {
    for (const auto& iio : entries(dev)) {
      if (iio.filename().string().rfind("iio:device", 0) != 0) continue;
      for (int k = 0; k < 3; ++k) {
        const auto rail = read_text(iio / ("rail_name_" + std::to_string(k)));
        const fs::path file = iio / ("in_power" + std::to_string(k) + "_input");
        if (!rail || !file_exists(file)) continue;
        add(*rail, file, [file](PowerSourceInfo info) -> std::unique_ptr<PowerSource> {
          return std::make_unique<SysfsSource>(std::move(info), file, 1e-3);
        });
      }
    }
  }
  // L4T 34 and later: the mainline ina3221 hwmon driver, in<k>_label, in<k>_input (mV),
  // curr<k>_input (mA).
  for (const auto& dev : entries(root / "sys/bus/i2c/drivers/ina3221")) {
    for (const auto& hw : entries(dev / "hwmon")) {
      for (int k = 1; k <= 3; ++k) {
        const std::string n = std::to_string(k);
        const auto rail = read_text(hw / ("in" + n + "_label"));
        const fs::path mv = hw / ("in" + n + "_input"), ma = hw / ("curr" + n + "_input");
        if (!rail || !file_exists(mv) || !file_exists(ma)) continue;
        add(*rail, hw, [mv, ma](PowerSourceInfo info) -> std::unique_ptr<PowerSource> {
          return std::make_unique<VoltageCurrentSource>(std::move(info), mv, ma);
        });
      }
    }
  }
  if (infos.empty()) {
    out.notes.push_back("jetson: no INA3221 rails under " +
                        (root / "sys/bus/i2c/drivers/ina3221{,x}").string());
    return;
  }
  // The module input rail, where a board has one, already includes every other rail.
  const auto is_input = [](const PowerSourceInfo& i) {
    return i.name == "jetson:VDD_IN" || i.name == "jetson:POM_5V_IN";
  };
  const bool has_input = std::any_of(infos.begin(), infos.end(), is_input);
  for (std::size_t i = 0; i < infos.size(); ++i) {
    infos[i].in_total = !has_input || is_input(infos[i]);
    out.sources.push_back(makers[i](std::move(infos[i])));
  }
}

// ---- NVML, loaded at run time ----

// The subset of the NVML C API used here (nvml.h: nvmlReturn_t is an int enum, nvmlDevice_t an
// opaque pointer).
using NvmlReturn = int;
using NvmlDevice = void*;
constexpr NvmlReturn kNvmlSuccess = 0;
// nvmlUtilization_t and nvmlMemory_t.
struct NvmlUtilisation {
  unsigned gpu;
  unsigned memory;
};
struct NvmlMemory {
  unsigned long long total;
  unsigned long long free;
  unsigned long long used;
};

class NvmlLibrary {
 public:
  // Throws std::runtime_error with the reason when the library or a symbol is missing, or
  // nvmlInit fails.
  explicit NvmlLibrary(const std::string& path) {
    handle_ = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (handle_ == nullptr) {
      throw std::runtime_error(path + " not loadable (" + std::string(dlerror()) +
                               "): no NVIDIA driver");
    }
    try {
      init_ = symbol<NvmlReturn (*)()>("nvmlInit_v2", "nvmlInit");
      shutdown_ = symbol<NvmlReturn (*)()>("nvmlShutdown");
      error_string_ = symbol<const char* (*)(NvmlReturn)>("nvmlErrorString");
      count_ = symbol<NvmlReturn (*)(unsigned*)>("nvmlDeviceGetCount_v2", "nvmlDeviceGetCount");
      handle_by_index_ = symbol<NvmlReturn (*)(unsigned, NvmlDevice*)>(
          "nvmlDeviceGetHandleByIndex_v2", "nvmlDeviceGetHandleByIndex");
      name_ = symbol<NvmlReturn (*)(NvmlDevice, char*, unsigned)>("nvmlDeviceGetName");
      energy_ = symbol<NvmlReturn (*)(NvmlDevice, unsigned long long*)>(
          "nvmlDeviceGetTotalEnergyConsumption");
      power_ = symbol<NvmlReturn (*)(NvmlDevice, unsigned*)>("nvmlDeviceGetPowerUsage");
      // The load is extra: a library without these still measures power.
      utilisation_ = optional_symbol<NvmlReturn (*)(NvmlDevice, NvmlUtilisation*)>(
          "nvmlDeviceGetUtilizationRates");
      memory_ = optional_symbol<NvmlReturn (*)(NvmlDevice, NvmlMemory*)>("nvmlDeviceGetMemoryInfo");
      if (const NvmlReturn rc = init_(); rc != kNvmlSuccess) {
        throw std::runtime_error(path + ": nvmlInit failed: " + error(rc));
      }
    } catch (...) {
      dlclose(handle_);
      throw;
    }
  }
  ~NvmlLibrary() {
    shutdown_();
    dlclose(handle_);
  }
  NvmlLibrary(const NvmlLibrary&) = delete;
  NvmlLibrary& operator=(const NvmlLibrary&) = delete;

  std::string error(NvmlReturn rc) const {
    const char* text = error_string_(rc);
    return (text ? text : "error") + std::string(" (") + std::to_string(rc) + ")";
  }
  NvmlReturn count(unsigned* n) const { return count_(n); }
  NvmlReturn device(unsigned i, NvmlDevice* d) const { return handle_by_index_(i, d); }
  NvmlReturn name(NvmlDevice d, char* buf, unsigned size) const { return name_(d, buf, size); }
  NvmlReturn energy_mj(NvmlDevice d, unsigned long long* mj) const { return energy_(d, mj); }
  NvmlReturn power_mw(NvmlDevice d, unsigned* mw) const { return power_(d, mw); }
  // Utilisation (percent of its last sample window the GPU ran a kernel) and memory in use;
  // nullopt when the library or the GPU does not report them.
  std::optional<DeviceLoad> load(NvmlDevice d) const {
    if (utilisation_ == nullptr || memory_ == nullptr) return std::nullopt;
    NvmlUtilisation u{};
    NvmlMemory m{};
    if (utilisation_(d, &u) != kNvmlSuccess || memory_(d, &m) != kNvmlSuccess) return std::nullopt;
    return DeviceLoad{static_cast<double>(u.gpu), m.used, m.total};
  }

 private:
  template <typename Function>
  Function optional_symbol(const char* name) {
    return reinterpret_cast<Function>(dlsym(handle_, name));
  }
  template <typename Function>
  Function symbol(const char* name, const char* fallback = nullptr) {
    void* address = dlsym(handle_, name);
    if (address == nullptr && fallback != nullptr) address = dlsym(handle_, fallback);
    if (address == nullptr) throw std::runtime_error(std::string("NVML has no ") + name);
    return reinterpret_cast<Function>(address);
  }

  void* handle_ = nullptr;
  NvmlReturn (*init_)() = nullptr;
  NvmlReturn (*shutdown_)() = nullptr;
  const char* (*error_string_)(NvmlReturn) = nullptr;
  NvmlReturn (*count_)(unsigned*) = nullptr;
  NvmlReturn (*handle_by_index_)(unsigned, NvmlDevice*) = nullptr;
  NvmlReturn (*name_)(NvmlDevice, char*, unsigned) = nullptr;
  NvmlReturn (*energy_)(NvmlDevice, unsigned long long*) = nullptr;
  NvmlReturn (*power_)(NvmlDevice, unsigned*) = nullptr;
  NvmlReturn (*utilisation_)(NvmlDevice, NvmlUtilisation*) = nullptr;
  NvmlReturn (*memory_)(NvmlDevice, NvmlMemory*) = nullptr;
};

class NvmlSource : public PowerSource {
 public:
  NvmlSource(PowerSourceInfo info, std::shared_ptr<NvmlLibrary> nvml, NvmlDevice device)
      : PowerSource(std::move(info)), nvml_(std::move(nvml)), device_(device) {}
  std::optional<double> read(std::string& error) override {
    if (this->info().kind == PowerSourceKind::kEnergyCounter) {
      unsigned long long mj = 0;
      if (const NvmlReturn rc = nvml_->energy_mj(device_, &mj); rc != kNvmlSuccess) {
        error = info().name + ": nvmlDeviceGetTotalEnergyConsumption: " + nvml_->error(rc);
        return std::nullopt;
      }
      return static_cast<double>(mj) * 1e-3;
    }
    unsigned mw = 0;
    if (const NvmlReturn rc = nvml_->power_mw(device_, &mw); rc != kNvmlSuccess) {
      error = info().name + ": nvmlDeviceGetPowerUsage: " + nvml_->error(rc);
      return std::nullopt;
    }
    return static_cast<double>(mw) * 1e-3;
  }
  std::optional<DeviceLoad> load() override { return nvml_->load(device_); }

 private:
  std::shared_ptr<NvmlLibrary> nvml_;
  NvmlDevice device_;
};

void discover_nvml(const std::string& library, PowerDiscovery& out) {
  std::shared_ptr<NvmlLibrary> nvml;
  try {
    nvml = std::make_shared<NvmlLibrary>(library);
  } catch (const std::exception& e) {
    out.notes.push_back(std::string("nvml: ") + e.what());
    return;
  }
  unsigned count = 0;
  if (const NvmlReturn rc = nvml->count(&count); rc != kNvmlSuccess) {
    out.notes.push_back("nvml: nvmlDeviceGetCount: " + nvml->error(rc));
    return;
  }
  const std::size_t before = out.sources.size();
  for (unsigned i = 0; i < count; ++i) {
    NvmlDevice device = nullptr;
    if (const NvmlReturn rc = nvml->device(i, &device); rc != kNvmlSuccess) {
      out.notes.push_back("nvml: GPU " + std::to_string(i) + ": " + nvml->error(rc));
      continue;
    }
    PowerSourceInfo info;
    info.type = "nvml";
    info.name = "nvml:gpu" + std::to_string(i);
    info.location = library;
    char name[96] = {};
    if (nvml->name(device, name, sizeof name) == kNvmlSuccess) info.description = name;
    // The energy counter (Volta and later) is exact; older boards only report power.
    unsigned long long mj = 0;
    unsigned mw = 0;
    if (nvml->energy_mj(device, &mj) == kNvmlSuccess) {
      info.kind = PowerSourceKind::kEnergyCounter;
    } else if (const NvmlReturn rc = nvml->power_mw(device, &mw); rc == kNvmlSuccess) {
      info.kind = PowerSourceKind::kPowerGauge;
    } else {
      out.notes.push_back("nvml: GPU " + std::to_string(i) +
                          " reports neither energy nor power: " + nvml->error(rc));
      continue;
    }
    out.sources.push_back(std::make_unique<NvmlSource>(std::move(info), nvml, device));
  }
  if (out.sources.size() == before && count == 0) out.notes.push_back("nvml: no NVIDIA GPU");
}

// ---- external meter ----

class ExternalMeterSource : public PowerSource {
 public:
  ExternalMeterSource(PowerSourceInfo info, std::string command, double timeout_s)
      : PowerSource(std::move(info)), command_(std::move(command)), timeout_s_(timeout_s) {}

  std::optional<double> read(std::string& error) override {
    std::string output;
    if (!run(output, error)) return std::nullopt;
    std::istringstream tokens(output);
    std::string first;
    tokens >> first;
    const auto watts = parse_number(first);
    if (!watts || !(*watts >= 0) || *watts > kMaxPhysicalWatts) {
      error = "power meter '" + one_line(command_) + "' printed '" +
              one_line(trim(output).substr(0, 60)) + "', expected watts (a number from 0 to " +
              std::to_string(int(kMaxPhysicalWatts)) + ") as its first word";
      return std::nullopt;
    }
    return *watts;
  }

 private:
  // Runs the command; its standard output goes to `output`, and on failure `error` says why,
  // with the last line the meter wrote to its standard error (which is kept off the terminal:
  // a failing meter is one line of robotperf's).
  bool run(std::string& output, std::string& error) {
    int out_fds[2], err_fds[2];
    if (pipe2(out_fds, O_CLOEXEC) != 0) {
      error = std::string("pipe: ") + std::strerror(errno);
      return false;
    }
    if (pipe2(err_fds, O_CLOEXEC) != 0) {
      error = std::string("pipe: ") + std::strerror(errno);
      ::close(out_fds[0]);
      ::close(out_fds[1]);
      return false;
    }
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, out_fds[1], STDOUT_FILENO);
    posix_spawn_file_actions_adddup2(&actions, err_fds[1], STDERR_FILENO);
    posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
    // Its own process group, so that a timeout kills the shell's children too.
    posix_spawnattr_t attributes;
    posix_spawnattr_init(&attributes);
    posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETPGROUP);
    posix_spawnattr_setpgroup(&attributes, 0);
    std::string shell = "/bin/sh", flag = "-c", command = command_;
    char* argv[] = {shell.data(), flag.data(), command.data(), nullptr};
    pid_t pid = -1;
    const int rc = posix_spawn(&pid, argv[0], &actions, &attributes, argv, environ);
    posix_spawn_file_actions_destroy(&actions);
    posix_spawnattr_destroy(&attributes);
    ::close(out_fds[1]);
    ::close(err_fds[1]);
    if (rc != 0) {
      ::close(out_fds[0]);
      ::close(err_fds[0]);
      error = "cannot start /bin/sh for the power meter: " + std::string(std::strerror(rc));
      return false;
    }
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s_);
    bool timed_out = false;
    std::string diagnostics;
    pollfd fds[2] = {{out_fds[0], POLLIN, 0}, {err_fds[0], POLLIN, 0}};
    std::string* into[2] = {&output, &diagnostics};
    // Reads what fds[i] has; closes it at its end (poll ignores a negative descriptor).
    const auto take = [&](int i) {
      char buffer[256];
      const ssize_t n = ::read(fds[i].fd, buffer, sizeof buffer);
      if (n < 0 && errno == EINTR) return;
      if (n <= 0) {
        ::close(fds[i].fd);
        fds[i].fd = -1;
      } else if (into[i]->size() < 4096) {
        into[i]->append(buffer, static_cast<std::size_t>(n));
      }
    };
    while (fds[0].fd >= 0) {  // until the standard output ends
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          deadline - std::chrono::steady_clock::now());
      if (left.count() <= 0) {
        timed_out = true;
        break;
      }
      if (::poll(fds, 2, static_cast<int>(left.count())) <= 0) continue;  // EINTR, or the deadline
      for (int i = 0; i < 2; ++i) {
        if (fds[i].fd >= 0 && fds[i].revents != 0) take(i);
      }
    }
    // Then what the standard error holds already: a child the meter left running may keep it open.
    while (!timed_out && fds[1].fd >= 0 && ::poll(&fds[1], 1, 0) > 0) take(1);
    for (const pollfd& fd : fds) {
      if (fd.fd >= 0) ::close(fd.fd);
    }
    if (timed_out) ::kill(-pid, SIGKILL);
    int status = 0;
    while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    if (timed_out) {
      error = "power meter '" + one_line(command_) + "' did not finish within " +
              std::to_string(timeout_s_) + " s";
      return false;
    }
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
      error = "power meter '" + one_line(command_) + "' failed (" +
              (WIFEXITED(status) ? "exit status " + std::to_string(WEXITSTATUS(status))
                                 : "killed by signal " + std::to_string(WTERMSIG(status))) +
              ")" + last_line(diagnostics);
      return false;
    }
    return true;
  }

  // ": LINE" with the last non-empty line of `text` (shortened), or nothing.
  static std::string last_line(const std::string& text) {
    std::string line;
    std::istringstream lines(text);
    for (std::string l; std::getline(lines, l);) {
      if (!trim(l).empty()) line = trim(l);
    }
    if (line.empty()) return "";
    if (line.size() > 160) line = line.substr(0, 157) + "...";
    return ": " + line;
  }

  std::string command_;
  double timeout_s_;
};

// A meter of the whole machine already includes every other source: adding them would count
// them twice, so the total is that meter alone (the external one, which the user gave, before an
// ACPI one). The others stay listed with their own readings.
void count_whole_machine_alone(PowerDiscovery& out) {
  const auto whole = [](const std::unique_ptr<PowerSource>& s) { return s->info().whole_machine; };
  auto counted = std::ranges::find_if(
      out.sources, [&](const auto& s) { return whole(s) && s->info().type == "external"; });
  if (counted == out.sources.end()) counted = std::ranges::find_if(out.sources, whole);
  if (counted == out.sources.end()) return;
  std::string others;
  for (auto& s : out.sources) {
    if (s == *counted || !s->info().in_total) continue;
    s->leave_out_of_total();
    others += (others.empty() ? "" : ", ") + s->info().name;
  }
  if (!others.empty()) {
    out.notes.push_back("total: " + (*counted)->info().name +
                        " measures the whole machine, so the total is it alone; " + others +
                        " are part of it (listed, not added)");
  }
}

}  // namespace

PowerDiscovery discover_power_sources(const PowerOptions& options) {
  for (const auto& type : options.types) {
    if (!kSourceTypes.contains(type)) {
      throw std::invalid_argument("unknown power source type '" + type +
                                  "' (known: rapl, hwmon, nvml, jetson, external)");
    }
  }
  const auto wanted = [&](const char* type) {
    return options.types.empty() || options.types.contains(type);
  };
  PowerDiscovery out;
  if (wanted("rapl")) discover_rapl(options.sysfs_root, out);
  const bool rapl_found = !out.sources.empty();
  if (wanted("hwmon")) discover_hwmon(options.sysfs_root, rapl_found, out);
  if (wanted("jetson")) discover_jetson(options.sysfs_root, out);
  if (wanted("nvml")) discover_nvml(options.nvml_library, out);
  if (wanted("external")) {
    if (options.meter_command.empty()) {
      out.notes.push_back("external: no meter command given (--power-meter)");
    } else {
      PowerSourceInfo info;
      info.type = "external";
      info.name = "external:meter";
      info.location = options.meter_command;
      info.kind = PowerSourceKind::kPowerGauge;
      info.whole_machine = true;
      auto meter = std::make_unique<ExternalMeterSource>(std::move(info), options.meter_command,
                                                         options.meter_timeout_s);
      // The user asked for this meter: one that does not work is an error, not a note.
      std::string error;
      if (!meter->read(error)) throw std::invalid_argument(error);
      out.sources.push_back(std::move(meter));
    }
  }
  count_whole_machine_alone(out);
  return out;
}

}  // namespace robotperf::metrics
