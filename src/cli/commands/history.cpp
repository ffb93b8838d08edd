// `robotperf history ID`: a benchmark's figure over time or revisions, per configuration, with
// the change points where it moved (docs/design.md §8).
#include "robotperf/report/history.hpp"

#include <cstdio>
#include <iostream>
#include <stdexcept>

#include "../options.hpp"
#include "commands.hpp"
#include "results_source.hpp"
#include "robotperf/cli/exit_codes.hpp"
#include "robotperf/report/report.hpp"
#include "robotperf/report/run_store.hpp"

namespace robotperf::cli {

namespace {

class HistoryCommand : public Command {
 public:
  CLI::App* declare(CLI::App& app) override {
    auto* command = app.add_subcommand(
        "history",
        "a benchmark's figure across runs or revisions, per configuration, with change points");
    command->add_option("id", options_.benchmark_id, "the benchmark (a1, d6, ...)")->required();
    command->add_option("--metric", options_.metric,
                        "the figure: latency.p50 (default), latency.p99, throughput, "
                        "energy_per_message, cpu, functional.NAME, ... (as the results "
                        "database names them)");
    command->add_option("--by", options_.by,
                        "a label KEY (run --label KEY=VALUE, or package.revision): one point per "
                        "value of it, its runs pooled");
    command
        ->add_option("--label", labels_,
                     "KEY=VALUE: only the runs with this label (repeatable); a configuration's "
                     "series is not split by labels")
        ->check(label_check());
    command
        ->add_option("--significance", options_.change_points.significance,
                     "a change point is kept at this permutation-test p-value or below "
                     "(default 0.01: about 1 % of series without a change show one)")
        ->check(number_between(0.002, 0.5));
    command->add_option("--results", results_,
                        "results folders or files (default: the database --from or "
                        "ROBOTPERF_RESULTS_URL names, else ./results)");
    command->add_option("--from", from_,
                        "read the runs from this PostgreSQL database (postgresql://...; "
                        "credentials from PGPASSWORD, ~/.pgpass or PGPASSFILE)");
    command->add_option("--format", format_, "text (default) or json")
        ->check(CLI::IsMember({"text", "json"}));
    command->footer(
        "Examples:\n  robotperf history a1\n"
        "  robotperf history a5 --metric latency.p99 --by rev --results results\n"
        "  robotperf history a1 --by rev --from postgresql://robotperf@lab-db/results");
    return command;
  }

  int run(const Context&) override {
    std::vector<report::StoredRun> runs;
    std::optional<report::MetricSource> source;
    std::optional<FolderRuns> folder;  // holds the database the source reads
    if (const auto url = database_to_read(from_, !results_.empty())) {
      runs = runs_from_database(*url);
    } else if (results_.size() <= 1 && (results_.empty() || fs::is_directory(results_[0]))) {
      const fs::path dir = results_.empty() ? fs::path("results") : fs::path(results_[0]);
      if (results_.empty() && !fs::is_directory(dir))
        throw report::ReportError(
            "history: no ./results folder here; name the results with --results DIR");
      folder = folder_runs(dir);
      if (folder->database) source = results_db::metric_source(folder->database->database);
      runs = std::move(folder->runs);
    } else {
      // Several folders, or files: read whole (the figures come from the files).
      for (const auto& path : results_) {
        if (fs::is_directory(path)) {
          report::RunScan scan = report::scan_results(path);
          for (const auto& s : scan.skipped)
            std::fprintf(stderr, "robotperf: skipped %s\n", s.c_str());
          for (auto& run : scan.runs) runs.push_back(std::move(run));
        } else {
          runs.push_back(report::load_run(path));
        }
      }
    }
    keep_labelled(runs, labels_);
    const report::History h =
        source ? report::history(runs, options_, *source) : report::history(runs, options_);
    if (format_ == "json")
      std::cout << json_text(report::history_json(h), 1) << "\n";
    else
      std::cout << report::history_text(h);
    return kExitOk;
  }

 private:
  report::HistoryOptions options_;
  std::vector<std::string> results_, labels_;
  std::string from_;
  std::string format_ = "text";
};

}  // namespace

std::unique_ptr<Command> history_command() {
  return std::make_unique<HistoryCommand>();
}

}  // namespace robotperf::cli
