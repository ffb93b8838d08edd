// What several verbs of the robotperf command share: number checks for CLI11 options, the power
// and scheduling option groups, the benchmark folders, and how JSON and output folders are
// written.
#pragma once

#include <CLI/CLI.hpp>
#include <charconv>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "robotperf/harness/scheduling.hpp"
#include "robotperf/metrics/power.hpp"

namespace robotperf::cli {

namespace fs = std::filesystem;

// All of `text` as std::from_chars reads a T in decimal, or nothing: a double's digits, point and
// exponent (also inf and nan, which the callers bound), an unsigned's digits alone (no sign,
// space or 0x); nullopt for anything else and beyond T's range.
template <class T>
std::optional<T> decimal(const std::string& text) {
  T value{};
  const char* end = text.data() + text.size();
  const auto [stop, error] = std::from_chars(text.data(), end, value);
  if (error != std::errc() || stop != end) return std::nullopt;
  return value;
}

// A number option greater than 0, its bound said in words.
extern const CLI::Validator kPositive;

// A number option bounded on both sides. CLI11's Range lets "nan" through (every comparison with
// it is false).
CLI::Validator number_between(double low, double high);

// A whole-number option's check. CLI11 2.1.2 converts integers with strtoll/strtoull in base 0
// (0x10 is 16, 010 is 8, and -1 an unsigned 2^64-1), so only decimal digits pass, and they are
// rewritten without leading zeros, which that conversion then reads as decimal: options take it
// with transform(), as check() would discard the rewrite.
CLI::Validator whole_number(std::uint64_t min,
                            std::uint64_t max = std::numeric_limits<std::uint64_t>::max());

// A duration option's check that also takes a unit: 5, 5s, 500ms, 250us, 2min or 1h, rewritten
// as plain seconds (taken with transform(), as whole_number's is).
CLI::Validator seconds_with_unit();

// A rate option's check that also takes a unit: 30, 30Hz, 1.5kHz or 2MHz, rewritten as plain Hz;
// the `words` ("bag") pass unchanged.
CLI::Validator hertz_with_unit(std::vector<std::string> words = {});

// A --label KEY=VALUE check: the key of letters, digits, '_', '.' and '-' (up to 64), the value
// printable (up to 256, no control characters), since both become report series and filters.
CLI::Validator label_check();

// A name shown in reports (--system): 1 to 128 printable characters.
CLI::Validator display_name_check();

// A --domain option's check, rewritten and taken with transform() as whole_number's is.
CLI::Validator domain_id_check(bool auto_allowed);

// Power options shared by `run` and `sysinfo`.
struct PowerArgs {
  double period_s = 0.1;
  std::string meter;
  std::string sysfs_root = "/";
  std::string nvml_library = "libnvidia-ml.so.1";
  std::vector<std::string> types;

  metrics::PowerOptions options() const;
};
void add_power_options(CLI::App* command, PowerArgs& args, bool with_period);

// Scheduling options shared by `run` and `node`.
struct SchedulingArgs {
  std::optional<std::string> cpus;  // given empty, it is refused, not taken as no pinning
  int rt_priority = 0;
  bool lock_memory = false;

  harness::SchedulingOptions options() const;
};
void add_scheduling_options(CLI::App* command, SchedulingArgs& args);

fs::path self_executable();

using Roots = std::vector<fs::path>;

// The built-in benchmarks (installed beside the executable, else the source tree's), then the
// folders of ROBOTPERF_BENCHMARKS (':'-separated) and of --benchmarks.
Roots benchmark_roots(const std::vector<std::string>& flags);

// Creates `folder` if needed and checks that a file can be written in it; throws
// std::invalid_argument naming `option` and the reason.
void require_writable_folder(const fs::path& folder, const std::string& option);

// JSON as text for a file or the terminal: bytes that are not UTF-8 (names from a trace or a bag)
// are replaced, not refused, so that what was measured is always written.
std::string json_text(const nlohmann::json& j, int indent);

}  // namespace robotperf::cli
