// `robotperf trace analyze DIR`: the grey-box analysis of any CTF trace folder.
#include <iostream>
#include <limits>
#include <stdexcept>

#include "commands.hpp"
#include "robotperf/cli/exit_codes.hpp"
#include "robotperf/files/atomic_file.hpp"
#include "robotperf/metrics/latency_stats.hpp"
#include "robotperf/tracing/analysis.hpp"

namespace robotperf::cli {

namespace {

// The analysed run's figures, as the --json file holds them.
nlohmann::json run_json(const tracing::TraceAnalysis& analysis) {
  return {{"benchmark", analysis.run->benchmark},
          {"rmw", analysis.run->rmw},
          {"pid", analysis.run->pid},
          {"sent", analysis.sent},
          {"measured", analysis.measured},
          {"matched", analysis.matched},
          {"lost", analysis.lost},
          {"unobserved", analysis.unobserved},
          {"duplicates", analysis.duplicates},
          {"repeats", analysis.repeats},
          {"unknown", analysis.unknown},
          {"latency_ms",
           {{"from_scheduled", metrics::to_json(analysis.latency_from_scheduled, 1e-6, "ms")},
            {"from_sent", metrics::to_json(analysis.latency_from_sent, 1e-6, "ms")}}},
          {"throughput_hz", analysis.throughput_hz}};
}

class TraceCommand : public Command {
 public:
  CLI::App* declare(CLI::App& app) override {
    auto* command = app.add_subcommand("trace", "work with LTTng traces");
    command->require_subcommand(1);
    command->footer("Example: robotperf trace analyze results/a1-intra-20261129T040000.trace");
    auto* analyze = command->add_subcommand(
        "analyze", "grey-box analysis of a CTF trace (robotperf or ros2_tracing)");
    analyze->add_option("dir", dir_, "the trace folder (searched for CTF metadata)")->required();
    analyze->add_option("--json", json_, "also write the analysis as JSON to this file");
    analyze
        ->add_option("--pid", pid_,
                     "analyse the robotperf run of this process (default: the first)")
        ->transform(whole_number(0, std::numeric_limits<int>::max()));
    analyze->footer("Example: robotperf trace analyze results/a1-grey.trace --json analysis.json");
    return command;
  }

  int run(const Context&) override {
    const auto analysis = tracing::analyze_trace(dir_, {.run_pid = pid_, .extra_processes = {}});
    // A process the trace has no run of is a wrong --pid, not an invalid run.
    if (pid_ != 0 && !analysis.run) {
      throw std::invalid_argument(
          tracing::missing_run(analysis, pid_) +
          (analysis.run_pids.empty() ? ": leave --pid out to analyse the trace's other events"
                                     : ": give --pid one of those, or leave it out for the first"));
    }
    std::cout << tracing::analysis_summary(analysis);
    if (!json_.empty()) {
      nlohmann::json j = tracing::to_json(analysis);
      j["valid"] = analysis.valid;
      j["reasons"] = analysis.invalid_reasons;
      if (analysis.run) j["run"] = run_json(analysis);
      files::write_output(json_, json_text(j, 2) + "\n");
    }
    return analysis.valid ? kExitOk : kExitInvalidResult;
  }

 private:
  std::string dir_;
  std::string json_;
  int pid_ = 0;
};

}  // namespace

std::unique_ptr<Command> trace_command() {
  return std::make_unique<TraceCommand>();
}

}  // namespace robotperf::cli
