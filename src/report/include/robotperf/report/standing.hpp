// Where a run stands against the published RobotPerf results of its benchmark: the verdict line
// of the summary and the report's table against the published rows, one rule for both
// (docs/design.md §8).
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "robotperf/harness/run.hpp"
#include "robotperf/report/benchmark_yaml.hpp"

namespace robotperf::report {

// What was ranked and against what.
struct Standing {
  double value_ms = 0;        // the run's maximum latency (or a series' median of maxima)
  std::size_t rows = 0;       // published rows measured alike
  std::size_t platforms = 0;  // their hardware
  std::size_t slower = 0;     // platforms whose median is above value_ms
  double best_ms = 0;         // the lowest platform median
  std::string best_platform;
  double median_ms = 0;  // the median of the platforms' medians
  std::string rate;      // as the rows state it ("30 Hz")
};

// Compared like with like: RobotPerf publishes a latency's maximum, so a maximum goes against the
// black-box latency rows of benchmark `id` (or `name`) that state one input rate equal to one of
// `rates_hz` (a control benchmark's rows state the controller's rate), flagged rows left out,
// each platform by the median of its rows. Nothing when no such row exists or `max_ms` is not a
// number.
std::optional<Standing> standing_among(double max_ms, const std::string& id,
                                       const std::string& name, const std::vector<double>& rates_hz,
                                       const std::vector<PublishedBenchmark>& published);

// The summary's line for a run: "RobotPerf max 11.422 ms: lower than 4 of 4 published platforms
// (black-box, 30 Hz; best 16.790 ms, median 19.602 ms)", or empty.
std::string published_standing(const harness::RunResult& run,
                               const std::vector<PublishedBenchmark>& published);

}  // namespace robotperf::report
