// What bench_backends prints of one run of a benchmark on a backend, and issue #19's target
// judged from two of them.
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

// Issue #19's target for the cuda backend of `id` against `cpu`, and whether `cuda` meets it:
// "-" for a benchmark without one; else each part with ": met" or ": NOT met" (a1 has two, joined
// by "; "), or the parts and ": not judged" where either run is invalid (a latency of a graph
// that fell behind its rate or answered wrongly says nothing).
std::string cuda_target(const std::string& id, const BackendRow& cpu, const BackendRow& cuda);

}  // namespace robotperf::bench
