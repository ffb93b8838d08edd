// Private to the harness: the stages of run_benchmark after its plan (run_plan.hpp), in their
// order (RunStage). A stage is a function of what the stages before it produced, or the
// constructor of the object that owns what it acquires: declared in run_benchmark in stage order,
// these unwind exactly what was set up, in reverse order, on an exception or interrupt.
#pragma once

#include <sys/types.h>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "black_box.hpp"
#include "grey_box.hpp"
#include "launched_processes.hpp"
#include "measurement.hpp"
#include "node_processes.hpp"
#include "robotperf/graph/executor.hpp"
#include "robotperf/harness/run.hpp"
#include "run_isolation.hpp"
#include "run_plan.hpp"

namespace robotperf::harness {

// kPrepare: where the run's threads run, its grey-box recording, its message IDs and transport.
struct RunEnvironment {
  RunEnvironment(const RunPlan& plan, const RunOptions& options, RunResult& r);
  RunEnvironment(const RunEnvironment&) = delete;
  RunEnvironment& operator=(const RunEnvironment&) = delete;

  // In one process the scheduling options cover every thread created from here on.
  std::optional<ScopedScheduling> scheduling;
  std::optional<GreyBoxRecording> grey;
  MessageIds ids;
  // On the heap: a callback that never returns keeps using it, and it is then left alive
  // (released, never destroyed; RunResult::threads_abandoned).
  std::unique_ptr<graph::Context> context;
  std::optional<RunIsolation> isolation;
  // Bag payloads go on the wire as recorded. They need a participant of their own: a DDS
  // participant knows one TopicDataType per type name, and the graph's typed endpoints need
  // theirs. Null otherwise: the Playback uses `context`.
  std::unique_ptr<graph::Context> playback_context;
};

// kPrepare, too: the Playback and Monitor around the graph, and what the Monitor keeps of the
// outputs for the checks after the run.
struct Instruments {
  Instruments(const RunPlan& plan, const RunOptions& options, RunEnvironment& env,
              const RunResult& r);
  Instruments(const Instruments&) = delete;
  Instruments& operator=(const Instruments&) = delete;

  Playback playback;
  Monitor monitor;
  // The graph's further outputs (graph.yaml `outputs:`), a Monitor each, and what each had when
  // the drain ended.
  std::vector<std::unique_ptr<Monitor>> more_monitors;
  std::vector<Monitor::Tally> more_tallies;
  std::vector<uint64_t> functional_ids;  // the outputs the Monitor keeps
  // An evaluator that checks each output as it arrives; null when the outputs are kept to the
  // end instead (a state output's later receptions, or a truth observed during the run).
  std::unique_ptr<plugin::FunctionalEvaluator> on_arrival;
  bool on_device = false;  // nodes run on another backend than cpu (uses_other_backend)
  graph::Executor monitor_executor;
};

// kStartGraph: the graph's nodes in this process under an executor, or its node processes, or
// an external graph's launched processes; the executors started.
struct GraphUnderTest {
  GraphUnderTest(const RunPlan& plan, const RunOptions& options, RunEnvironment& env,
                 Instruments& instruments, RunResult& r);
  GraphUnderTest(const GraphUnderTest&) = delete;
  GraphUnderTest& operator=(const GraphUnderTest&) = delete;

  // On the heap: a callback that never returns keeps using it, and it is then left alive.
  std::unique_ptr<graph::Executor> executor;
  std::vector<std::shared_ptr<graph::Node>> local_nodes;   // Playback, Monitor, kernel nodes
  std::vector<std::shared_ptr<graph::Node>> kernel_nodes;  // in the order of r.nodes
  std::unique_ptr<NodeProcesses> children;
  std::unique_ptr<LaunchedProcesses> launched;
  int64_t connect_deadline_ns = 0;  // steady clock: --connect-timeout from the start
};

// kConnect: returns once every endpoint has its peer (and every child is ready); throws
// RunInterrupted on an interrupt, GraphNotConnected at the deadline.
void connect_graph(const RunPlan& plan, const RunOptions& options, const RunEnvironment& env,
                   GraphUnderTest& graph, const RunResult& r);

// kConnect, once connected: what is measured over the window besides latency.
struct MeasurementWindow {
  MeasurementWindow(const RunOptions& options, const BenchmarkSpec& spec,
                    const GraphUnderTest& graph);
  WindowMeasurement measurement;
  std::optional<NetworkLink::Counters> link_before;  // when robotperf made the link
};

// kConnect, last: the run rules before timing, as warnings; throws RunRefused with --strict.
void check_before_timing(const RunPlan& plan, const RunOptions& options, RunEnvironment& env,
                         MeasurementWindow& window, RunResult& r);

// Why the run must end now: an interrupt (it marks the result interrupted), a callback stuck past
// the timeout, or a failure of the graph, the Monitor or a process.
class RunWatch {
 public:
  RunWatch(const RunOptions& options, const Instruments& instruments, const GraphUnderTest& graph,
           RunResult& r);
  // An interrupt or a stuck callback, from the first time one was seen; empty while neither.
  const std::string& must_stop();
  std::string failure();

 private:
  const RunOptions& options_;
  const Instruments& instruments_;
  const GraphUnderTest& graph_;
  RunResult& r_;
  std::string stop_now_;
};

// kMeasure: the warm-up (repeated until an external or device graph delivers), then the
// measured messages; throws RunInterrupted when interrupted before timing started.
void warm_up_and_measure(const RunPlan& plan, const RunOptions& options, Instruments& instruments,
                         MeasurementWindow& window, RunWatch& watch, RunResult& r);

// kDrain: waits for the outputs still on their way, closes the window, and tallies.
Monitor::Tally drain(const RunPlan& plan, const RunOptions& options, Instruments& instruments,
                     MeasurementWindow& window, RunWatch& watch, RunResult& r);

// kStopGraph: the executors (a stuck callback's, and its context, left alive), the processes, and
// the nodes' reports.
void stop_graph(const RunPlan& plan, RunEnvironment& env, Instruments& instruments,
                GraphUnderTest& graph, RunWatch& watch, RunResult& r);

// kSummarise: the figures (from the trace when grey-box), and the warnings about the run.
void summarise_run(const RunPlan& plan, const RunOptions& options, RunEnvironment& env,
                   const Monitor::Tally& tally, const std::vector<Monitor::Tally>& more_tallies,
                   RunResult& r);

// kCheck: after timing, the outputs against ground truth and other backends' against the cpu's.
void check_outputs(const RunPlan& plan, Instruments& instruments, const Monitor::Tally& tally,
                   RunResult& r);

// The device a built kernel node computes on, when its backend is not the host CPU.
std::optional<plugin::DeviceInfo> device_of(const graph::Node& node, const NodeSpec& spec);

}  // namespace robotperf::harness
