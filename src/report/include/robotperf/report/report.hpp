// The comparison report: per category, radar plots of latency, throughput and power across
// hardware (RobotPerf's presentation); per benchmark, every run and its latency distribution; a
// comparison of two runs or platforms with a significance judgement; machine descriptions and
// validity warnings. As one self-contained HTML page (inline SVG and CSS, no script, no network)
// and as Markdown with the same tables.
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

struct ReportOptions {
  std::string title = "robotperf report";
  // Two selectors: a results file (path, name or name prefix such as "a1-fastdds"), a hardware
  // name (local or published), or a series name as the radar legend shows it. Without it, the
  // first two local series are compared when there are two or more.
  std::optional<std::pair<std::string, std::string>> compare;
  std::size_t max_radar_series = 12;
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
