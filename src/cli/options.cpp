#include "options.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <sstream>
#include <stdexcept>
#include <system_error>

#include "robotperf/build_info.hpp"
#include "robotperf/rmw/transport.hpp"

namespace robotperf::cli {

// CLI11's PositiveNumber prints the range up to DBL_MAX, three hundred digits long.
const CLI::Validator kPositive(
    [](std::string& text) -> std::string {
      const auto value = decimal<double>(text);
      if (value && *value > 0) return "";
      return "must be a number greater than 0 (got " + text + ")";
    },
    "POSITIVE");

CLI::Validator number_between(double low, double high) {
  std::ostringstream wanted;
  wanted << "a number from " << low << " to " << high;
  return CLI::Validator(
      [low, high, wanted = wanted.str()](std::string& text) -> std::string {
        const auto value = decimal<double>(text);
        if (value && *value >= low && *value <= high) return "";
        return "must be " + wanted + " (got " + text + ")";
      },
      "NUMBER");
}

namespace {

bool printable(const std::string& text) {
  return std::ranges::none_of(text, [](unsigned char c) { return c < 0x20 || c == 0x7f; });
}

}  // namespace

CLI::Validator label_check() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        const auto equals = text.find('=');
        const std::string key = text.substr(0, equals);
        const bool key_ok =
            !key.empty() && key.size() <= 64 && std::ranges::all_of(key, [](unsigned char c) {
              return std::isalnum(c) || c == '_' || c == '.' || c == '-';
            });
        if (equals == std::string::npos || !key_ok)
          return "expected KEY=VALUE, the key of letters, digits, '_', '.' and '-' (got " + text +
                 ")";
        const std::string value = text.substr(equals + 1);
        if (value.empty() || value.size() > 256 || !printable(value))
          return "the value of " + key + " must be 1 to 256 printable characters";
        return "";
      },
      "KEY=VALUE");
}

CLI::Validator display_name_check() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        if (text.empty() || text.size() > 128 || !printable(text))
          return "must be 1 to 128 printable characters";
        return "";
      },
      "NAME");
}

CLI::Validator whole_number(std::uint64_t min, std::uint64_t max) {
  const bool unbounded = max == std::numeric_limits<std::uint64_t>::max();
  const std::string range = unbounded ? std::to_string(min) + " or more"
                                      : std::to_string(min) + " to " + std::to_string(max);
  const std::string wanted = unbounded ? ", " + range : " from " + range;
  return CLI::Validator(
      [min, max, wanted](std::string& text) -> std::string {
        const auto value = decimal<std::uint64_t>(text);
        if (!value || *value < min || *value > max)
          return "must be a whole number" + wanted + " (got " + text + ")";
        text = std::to_string(*value);
        return "";
      },
      range);
}

namespace {

struct Unit {
  const char* name;
  double factor;  // to the option's unit
};

// "<number><unit>" in the option's unit, for a unit of `units` ("" the number alone); nothing for
// anything else.
std::optional<double> with_unit(const std::string& text, std::initializer_list<Unit> units) {
  double value{};
  const char* end = text.data() + text.size();
  const auto [stop, error] = std::from_chars(text.data(), end, value);
  if (error != std::errc() || stop == text.data()) return std::nullopt;
  const std::string unit(stop, end);
  for (const Unit& u : units) {
    if (unit == u.name) return value * u.factor;
  }
  return std::nullopt;
}

// The shortest text that reads back as `value`.
std::string plain_number(double value) {
  std::array<char, 64> text{};
  const auto [end, error] = std::to_chars(text.data(), text.data() + text.size(), value);
  return std::string(text.data(), end);
}

}  // namespace

CLI::Validator seconds_with_unit() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        const auto s = with_unit(
            text, {{"", 1}, {"s", 1}, {"ms", 1e-3}, {"us", 1e-6}, {"min", 60}, {"h", 3600}});
        if (!s)
          return "must be seconds, or a duration with its unit: 5s, 500ms, 2min (got " + text + ")";
        text = plain_number(*s);
        return "";
      },
      "SECONDS");
}

CLI::Validator hertz_with_unit(std::vector<std::string> words) {
  return CLI::Validator(
      [words = std::move(words)](std::string& text) -> std::string {
        if (std::ranges::find(words, text) != words.end()) return "";
        const auto hz = with_unit(
            text, {{"", 1}, {"Hz", 1}, {"hz", 1}, {"kHz", 1e3}, {"khz", 1e3}, {"MHz", 1e6}});
        if (!hz) return "must be a rate in Hz, or with its unit: 30Hz, 1.5kHz (got " + text + ")";
        text = plain_number(*hz);
        return "";
      },
      "HZ");
}

CLI::Validator domain_id_check(bool auto_allowed) {
  const std::string range = "0 to " + std::to_string(rmw::kMaxDomainId);
  const std::string wanted = "a DDS domain id from " + range + (auto_allowed ? ", or auto" : "");
  return CLI::Validator(
      [auto_allowed, wanted](std::string& text) -> std::string {
        if (auto_allowed && text == "auto") return "";
        const auto id = rmw::parse_domain_id(text);
        if (!id) return "must be " + wanted + " (got " + text + ")";
        text = std::to_string(*id);
        return "";
      },
      auto_allowed ? range + ", or auto" : range);
}

metrics::PowerOptions PowerArgs::options() const {
  metrics::PowerOptions o;
  o.period =
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::duration<double>(period_s));
  o.meter_command = meter;
  o.sysfs_root = sysfs_root;
  o.nvml_library = nvml_library;
  o.types.insert(types.begin(), types.end());
  return o;
}

void add_power_options(CLI::App* command, PowerArgs& args, bool with_period) {
  if (with_period) {
    command
        ->add_option("--power-period", args.period_s,
                     "seconds between power readings in the measured window (default 0.1)")
        ->transform(seconds_with_unit())
        ->check(number_between(0.0005, 60.0));
  }
  command->add_option("--power-meter", args.meter,
                      "external power meter: a shell command that prints watts, run once per "
                      "reading");
  command
      ->add_option("--power-sources", args.types,
                   "use only these source types: rapl, hwmon, nvml, jetson, external "
                   "(default: all found)")
      ->delimiter(',')
      ->check(CLI::IsMember({"rapl", "hwmon", "nvml", "jetson", "external"}));
  command->add_option("--sysfs-root", args.sysfs_root,
                      "root under which sys/ holds the power sensors (default /; for testing)");
  command->add_option("--nvml-library", args.nvml_library,
                      "NVML library to load (default libnvidia-ml.so.1)");
}

harness::SchedulingOptions SchedulingArgs::options() const {
  harness::SchedulingOptions o;
  if (cpus) {
    o.cpus = harness::parse_cpu_list(*cpus);
    harness::check_cpus_allowed(o.cpus);
  }
  o.rt_priority = rt_priority;
  o.lock_memory = lock_memory;
  return o;
}

void add_scheduling_options(CLI::App* command, SchedulingArgs& args) {
  command->add_option("--cpus", args.cpus, "pin the graph to these CPUs, e.g. 2-3 or 0,2");
  command
      ->add_option("--rt-priority", args.rt_priority,
                   "run the graph with SCHED_FIFO at this priority (1-99)")
      ->transform(whole_number(1, 99));
  command->add_flag("--mlock", args.lock_memory, "lock the graph's memory (mlockall)");
}

fs::path self_executable() {
  std::error_code ec;
  fs::path p = fs::read_symlink("/proc/self/exe", ec);
  if (ec) throw std::runtime_error("cannot locate the robotperf executable: " + ec.message());
  return p;
}

Roots benchmark_roots(const std::vector<std::string>& flags) {
  Roots roots;
  const fs::path installed =
      self_executable().parent_path().parent_path() / build_info::kInstalledBenchmarksDir;
  std::error_code ec;
  roots.push_back(fs::is_directory(installed, ec) ? installed
                                                  : fs::path(build_info::kBenchmarksDir));
  if (const char* env = std::getenv("ROBOTPERF_BENCHMARKS"); env && *env) {
    std::stringstream entries(env);
    std::string entry;
    while (std::getline(entries, entry, ':')) {
      if (!entry.empty()) roots.emplace_back(entry);
    }
  }
  for (const auto& f : flags) roots.emplace_back(f);
  // A folder given twice (or the built-in one again) is read once.
  Roots unique;
  for (const auto& r : roots) {
    const fs::path canonical = fs::weakly_canonical(r, ec);
    if (std::ranges::none_of(unique, [&](const fs::path& u) { return u == canonical; }))
      unique.push_back(ec ? r : canonical);
  }
  return unique;
}

void require_writable_folder(const fs::path& folder, const std::string& option) {
  std::error_code ec;
  fs::create_directories(folder, ec);
  const fs::path probe = folder / (".robotperf-write-check-" + std::to_string(getpid()));
  if (!ec) {
    const int fd = open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
    if (fd < 0) {
      ec.assign(errno, std::generic_category());
    } else {
      close(fd);
      fs::remove(probe, ec);
    }
  }
  if (ec) {
    throw std::invalid_argument(option + " " + folder.string() + ": cannot write there (" +
                                ec.message() + "); give a folder you can write to");
  }
}

std::string json_text(const nlohmann::json& j, int indent) {
  return j.dump(indent, ' ', false, nlohmann::json::error_handler_t::replace);
}

}  // namespace robotperf::cli
