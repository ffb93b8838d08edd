#include "robotperf/sysinfo/run_rules.hpp"

#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <system_error>

namespace robotperf::sysinfo {
namespace {

namespace fs = std::filesystem;

std::optional<std::string> read_word(const fs::path& path) {
  std::ifstream in(path);
  std::string word;
  if (!(in >> word)) return std::nullopt;
  return word;
}

// Why tracing looks active, or empty. An LTTng session daemon means sessions may be recording;
// ftrace counts when it is on with a tracer or events enabled.
std::string tracing_activity(const fs::path& root, bool lttng_expected) {
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(root / "proc", ec)) {
    if (lttng_expected) break;
    const std::string pid = entry.path().filename().string();
    if (pid.empty() || pid.find_first_not_of("0123456789") != std::string::npos) continue;
    if (read_word(entry.path() / "comm") == "lttng-sessiond") {
      return "an LTTng session daemon is running (pid " + pid + ")";
    }
  }
  for (const char* dir : {"sys/kernel/tracing", "sys/kernel/debug/tracing"}) {
    const fs::path tracing = root / dir;
    if (read_word(tracing / "tracing_on") != "1") continue;
    const auto tracer = read_word(tracing / "current_tracer");
    if (tracer && *tracer != "nop") return "ftrace is on with the '" + *tracer + "' tracer";
    if (read_word(tracing / "set_event")) return "ftrace is on with events enabled";
  }
  return {};
}

std::string join(const std::vector<std::string>& words) {
  std::string out;
  for (const auto& w : words) out += (out.empty() ? "" : ", ") + w;
  return out;
}

}  // namespace

std::vector<RunWarning> build_warnings(const std::string& build_type, bool sanitized) {
  std::vector<RunWarning> warnings;
  if (build_type == "Debug" || build_type.empty()) {
    warnings.push_back({"build", "robotperf is a " +
                                     (build_type.empty() ? "unoptimised" : build_type) +
                                     " build: kernels run far slower than in a release; build "
                                     "with -DCMAKE_BUILD_TYPE=Release"});
  }
  if (sanitized) {
    warnings.push_back({"build",
                        "robotperf is built with AddressSanitizer/UBSan: several times slower "
                        "than a normal build; rebuild without -DROBOTPERF_SANITIZE=ON"});
  }
  return warnings;
}

std::vector<RunWarning> check_run_rules(const RunRuleInputs& in) {
  std::vector<RunWarning> warnings = build_warnings(in.build_type, in.sanitized);
  const auto warn = [&](std::string rule, std::string message) {
    warnings.push_back({std::move(rule), std::move(message)});
  };
  const MachineInfo& m = in.machine;

  std::vector<std::string> slow_governors;
  for (const auto& g : m.governors) {
    if (g != "performance") slow_governors.push_back(g);
  }
  if (!slow_governors.empty()) {
    warn("governor", "CPU frequency governor " + join(slow_governors) +
                         " (not 'performance'): the clock follows the load, so latency depends "
                         "on it; set 'performance' (cpupower frequency-set -g performance)");
  } else if (m.governors.empty()) {
    warn("frequency",
         "CPU frequency scaling is not visible (no cpufreq in sysfs): the clock "
         "speed during the run is unknown");
  }
  if (read_word(in.root / "sys/devices/system/cpu/intel_pstate/no_turbo") == "0" ||
      read_word(in.root / "sys/devices/system/cpu/cpufreq/boost") == "1") {
    warn("turbo",
         "turbo boost is on: the clock depends on temperature and on how many cores are "
         "busy; disable it for repeatable numbers");
  }
  if (m.smt_enabled.value_or(false)) {
    warn("smt",
         "SMT (hyper-threading) is on: the graph's threads may share a core with other "
         "work; pin the graph (--cpus) to one thread per core, or disable SMT");
  }
  if (m.virtual_machine.value_or(false)) {
    warn("virtual_machine",
         "running in a virtual machine: the hypervisor may steal CPU time and "
         "the clock is virtual; results describe the VM, not the hardware");
  }
  if (m.in_container) {
    warn("container", "running in a container (" + m.container_runtime.value_or("unknown") +
                          "): CPU and memory limits of the container apply");
  }
  if (in.other_load_percent && *in.other_load_percent > kBusyThresholdPercent) {
    char message[200];
    std::snprintf(message, sizeof message,
                  "system busy: other processes used %.0f %% of a core just before the run; "
                  "they compete with the graph",
                  *in.other_load_percent);
    warn("system_busy", message);
  }
  if (const std::string tracing = tracing_activity(in.root, in.grey_box); !tracing.empty()) {
    warn("tracing", in.grey_box ? "tracing beside this grey-box run's own LTTng session: " +
                                      tracing + "; it adds overhead to what is measured"
                                : "tracing may be active during a black-box run: " + tracing +
                                      "; it adds overhead to what is measured");
  }
  // Below this the p99 is the largest few samples, and no sample bounds it from above.
  if (in.measured_messages < in.samples_for_p99_bound) {
    warn("samples", std::to_string(in.measured_messages) +
                        " measured messages: the p99's 95 % interval has no upper end below " +
                        std::to_string(in.samples_for_p99_bound) +
                        " samples (each percentile is reported with the interval its samples "
                        "give); use --count or --duration");
  }
  return warnings;
}

std::string machine_condition(const RunWarning& warning) {
  static const std::map<std::string, std::string> kConditions = {
      {"governor", "governor not 'performance'"},
      {"frequency", "CPU clock not visible"},
      {"turbo", "turbo boost on"},
      {"smt", "SMT on"},
      {"virtual_machine", "virtual machine"},
      {"container", "container"}};
  const auto found = kConditions.find(warning.rule);
  return found == kConditions.end() ? std::string() : found->second;
}

}  // namespace robotperf::sysinfo
