// What both results stores (SQLite, PostgreSQL) record of a run: its row of the runs table, its
// figures, labels and latency samples, made once here so that the two hold the same values.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "robotperf/report/run_metrics.hpp"
#include "robotperf/report/run_store.hpp"
#include "robotperf/results_db/results_db.hpp"

namespace robotperf::results_db::detail {

// JSON text as the results file has it: a string that is not UTF-8 (a machine's odd model name)
// with replacement characters.
std::string json_text(const nlohmann::json& j);

// A figure of a run; NaN where it has no interval end (NULL).
using Metric = report::RunMetric;

// One column of the runs table and its value: text, an integer, a real (NaN: NULL), or JSON
// (text in SQLite, jsonb in PostgreSQL).
struct JsonText {
  std::string text;
};
struct Column {
  const char* name;
  std::variant<std::string, std::int64_t, double, JsonText> value;
};

// The rows of one run, the runs table's `file` (each store names it its own way) and `id` left
// out.
struct RunRows {
  std::vector<Column> run;                                  // in the tables' column order
  std::vector<Metric> metrics;                              // the figures it has a value for
  std::vector<std::pair<std::string, std::string>> labels;  // key, value
  std::string samples_source;                               // "csv", "histogram" or "none"
  std::vector<std::int64_t> samples_ns;                     // samples_source "csv"
  std::vector<HistogramBin> histogram;                      // samples_source "histogram"
};

// Reads the run's .latencies.csv when it has one: throws report::ReportError naming it when it is
// malformed, before anything is written.
RunRows rows_of(const report::StoredRun& run);

}  // namespace robotperf::results_db::detail
