// Run rules: conditions under which a benchmark's numbers do not mean what they seem (a Debug
// build, a CPU clock that follows the load, other load on the machine, tracing during a
// black-box run, too few samples to bound the p99 from above). They are checked before a run;
// each one found becomes a warning recorded in the result (or, with --strict, a refusal).
#pragma once

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "robotperf/sysinfo/machine.hpp"

namespace robotperf::sysinfo {

struct RunWarning {
  std::string rule;     // short id: "build", "governor", "system_busy", ...
  std::string message;  // one line: what, why it matters, what to do
};

struct RunRuleInputs {
  MachineInfo machine;
  std::string build_type;  // CMAKE_BUILD_TYPE of this robotperf
  bool sanitized = false;
  std::size_t measured_messages = 0;
  // The fewest samples whose 95 % interval of the p99 has an upper end
  // (metrics::samples_for_upper_bound(0.99)); fewer measured messages are warned about.
  std::size_t samples_for_p99_bound = 368;
  // CPU used by processes other than the graph's just before the run, in % of one core.
  std::optional<double> other_load_percent;
  // A grey-box run records LTTng events by design: the session daemon it uses is not a warning.
  bool grey_box = false;
  std::filesystem::path root = "/";  // where proc/ and sys/ are (fixture trees in tests)
};

// Load by other processes above this (in % of one core) makes the machine "busy".
inline constexpr double kBusyThresholdPercent = 25.0;

std::vector<RunWarning> check_run_rules(const RunRuleInputs& inputs);

// A few words for a warning that holds for every run on this machine as it is set up (a virtual
// machine, a container, the governor, turbo, SMT, an unknown clock), which a summary condenses to
// one line; empty for a warning about this run (load, tracing, samples, the build).
std::string machine_condition(const RunWarning& warning);

// The rules on robotperf's own build alone (an unoptimised or sanitized one), for the benches,
// whose figures such a build makes as wrong as a run's.
std::vector<RunWarning> build_warnings(const std::string& build_type, bool sanitized);

}  // namespace robotperf::sysinfo
