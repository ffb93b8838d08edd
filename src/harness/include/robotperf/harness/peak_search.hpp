// Peak-throughput search: the highest input rate a graph sustains within stated bounds, found by
// running the benchmark at one rate after another (ros2_benchmark's and MLPerf LoadGen's peak
// searches), each step a full measured run with its own warm-up and validity rules.
#pragma once

#include <functional>
#include <optional>

#include "robotperf/harness/run.hpp"

namespace robotperf::harness {

struct PeakSearchOptions {
  // A rate is sustained when the run completes without duplicates or unknown IDs, the Playback
  // kept the rate its schedule asked for, at most this share of the measured messages is lost
  // (default: the benchmark's max_loss_percent, so that the run at the peak is valid by the
  // benchmark's own rules), the outputs came out at least 95 % as fast as the inputs went in, and
  // (when given) the latency percentile is within its bound.
  std::optional<double> loss_bound_percent;
  std::optional<double> latency_bound_ms;
  double latency_percentile = 99.0;  // of the latency from the scheduled send
  // The rates searched; default: from the benchmark's rate (or RunOptions::rate_hz) up to 1 MHz.
  std::optional<double> rate_low_hz, rate_high_hz;
  // Bisection stops once the failing rate is within this many percent above the passing one.
  double resolution_percent = 5.0;
  double step_duration_s = 5.0;  // measured messages per step = rate x this
};

struct PeakSearchResult {
  PeakSearchRecord record;
  // The run at the highest rate that met the bounds (throughput_kind "peak", peak_search set);
  // absent when even the lowest rate did not.
  std::optional<RunResult> peak;
};

// Searches by bracketing (doubling from the low rate until a rate fails or the high one passes;
// halving while the low one fails) and then bisection to the resolution. `on_step` sees each step
// as it ends. A step that cannot run (bad options) throws as run_benchmark does; one that ends in
// an error (a node died) or an interrupt ends the search, its reason the stop reason.
PeakSearchResult find_peak(const BenchmarkSpec& spec, const RunOptions& options,
                           const PeakSearchOptions& search,
                           const std::function<void(const PeakStep&)>& on_step = {});

// Whether a finished run sustained its rate within the bounds: the reason it did not, else empty.
std::string peak_step_failure(const RunResult& run, const BenchmarkSpec& spec,
                              const PeakSearchOptions& search, double latency_ms);

}  // namespace robotperf::harness
