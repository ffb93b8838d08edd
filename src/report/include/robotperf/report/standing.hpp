// Where a run stands against the published RobotPerf results of its benchmark: the one line of
// the summary's verdict that tells a reader whether the number is good (docs/design.md §8).
#pragma once

#include <string>
#include <vector>

#include "robotperf/harness/run.hpp"
#include "robotperf/report/benchmark_yaml.hpp"

namespace robotperf::report {

// Compared like with like: RobotPerf publishes a latency's maximum, so the run's maximum goes
// against the black-box latency rows of the same benchmark at the same input rate (a control
// benchmark's rows state the controller's rate), flagged rows left out, each platform by the
// median of its rows. Empty when no such row exists or the run matched no message.
std::string published_standing(const harness::RunResult& run,
                               const std::vector<PublishedBenchmark>& published);

}  // namespace robotperf::report
