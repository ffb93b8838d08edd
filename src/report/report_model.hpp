// What the HTML and Markdown reports show, computed once (private to the report piece).
#pragma once

#include <limits>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "robotperf/report/history.hpp"
#include "robotperf/report/report.hpp"

namespace robotperf::report::detail {

// A table as both renderers write it.
struct Table {
  std::string css_class;
  std::vector<std::string> header;
  std::vector<bool> numeric;  // right-aligned columns
  std::vector<std::vector<std::string>> rows;
  std::vector<bool> row_warning;  // rows to highlight (invalid runs, flagged rows)
  // Per row, what the page's filters match it by (filter group -> value); empty: always shown.
  std::vector<std::map<std::string, std::string>> row_tags;
};

// A table as aligned plain text for a terminal: each column as wide as its widest cell, numeric
// columns to the right, the last column unpadded.
std::string table_text(const Table& table);

// One radar plot: axes = benchmarks of a category, one polygon per hardware series.
struct Radar {
  std::string category, metric, unit;
  std::string figure;  // the metric as its title names it ("maximum latency")
  bool smaller_is_better = true;
  std::vector<std::string> axes;
  std::vector<std::string> series;
  std::vector<bool> series_local;
  std::vector<std::size_t> colours;  // per series: its page-wide colour (kPalette or kNoColour)
  std::vector<std::vector<double>> values;  // [series][axis], NaN where there is no value
  std::vector<std::string> omitted;         // series left out to keep the plot readable
  // Where local and published values on an axis are not the same measurement: said beside it.
  std::vector<std::string> notes;
  Table data;  // the same numbers as a table
};

// No colour: a series beyond the palette is drawn in outline and named where it is drawn, so that
// no colour stands for two series on one page.
inline constexpr std::size_t kNoColour = static_cast<std::size_t>(-1);

// One bar of a benchmark's bar chart: a configuration's local runs, or one published series.
struct Bar {
  std::string series;  // its name, the same in every plot and table of the page
  bool local = true;
  double value = std::numeric_limits<double>::quiet_NaN();
  // The whisker: the value's 95 % interval, NaN where it is not known (open, or too few samples).
  double lower = std::numeric_limits<double>::quiet_NaN();
  double upper = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> points;  // each run's value, when the series has more than one run
  std::string count;           // "3 runs", "12 rows"
  std::size_t colour = kNoColour;
  std::map<std::string, std::string> tags;  // what the filters match it by
};

// A benchmark's configurations and published series as sorted horizontal bars of one figure.
struct BarChart {
  std::string benchmark;
  std::string figure;              // "p50", "max": which latency figure each bar is
  std::string axis;                // the axis title, naming the figure and how runs were combined
  std::vector<Bar> bars;           // smallest (best) first
  std::vector<std::string> notes;  // what the bars' measurements differ in, said under the plot
};

// One latency distribution curve.
struct Distribution {
  std::string label;
  std::string source;  // "per-message CSV", "stored histogram", "stored percentiles"
  std::vector<std::pair<double, double>> points;  // (latency ms, cumulative fraction)
  double p50 = 0, p99 = 0;
  bool valid = true;   // an INVALID run's curve is drawn grey and dashed, and labelled so
  std::string series;  // its run's configuration, whose colour it is drawn in
  std::size_t colour = kNoColour;
};

struct BenchmarkSection {
  std::string id, name, category;
  Table runs;            // local runs
  Table also_measured;   // their functional check, resources, energy per message, control loops
  Table outputs;         // each run's monitored outputs with their output jitter
  Table hops;            // the newest grey-box run's per-hop breakdown
  std::string hops_run;  // that run, and its hops' mean durations drawn as bars
  std::vector<StoredRun::Hop> hop_bars;
  Table callbacks;    // the newest grey-box run's callback durations
  Table peak_search;  // the steps of each --find-peak run
  std::vector<Distribution> distribution;
  std::vector<BarChart> charts;  // p50 of the local runs; max beside the published rows
  // Each local configuration against the published rows measured alike (black-box, same rate).
  Table versus_published;
  std::vector<double> versus_ratios;  // per row of it: this configuration / the published median
  Table published;                    // per published hardware: medians of unflagged rows
  Table flagged;                      // published rows that break the measurement rules
  std::size_t published_rows = 0;
  // The p50 of each configuration run at least kTrendPoints times, over its runs, with change
  // points: a --repeat series, or the configuration's history.
  std::vector<HistorySeries> trends;
};

inline constexpr std::size_t kTrendPoints = 3;

struct Comparison {
  std::string a, b;  // labels of the two sides
  Table table;
  std::vector<std::string> notes;
};

// Warnings under one heading: a machine's (said once for all its runs), a run's, or the report's.
struct WarningGroup {
  std::string heading;
  std::vector<std::string> items;
};

// A series on the page: its colour, and whether it is local runs or published rows.
struct KeyEntry {
  std::string series;
  std::size_t colour = kNoColour;
  bool local = true;
};

struct Model {
  std::string title;
  std::string summary;
  std::vector<std::string> overview;  // what was run, on which systems
  std::vector<std::string> findings;  // the few that matter, most important first
  Table at_a_glance;                  // per benchmark: fastest configuration, standing, validity
  std::vector<KeyEntry> key;          // every series drawn, in the order its colour was given
  // The filters' groups and values ("system" -> {"AMD EPYC", ...}), in the page's order.
  std::vector<std::pair<std::string, std::vector<std::string>>> filters;
  std::vector<std::string> invalid_runs;  // "run X is INVALID: why": shown first, never folded
  // Machine-level warnings once per machine, then each run's own.
  std::vector<WarningGroup> warning_groups;
  // The report's own: skipped files, flagged published rows, distributions not drawn as stored.
  std::vector<std::string> warnings;
  std::vector<std::string> categories;
  std::map<std::string, std::vector<Radar>> radars;                 // by category
  std::map<std::string, std::vector<BenchmarkSection>> benchmarks;  // by category
  std::optional<Comparison> comparison;
  std::string no_comparison;  // why no automatic comparison was made, when none was
  Table machines;
};

Model build_model(const ReportInput& input, const ReportOptions& options);
// The comparison of two selectors alone (what build_model puts in Model::comparison); throws
// ReportError as it does.
Comparison build_comparison(const ReportInput& input, const std::string& a, const std::string& b);

// The local runs a selector (as compare takes it) chooses, and the configuration fields it names.
struct Selection {
  std::vector<const StoredRun*> runs;
  std::set<std::string> fields;
};
Selection select_runs(const std::string& selector, const ReportInput& input);

// How two runs' configurations differ ("rmw intra vs fastdds"), besides the `chosen` fields.
std::vector<std::string> unlike(const StoredRun& a, const StoredRun& b,
                                const std::set<std::string>& chosen);

// "2 INVALID runs · 5 machine warnings (1 machine) · 12 run warnings · 1 other": the line that
// stands for all of them.
std::string warning_summary(const Model& model);

// Whether a run-rule warning ("rule: message") is about the machine (its CPU settings, its
// virtualisation, robotperf's build) rather than the run.
bool is_machine_warning(const std::string& warning);

// Series label of a local run: "<hardware> · <rmw>[ · per-node][ · <backend>][ · grey][ ·
// <arrivals>] · <rate> Hz": runs of one series are comparable (docs/design.md §3.9).
std::string local_series(const StoredRun& run);
// The same without the rate: a peak throughput's series.
std::string configuration_series(const StoredRun& run);
// Series label of published rows: "<hardware> (RobotPerf)", "<hardware> · grey (RobotPerf)".
std::string published_series(const PublishedResult& row);

// For HTML, and for XML too (the JUnit of the gate).
std::string html_escape(const std::string& text);
std::string format_value(double value);  // 4 significant digits, "-" for NaN

// SVG renderers.
std::string radar_svg(const Radar& radar);
// Whether radar_svg draws bars instead: fewer than three axes, or no axis with two values.
bool drawn_as_bars(const Radar& radar);

// A text on a plot: its baseline's left end, and its colour.
struct Label {
  double x = 0, y = 0;
  std::string text;
  const char* colour = "#444";
};
// Moves labels down, in order, until no two of them overlap (each keeps its x).
void place_labels(std::vector<Label>& labels);
std::string distribution_svg(const std::vector<Distribution>& curves, const std::string& id);
// One stacked bar of a grey-box run's hops: where the mean latency of a message goes.
std::string hops_svg(const std::vector<StoredRun::Hop>& hops, const std::string& run);
// Okabe and Ito's colour-blind-safe palette.
extern const char* const kPalette[8];
// A series' colour, or the outline colour of one without.
const char* colour_of(std::size_t colour);
// Sorted horizontal bars with whiskers and run points; "" when no bar has a value.
std::string bar_chart_svg(const BarChart& chart);
// A configuration's p50 run after run: each run's value with its interval, its revisions below,
// and its change points marked with the change's size.
std::string trend_svg(const HistorySeries& series, const std::string& benchmark);

}  // namespace robotperf::report::detail
