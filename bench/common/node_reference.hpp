// The like-for-like reference of a kernel's time in its benchmark graph: the benchmark's own
// kernel nodes, built by the harness as a run builds them, on an executor of their own, fed the
// same frames as the Playback feeds the graph (fresh copies made ahead on the sending thread,
// stamped, published at their time, which wakes the executor as in the graph). The time of a
// frame runs from the executor's first callback for it to the answer's arrival at a sink node on
// the same executor thread: the same node code on the same messages, with the same output
// allocation and the same thread hand-off into the executor, but without what the graph adds to a
// message's latency — the Playback's publish, the wake-up into the executor, the Monitor.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <functional>
#include <memory>
#include <mutex>
#include <vector>

#include "robotperf/graph/executor.hpp"
#include "robotperf/graph/node.hpp"
#include "robotperf/harness/benchmark_spec.hpp"
#include "robotperf/harness/dataset.hpp"
#include "robotperf/harness/run.hpp"

namespace robotperf::bench {

class NodeReference {
 public:
  using Clock = std::chrono::steady_clock;

  // Builds every node of `spec` on an intra transport of its own and starts their executor
  // (spec.executor_threads threads); `dataset` must outlive it.
  NodeReference(const harness::BenchmarkSpec& spec, const harness::Dataset& dataset);
  ~NodeReference();

  // Frames 0..count-1 paced as the Playback paces a run, on the calling thread: frame k made
  // `lead` before first + k * period and published then. Returns each frame's time in ms (NaN
  // for a frame whose answer did not come within a second).
  std::vector<double> run_paced(Clock::time_point first, Clock::duration period,
                                Clock::duration lead, std::size_t count);

  // A round: `run_graph` runs the benchmark with `options` (given a progress callback to see its
  // first send) and, beside it in the same process, this reference takes the same frames half a
  // period after each of the graph's sends, 2 ms lead, so that both meet the same load. Returns the
  // graph's result; `reference_ms` gets the reference's times of the frames after the warm-up
  // that it answered.
  harness::RunResult run_beside(
      harness::RunOptions options,
      const std::function<harness::RunResult(const harness::RunOptions&)>& run_graph,
      std::vector<double>& reference_ms);

 private:
  struct Input {
    std::shared_ptr<graph::GenericPublisher> publisher;
    const harness::DatasetStream* stream;
  };
  const harness::Dataset& dataset_;
  std::unique_ptr<graph::Context> context_;
  std::unique_ptr<graph::Node> driver_;  // publishes the inputs, off the executor
  std::vector<Input> inputs_;
  std::size_t sent_ = 0;  // frames sent so far: their stamps increase across calls

  std::mutex mutex_;
  std::condition_variable answered_;
  Clock::time_point first_callback_{};  // of the frame in flight; zero until its probe runs
  std::vector<double> took_ms_;         // per answered frame

  std::unique_ptr<graph::Executor> executor_;  // last: stopped before the rest goes
};

// One round of an overhead bench, at `options`' rate, count and warm-up: `spec` on intra (as
// harness::run_benchmark runs it) and, beside it, a NodeReference built afresh, so that each round
// draws both sides' thread placement anew. Times of the measured frames in ms; `graph_result` gets
// the graph's run (its functional result among the rest).
struct OverheadSamples {
  std::vector<double> reference_ms, graph_ms;
};
OverheadSamples measure_overhead_round(const harness::BenchmarkSpec& spec,
                                       const harness::Dataset& dataset,
                                       const harness::RunOptions& options,
                                       harness::RunResult& graph_result);

}  // namespace robotperf::bench
