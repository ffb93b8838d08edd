// A benchmark's figure over time or revisions, per configuration, with the change points where
// its level moved (`robotperf history`, the report's trend view; docs/design.md §8).
#pragma once

#include <cstddef>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "robotperf/report/change_points.hpp"
#include "robotperf/report/run_metrics.hpp"
#include "robotperf/report/run_store.hpp"

namespace robotperf::report {

struct HistoryOptions {
  std::string benchmark_id;
  std::string metric = "latency.p50";  // a name of run_metrics
  // A label key: one point per value of that label (its runs pooled), in the order of their first
  // run; runs without the label are left out. Empty: one point per run.
  std::string by;
  ChangePointOptions change_points;
};

struct HistoryPoint {
  std::string started_utc;  // of its first run
  // What it was measured at: the --by label's value, else the run's package.revision label (an
  // external graph's commit), else the robotperf revision that measured it.
  std::string revision;
  std::size_t runs = 0;
  double value = kNoValue;  // the run's figure, or the median over its runs
  // One run: the figure's 95 % interval where the run has one. Several: the runs' range.
  double low = kNoValue, high = kNoValue;
  std::vector<std::string> files;
};

struct HistorySeries {
  std::string name;  // the configuration, as the report names it
  std::vector<HistoryPoint> points;
  std::vector<ChangePoint> changes;  // indexes into points
};

struct History {
  std::string benchmark_id, metric, unit, by;
  RunMetric::Better better = RunMetric::Better::kUnknown;
  std::vector<HistorySeries> series;  // by name
  std::vector<std::string> notes;     // runs left out and why
  ChangePointOptions change_points;   // how the change points were found
};

// Where history reads a run's figure: from the run's file (run_metrics), or, for runs listed from
// the results database, from its metrics table.
struct MetricSource {
  std::function<std::optional<RunMetric>(const StoredRun& run, const std::string& name)> of;
  // The figures the runs of a benchmark have: named when the one asked for is not among them.
  std::function<std::vector<std::string>(const std::string& benchmark_id)> names;
};
MetricSource metrics_from_files(const std::vector<StoredRun>& runs);

// The valid runs of `options.benchmark_id` that have `options.metric`, as one series per
// configuration (comparable only with like: design §3.9), each with its change points. Throws
// ReportError when no run of the benchmark has the metric (naming the metrics it has), or no such
// run is valid.
History history(const std::vector<StoredRun>& runs, const HistoryOptions& options,
                const MetricSource& source);
History history(const std::vector<StoredRun>& runs, const HistoryOptions& options);

// A git hash as its first `digits` digits; any other revision (a user's label) whole.
std::string short_revision(const std::string& revision, std::size_t digits);

std::string history_text(const History& history);  // for the terminal
nlohmann::json history_json(const History& history);

}  // namespace robotperf::report
