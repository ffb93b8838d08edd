// A run's figures by name, as the results database's metrics table, `history` and the report's
// trend view name them ("latency.p50", "throughput", "functional.ate_m"; docs/reference/
// results-database.md lists them).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "robotperf/report/run_store.hpp"

namespace robotperf::report {

struct RunMetric {
  std::string name;
  double value = kNoValue;
  std::string unit;
  // A percentile's distribution-free 95 % interval; NaN where not known.
  double low = kNoValue, high = kNoValue;
  // Which way is better: latencies, losses and costs smaller, throughput larger; a functional
  // metric by its threshold (a maximum: smaller). Unknown for counts and unbounded metrics.
  enum class Better { kSmaller, kLarger, kUnknown } better = Better::kUnknown;
};

// "smaller", "larger", or "" when unknown: as the results database's metrics.better holds it.
std::string better_text(RunMetric::Better better);
RunMetric::Better better_from_text(const std::string& text);

// Every figure the run has, NaN values included (a figure its file holds as null).
std::vector<RunMetric> run_metrics(const StoredRun& run);

// The figure `name` of the run, when it has a finite value.
std::optional<RunMetric> run_metric(const StoredRun& run, const std::string& name);

}  // namespace robotperf::report
