// RobotPerf's benchmark.yaml: its `results` entries, read from published files (with the rows that
// break the measurement rules flagged), written from our runs, and merged into a package's file
// without touching what is already there.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "robotperf/report/run_store.hpp"

namespace robotperf::report {

// One `- result:` entry. Field names are RobotPerf's (including its spelling "timestampt").
struct PublishedResult {
  std::string type;         // black | grey
  std::string metric;       // latency | throughput | power
  std::string metric_unit;  // ms | fps | W
  std::string hardware;
  std::string category;  // edge | workstation | datacenter | cloud (published files also mix)
  std::string timestampt;
  double value = kNoValue;
  std::string value_text;  // the value as written (kept when it is not a number)
  std::string note;
  std::string datasource;

  int line = 0;                    // 1-based line of the entry in its file; 0 when not from a file
  std::vector<std::string> flags;  // measurement rules the row breaks, one reason each

  // Figures read from the free-text note (RobotPerf writes "mean 14.73 ms, RMS 14.84 ms, ...",
  // "mean_benchmark ...", "min_latency ...", "lost messages 4.55 %").
  std::optional<double> note_mean, note_rms, note_min, note_max, note_loss_percent;
  // The input rate the note states, in Hz: one rate ("bounded to 30fps", "Fixed at 30 FPS",
  // "update rate 10 Hz": low == high) or a sweep ("swept from 30 to 300 fps", "configured in
  // the 30-500 FPS range").
  std::optional<std::pair<double, double>> note_rate_hz;
  // "30 Hz", "30-300 Hz sweep", or "" when the note states none.
  std::string stated_rate() const;

  // Equal in the nine RobotPerf fields (value compared as a number).
  bool same_entry(const PublishedResult& other) const;
};

// A benchmark.yaml file.
struct PublishedBenchmark {
  std::filesystem::path source;
  std::string id, name, short_description, description, graph, reproduction;
  std::string category;  // the package's category (perception, control, ...)
  std::vector<PublishedResult> results;

  std::size_t flagged() const;
};

// Reads a benchmark.yaml (or a package folder holding one), checks every result against the
// measurement rules and fills `flags`. Throws ReportError naming the file and line when the file
// is not YAML or not a benchmark description. `category` is the package's when the caller knows it
// (a loaded package's BenchmarkSpec::category); empty: the folder above a package of robotperf's
// (one with a graph.yaml), as the harness records it, and for a published RobotPerf file the
// category RobotPerf's format gives its id, which holds for a copy outside its category folder.
PublishedBenchmark import_benchmark_yaml(const std::filesystem::path& path,
                                         const std::string& category = {});

// The measurement-rule checks of one entry (docs/design.md §3): negative latencies (value or note),
// loss above 100 %, power <= 0 W or below 1 mW (no real sensor read), throughput <= 0, and values
// that are not numbers. Also fills the note_* figures.
void check_published(PublishedResult& result);

struct ExportOptions {
  std::string hardware;  // empty: the run's machine label
  std::string category;  // empty: guessed from the machine (edge/workstation/datacenter/cloud)
};

// RobotPerf entries for one run: latency (value = the maximum latency from the scheduled send, in
// ms), throughput (output rate, in fps) and, when a real source was read, power (average W).
std::vector<PublishedResult> export_entries(const StoredRun& run, const ExportOptions& options);

// YAML text of `entries` as a `results:` block sequence (what `results export` prints).
std::string entries_yaml(const std::vector<PublishedResult>& entries);

struct MergeOutcome {
  std::string text;  // the new file content
  std::size_t added = 0;
  std::size_t already_present = 0;  // identical entries that were not added again
};

// Appends `entries` to the `results` sequence of the benchmark.yaml text `original` (read from
// `name`, used in messages). Every byte of the existing entries and of the other keys is kept:
// new entries are inserted after the last existing one, in its indentation and key order; an
// empty `results: []` becomes a block sequence. The result is parsed back and checked before it
// is returned. Throws ReportError when the file cannot be merged safely (e.g. a flow-style
// sequence).
MergeOutcome merge_entries(const std::string& original, const std::string& name,
                           const std::vector<PublishedResult>& entries);

// Imported files in the results folder ("results import --into"), schema robotperf.published/1.
inline constexpr const char* kPublishedSchema = "robotperf.published/1";
nlohmann::json to_json(const PublishedBenchmark& benchmark);
PublishedBenchmark published_from_json(const nlohmann::json& j, const std::filesystem::path& from);

// One line per flagged row: "<file>:<line>: <hardware> <metric> <value>: <reason>; ...".
std::string flagged_rows_report(const PublishedBenchmark& benchmark);

// Shortest text that reads back as exactly `value`.
std::string shortest_number(double value);

}  // namespace robotperf::report
