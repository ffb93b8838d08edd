// What bench_backends prints of one run of a benchmark on a backend, of several runs of it, and
// issue #19's target judged from them.
#pragma once

#include <string>
#include <vector>

#include "robotperf/harness/run.hpp"

namespace robotperf::bench {

struct BackendRow {
  double p50_ms = 0, p99_ms = 0;  // latency from send
  double loss_percent = 0;
  // The run delivered what its benchmark requires (harness::RunResult::valid) and its answers
  // passed the functional checks, the check against the cpu backend's among them.
  bool valid = false;
  std::vector<std::string> reasons;  // why not, one line each
};

BackendRow backend_row(const harness::RunResult& run);

// Several runs of one backend as one row: p50 and p99 the medians of the runs', the loss the
// largest, valid when every run is, the reasons each run's ("run k: " before them where there
// are several). Throws std::invalid_argument for no runs.
BackendRow combined(const std::vector<BackendRow>& runs);

// A backend's speed-up over the cpu's in pairs of runs, run k of each measured one after the
// other (the machine's state drifts between runs more than within a pair): cpu p50 / backend p50
// of each pair, their median, least and most. Throws std::invalid_argument unless there are as
// many runs of each, at least one.
struct Speedup {
  double median = 0, least = 0, most = 0;
  std::size_t pairs = 0;
};
Speedup speedup(const std::vector<BackendRow>& cpu, const std::vector<BackendRow>& backend);

// Issue #19's target for the cuda backend of `id` and whether its runs meet it, against the
// cpu's runs (paired as speedup() pairs them): "-" for a benchmark without one; else each part
// with ": met" or ": NOT met" (a1 has two, joined by "; "; the speed-up judged on the pairs'
// median, a1's p50 on the median of cuda's, and the pairs' least and most said where there are
// several), or the parts and ": not judged" where any run is invalid (a latency of a graph that
// fell behind its rate or answered wrongly says nothing).
std::string cuda_target(const std::string& id, const std::vector<BackendRow>& cpu,
                        const std::vector<BackendRow>& cuda);

}  // namespace robotperf::bench
