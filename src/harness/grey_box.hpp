// Private to the harness: grey-box runs. The run is recorded in an LTTng
// session and its results are computed from the CTF trace (src/tracing).
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "robotperf/harness/run.hpp"
#include "robotperf/tracing/analysis.hpp"
#include "robotperf/tracing/session.hpp"

namespace robotperf::harness {

class GreyBoxRecording {
 public:
  // Starts the session before the graph is built, so that the ros2:*
  // initialisation events are in the trace. Throws tracing::TracingUnavailable
  // when LTTng is missing.
  GreyBoxRecording(const BenchmarkSpec& spec, const RunOptions& options, RunResult& result);

  // Stops the session, analyses the trace, and puts its counts, latencies,
  // throughput and validity into `result` (keeping the run's own errors).
  void finish(RunResult& result);

 private:
  // The shortest path of the traced graph from one of the benchmark's inputs to its output.
  std::optional<std::vector<std::string>> path_to_output(const tracing::TraceAnalysis& a) const;
  // The run's counts and latencies as measured along `path` (outputs with stamps of their own).
  void measure_along_path(RunResult& r, const tracing::PathLatency& path) const;

  std::unique_ptr<tracing::RecordingSession> session_;
  // What measuring along a path needs of the benchmark (outputs_restamped).
  std::vector<std::string> input_topics_;
  std::string output_topic_;
  std::size_t min_samples_ = 0;
  double max_loss_percent_ = 0;
};

// robotperf:run_begin / run_end around the Playback (emitted in both modes:
// free while no session is active).
void trace_run_begin(const BenchmarkSpec& spec, const RunResult& result, int64_t period_ns);
void trace_run_end(std::size_t sent);
// robotperf:run_join from a per-node child: its events belong to its parent's run.
void trace_run_join();

}  // namespace robotperf::harness
