// Private to the harness: grey-box runs. The run is recorded in an LTTng
// session and its results are computed from the CTF trace (src/tracing).
#pragma once

#include <memory>

#include "robotperf/harness/run.hpp"
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
  std::unique_ptr<tracing::RecordingSession> session_;
};

// robotperf:run_begin / run_end around the Playback (emitted in both modes:
// free while no session is active).
void trace_run_begin(const BenchmarkSpec& spec, const RunResult& result, int64_t period_ns);
void trace_run_end(std::size_t sent);
// robotperf:run_join from a per-node child: its events belong to its parent's run.
void trace_run_join();

}  // namespace robotperf::harness
