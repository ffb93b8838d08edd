// Private to the harness: the first stage of a run (RunStage::kPlan). It checks what the run is
// asked for against the benchmark and resolves it (overrides, layout, rate, count, warm-up,
// drain) and loads the dataset, but starts nothing: no transport, no thread, no process.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "robotperf/harness/benchmark_spec.hpp"
#include "robotperf/harness/dataset.hpp"
#include "robotperf/harness/run.hpp"

namespace robotperf::harness {

struct RunPlan {
  // The benchmark as run: the package's, or a copy with RunOptions' overrides applied.
  const BenchmarkSpec& spec() const { return overridden ? *overridden : *package; }
  const BenchmarkSpec* package = nullptr;  // the caller's, which outlives the run
  std::optional<BenchmarkSpec> overridden;
  Dataset dataset;
  std::vector<std::string> corrupt_messages;  // of a bag: one line each, for the warnings
  // The result to be, with what is known before the run (its configuration as run); the later
  // stages take it over.
  RunResult result;
  int64_t period_ns = 0;  // the mean interval between messages: 1 / result.rate_hz
  // The benchmark names a functional evaluator and the dataset has ground truth for it.
  bool evaluate_outputs = false;
};

// Throws std::invalid_argument (or the dataset's errors) for a run that cannot be made as asked.
RunPlan plan_run(const BenchmarkSpec& package_spec, const RunOptions& options);

// Seconds or Hz as messages write them (6 significant digits).
std::string number_text(double value);

}  // namespace robotperf::harness
