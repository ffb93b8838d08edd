#include "run_rows.hpp"

#include <cmath>
#include <cstdio>

#include "robotperf/report/run_metrics.hpp"

namespace robotperf::results_db::detail {

namespace {

using nlohmann::json;
using report::member;

std::vector<Metric> metrics_of(const report::StoredRun& run) {
  std::vector<Metric> out = report::run_metrics(run);
  // A figure the run has no value for has no row.
  std::erase_if(out, [](const Metric& m) { return !std::isfinite(m.value); });
  return out;
}

// One text naming what makes runs comparable (docs/design.md §3.9), with the benchmark: runs that
// share it may be pooled, so that equality or GROUP BY finds them.
std::string configuration_key(const report::StoredRun& run) {
  char rate[48] = "rate ?";
  if (run.throughput_kind == "peak")
    std::snprintf(rate, sizeof rate, "peak");
  else if (std::isfinite(run.rate_hz))
    std::snprintf(rate, sizeof rate, "%.6g Hz", run.rate_hz);
  std::vector<std::string> parts{run.benchmark_id,
                                 run.hardware,
                                 run.rmw,
                                 run.processes,
                                 run.backend.empty() ? "cpu" : run.backend,
                                 run.type,
                                 run.timeline,
                                 "monitor " + run.monitor_wait,
                                 rate,
                                 run.node_settings};
  // Only where not plain, so that the keys of runs stored before it was recorded still match.
  if (run.network != "plain") parts.push_back("network " + run.network);
  return report::joined(parts, " | ");
}

// The non-empty bins of the results file's histogram, edges in ns.
std::vector<HistogramBin> histogram_of(const report::LogHistogram& h) {
  std::vector<HistogramBin> out;
  if (h.nonpositive > 0) out.push_back({std::nullopt, 0, static_cast<std::int64_t>(h.nonpositive)});
  for (std::size_t i = 0; i < h.counts.size(); ++i) {
    if (h.counts[i] == 0) continue;
    out.push_back(
        {h.lower_edge(i) * 1e6, h.upper_edge(i) * 1e6, static_cast<std::int64_t>(h.counts[i])});
  }
  return out;
}

}  // namespace

std::string json_text(const json& j) {
  return j.dump(-1, ' ', false, json::error_handler_t::replace);
}

RunRows rows_of(const report::StoredRun& run) {
  RunRows rows;
  // The results JSON (robotperf.result/1) holds no per-message records: the CSV is the exact
  // record, the histogram the summary every file has.
  if (run.csv_path) {
    rows.samples_source = "csv";
    // The CSV's integer ns, through read_latency_csv's ms: exact, far below 2^53 ns.
    for (double ms : report::read_latency_csv(*run.csv_path))
      rows.samples_ns.push_back(std::llround(ms * 1e6));
  } else if (run.histogram) {
    rows.samples_source = "histogram";
    rows.histogram = histogram_of(*run.histogram);
  } else {
    rows.samples_source = "none";
  }
  const std::string backend = run.backend.empty() ? "cpu" : run.backend;
  rows.run = {{"benchmark_id", run.benchmark_id},
              {"benchmark_name", run.benchmark_name},
              {"category", run.category},
              {"started_utc", run.started_utc},
              {"valid", std::int64_t{run.valid ? 1 : 0}},
              {"invalid_reasons", report::joined(run.invalid_reasons, "; ")},
              {"functional", run.functional},
              {"mode", run.type},
              {"rmw", run.rmw},
              {"processes", run.processes},
              {"backend", backend},
              {"arrivals", run.timeline},
              {"monitor_wait", run.monitor_wait},
              {"rate_hz", run.rate_hz},
              {"throughput_kind", run.throughput_kind},
              {"dataset", run.dataset},
              {"hardware", run.hardware},
              {"hardware_category", run.hardware_category},
              {"robotperf_version", run.robotperf_version},
              {"git_revision", run.git_revision},
              {"machine", JsonText{json_text(member(run.json, "machine"))}},
              {"software", JsonText{json_text(member(run.json, "software"))}},
              {"configuration", JsonText{json_text(member(run.json, "configuration"))}},
              {"configuration_key", configuration_key(run)},
              {"samples_source", rows.samples_source},
              {"warnings", JsonText{json_text(json(run.warnings))}},
              {"document", JsonText{json_text(run.json)}}};
  rows.metrics = metrics_of(run);
  // Labels: a top-level "labels" object, read now so that files which carry one later need no
  // migration.
  if (const json& labels = member(run.json, "labels"); labels.is_object()) {
    for (const auto& [key, value] : labels.items())
      rows.labels.emplace_back(key,
                               value.is_string() ? value.get<std::string>() : json_text(value));
  }
  return rows;
}

}  // namespace robotperf::results_db::detail
