// The comparison report: an executive summary (what was run, on which systems, the findings that
// matter, validity); per benchmark, sorted bars of its configurations and the published rows, a
// table of this system against the published ones, every run and its latency distribution;
// optionally radar plots per category (RobotPerf's presentation); a comparison of two
// configurations with a significance judgement; machine descriptions. As one self-contained HTML
// page (inline SVG, CSS and a filtering script, no network) and as Markdown with the same tables.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "robotperf/report/benchmark_yaml.hpp"
#include "robotperf/report/run_store.hpp"

namespace robotperf::report {

struct ReportInput {
  std::vector<StoredRun> runs;
  std::vector<PublishedBenchmark> published;
  std::vector<std::string> skipped;  // files in the given folders that could not be read
};

// Reads results files, imported files (robotperf.published/1), benchmark.yaml files, and folders
// holding any of them (searched recursively). A named file that cannot be read throws
// ReportError; unreadable files inside a folder are listed in `skipped`.
ReportInput load_report_inputs(const std::vector<std::filesystem::path>& paths);

// The files of the local runs that the selectors choose (as `compare` takes them): for a caller
// that lists many runs from the results database and reads only these whole. Selection reads
// only what a listed run has (its file, configuration, labels, rates), so it chooses as it would
// among the runs read whole.
std::vector<std::filesystem::path> files_of_runs_chosen(const ReportInput& input,
                                                        const std::vector<std::string>& selectors);

// More polygons than this on one radar cannot be told apart.
inline constexpr std::size_t kMaxRadarSeries = 6;

struct ReportOptions {
  std::string title = "robotperf report";
  // Two selectors: a results file (path, name or name prefix such as "a1-fastdds"), a hardware
  // name (local or published), or a series name as the report names it. Without it, two local
  // configurations that ran a benchmark in common are compared, when there are such.
  std::optional<std::pair<std::string, std::string>> compare;
  // Radar plots per category (RobotPerf's presentation); off by default, at most
  // kMaxRadarSeries series each.
  bool radar = false;
  std::size_t max_radar_series = 6;
  std::size_t max_distribution_runs = 8;
};

// Throws ReportError when a --compare selector matches nothing.
std::string render_html(const ReportInput& input, const ReportOptions& options);
std::string render_markdown(const ReportInput& input, const ReportOptions& options);
// `robotperf compare A B`: the report's comparison of two selectors (as ReportOptions::compare
// takes them) as an aligned text table with ratios and judgements, then what each side holds.
std::string render_comparison_text(const ReportInput& input, const std::string& a,
                                   const std::string& b);

}  // namespace robotperf::report
