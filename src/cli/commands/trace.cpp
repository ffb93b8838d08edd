// `robotperf trace analyze DIR` (the grey-box analysis of any CTF trace folder, optionally the
// latency of a path through its graph) and `robotperf trace paths DIR` (the graph's paths).
#include <iostream>
#include <limits>
#include <sstream>
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
    analyze
        ->add_option("--path", path_,
                     "also measure the latency along these topics, comma-separated (from the "
                     "trace alone: no header copying needed; see robotperf trace paths)")
        ->delimiter(',');
    analyze->footer(
        "Example: robotperf trace analyze results/a1-grey.trace --json analysis.json\n"
        "         robotperf trace analyze my.trace --path /image_raw,/image_rect,/detections");
    paths_ = command->add_subcommand(
        "paths", "list the topic chains (sources to sinks) of the graph a trace shows");
    paths_->add_option("dir", dir_, "the trace folder (searched for CTF metadata)")->required();
    paths_->add_option("--json", json_, "also write the graph and its paths as JSON to this file");
    paths_
        ->add_option("--max-paths", max_paths_,
                     "stop after this many paths (the search also stops after 10^6 steps)")
        ->transform(whole_number(1, 1'000'000));
    paths_->footer("Example: robotperf trace paths results/a1-grey.trace");
    export_ = command->add_subcommand(
        "export", "write a trace's callbacks, publishes, takes and path instances as a timeline");
    export_->add_option("dir", dir_, "the trace folder (searched for CTF metadata)")->required();
    export_
        ->add_option("--format", format_,
                     "chrome: Chrome Trace Event JSON, which Perfetto UI (ui.perfetto.dev) and "
                     "chrome://tracing open; perfetto: the same file")
        ->check(CLI::IsMember({"chrome", "perfetto"}));
    export_->add_option("-o,--output", output_, "the file to write")->required();
    export_
        ->add_option("--path", path_,
                     "also show each message's way along these topics (comma-separated) as a span")
        ->delimiter(',');
    export_->footer(
        "Example: robotperf trace export results/a1-grey.trace -o a1.json "
        "--path /camera/image_raw,/rectify/image_rect,/resize/image");
    return command;
  }

  int run(const Context&) override {
    if (paths_->parsed()) return list_paths();
    if (export_->parsed()) {
      tracing::AnalyzeOptions options;
      options.path = path_;
      options.timeline = true;
      const auto analysis = tracing::analyze_trace(dir_, options);
      std::ostringstream out;
      tracing::write_chrome_trace(analysis, out);
      files::write_output(output_, out.str());
      std::cout << "wrote " << output_ << ": " << analysis.timeline.size()
                << " callbacks, publishes and takes";
      if (analysis.path) std::cout << ", " << analysis.path->instances.size() << " path instances";
      std::cout << "\n";
      return kExitOk;
    }
    tracing::AnalyzeOptions options;
    options.run_pid = pid_;
    options.path = path_;
    const auto analysis = tracing::analyze_trace(dir_, options);
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
  int list_paths() {
    const auto analysis = tracing::analyze_trace(dir_);
    if (analysis.graph.topics.empty()) {
      throw std::invalid_argument(
          "the trace has no ros2:rcl_publisher_init / rcl_subscription_init events, so its graph "
          "is unknown: start tracing before the nodes start (robotperf run --mode grey does)");
    }
    const tracing::PathSearch search =
        tracing::find_paths(analysis.graph, {.max_paths = max_paths_});
    for (const auto& p : search.paths) std::cout << p.text() << "\n";
    std::cout << search.paths.size() << (search.paths.size() == 1 ? " path" : " paths") << " of "
              << analysis.graph.topics.size() << " topics, " << search.steps << " search steps";
    if (!search.stopped.empty()) std::cout << "; " << search.stopped << ": there may be more";
    std::cout << "\n";
    if (!json_.empty()) {
      nlohmann::json topics = nlohmann::json::array(), paths = nlohmann::json::array();
      for (const auto& t : analysis.graph.topics) {
        topics.push_back(
            {{"name", t.name}, {"publishers", t.publishers}, {"subscribers", t.subscribers}});
      }
      for (const auto& p : search.paths)
        paths.push_back({{"topics", p.topics}, {"nodes", p.nodes}, {"cut", p.cut}});
      files::write_output(json_, json_text({{"topics", topics},
                                            {"paths", paths},
                                            {"search_steps", search.steps},
                                            {"stopped", search.stopped}},
                                           2) +
                                     "\n");
    }
    return kExitOk;
  }

  CLI::App* paths_ = nullptr;
  CLI::App* export_ = nullptr;
  std::string format_ = "chrome";
  std::string output_;
  std::string dir_;
  std::string json_;
  int pid_ = 0;
  std::vector<std::string> path_;
  std::size_t max_paths_ = 1000;
};

}  // namespace

std::unique_ptr<Command> trace_command() {
  return std::make_unique<TraceCommand>();
}

}  // namespace robotperf::cli
