// What the HTML and Markdown reports show, computed once (private to the report piece).
#pragma once

#include <map>
#include <string>
#include <vector>

#include "robotperf/report/report.hpp"

namespace robotperf::report::detail {

// A table as both renderers write it.
struct Table {
  std::string css_class;
  std::vector<std::string> header;
  std::vector<bool> numeric;  // right-aligned columns
  std::vector<std::vector<std::string>> rows;
  std::vector<bool> row_warning;  // rows to highlight (invalid runs, flagged rows)
};

// One radar plot: axes = benchmarks of a category, one polygon per hardware series.
struct Radar {
  std::string category, metric, unit;
  bool smaller_is_better = true;
  std::vector<std::string> axes;
  std::vector<std::string> series;
  std::vector<bool> series_local;
  std::vector<std::vector<double>> values;  // [series][axis], NaN where there is no value
  std::vector<std::string> omitted;         // series left out to keep the plot readable
  Table data;                               // the same numbers as a table
};

// One latency distribution curve.
struct Distribution {
  std::string label;
  std::string source;  // "per-message CSV", "stored histogram", "stored percentiles"
  std::vector<std::pair<double, double>> points;  // (latency ms, cumulative fraction)
  double p50 = 0, p99 = 0;
};

struct BenchmarkSection {
  std::string id, name, category;
  Table runs;  // local runs
  std::vector<Distribution> distribution;
  Table published;  // per published hardware: medians of unflagged rows
  Table flagged;    // published rows that break the measurement rules
  std::size_t published_rows = 0;
};

struct Comparison {
  std::string a, b;  // labels of the two sides
  Table table;
  std::vector<std::string> notes;
};

struct Model {
  std::string title;
  std::string summary;
  std::vector<std::string> warnings;
  std::vector<std::string> categories;
  std::map<std::string, std::vector<Radar>> radars;                 // by category
  std::map<std::string, std::vector<BenchmarkSection>> benchmarks;  // by category
  std::optional<Comparison> comparison;
  Table machines;
};

Model build_model(const ReportInput& input, const ReportOptions& options);

// Series label of a local run: "<hardware> · <rmw>".
std::string local_series(const StoredRun& run);
// Series label of published rows: "<hardware> (RobotPerf)".
std::string published_series(const std::string& hardware);

std::string html_escape(const std::string& text);
std::string format_value(double value);  // 4 significant digits, "-" for NaN

// SVG renderers.
std::string radar_svg(const Radar& radar);
std::string distribution_svg(const std::vector<Distribution>& curves, const std::string& id);
extern const char* const kPalette[12];

}  // namespace robotperf::report::detail
