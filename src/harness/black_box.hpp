// Private to the harness: the Playback and Monitor nodes around the graph
// under test (docs/design.md §3).
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "robotperf/graph/node.hpp"
#include "robotperf/harness/benchmark_spec.hpp"
#include "robotperf/harness/dataset.hpp"
#include "robotperf/harness/run.hpp"
#include "run_isolation.hpp"

namespace robotperf::harness {

// For replaying a bag on its own timeline: the send time of message k relative
// to the first, for `count` messages, the recorded intervals divided by
// `scale`; the dataset loops with one mean interval between its last and first frame.
std::vector<int64_t> timeline_schedule(const std::vector<int64_t>& frame_times_ns, double scale,
                                       std::size_t count);

// The send time of message k relative to the first, for `count` messages at a mean interval of
// `period_ns`, following `pattern`. Poisson intervals come from a 64-bit Mersenne Twister seeded
// with pattern.seed, turned into exponential ones here (not by the standard library, whose
// distributions differ between implementations), so that a seed means the same schedule
// everywhere.
std::vector<int64_t> arrival_schedule(const ArrivalPattern& pattern, int64_t period_ns,
                                      std::size_t count);

// When a graph whose nodes compute on a device has warmed up: its device programs are built at
// the first message (an OpenCL driver compiles them then, for seconds on a CPU device), and the
// messages sent meanwhile queue up. Given the graph's answers so far at the end of each round of
// the warm-up, it is ready when it answers at its steady pace: as many answers in a round as
// messages sent in it (it keeps up), or some but no more than in the round before (it is slower
// than the rate, which the measurement will show). Or none after some: a graph that pairs its
// inputs by exact time (a3's disparity) drops the repeated warm-up, whose stamps are older than
// the sets it has emitted, so once its backlog is answered it falls silent, idle and warm.
class DeviceWarmup {
 public:
  explicit DeviceWarmup(std::size_t messages_per_round) : per_round_(messages_per_round) {}
  bool ready_after_round(std::size_t answers_so_far);

 private:
  std::size_t per_round_;
  std::size_t answers_before_ = 0;
  std::size_t answers_in_round_ = 0;
};

class Playback {
 public:
  // Streams of serialized payloads (bags) are published as they are, with the
  // ID written into their header bytes, when `publish_serialized`; otherwise
  // they are decoded here, before timing, into the compiled-in type. An empty
  // `schedule_ns` paces message k at k·ids.period_ns.
  Playback(graph::Context& context, const BenchmarkSpec& spec, const Dataset& dataset,
           MessageIds ids, bool publish_serialized = false, std::vector<int64_t> schedule_ns = {});
  std::shared_ptr<graph::Node> node() const { return node_; }

  // Holding the first measured message back until the graph delivers: with `delivering` set,
  // the warm-up messages (ids below `warmup`) are sent again, in their order and pace, until it
  // returns true, and measuring starts after. A graph robotperf did not start may have matched
  // our endpoints (what discovery shows us) before its own side has matched ours.
  struct DeliveryGate {
    std::size_t warmup = 0;
    std::function<bool()> delivering;
    int64_t deadline_ns = 0;  // steady clock; past it, GraphNotConnected with timeout_message()
    std::function<std::string()> timeout_message;  // asked at the deadline, what happened by then
  };

  // Sends ids.count messages, message k at start + k·period or start + schedule_ns[k] (absolute
  // deadlines: a late send does not delay the next ones); messages due at the same time (bursts)
  // are all prepared before it and sent back to back. Fills `records` (with the first send of a
  // repeated warm-up message). Stops early when `should_stop` returns true; returns the number of
  // distinct messages sent, which `after_send` is also given. Returns how long the warm-up was
  // repeated in `repeated_ns`.
  std::size_t run(std::vector<MessageRecord>& records, const std::function<bool()>& should_stop,
                  const std::function<void(std::size_t sent)>& after_send,
                  const DeliveryGate* gate = nullptr, int64_t* repeated_ns = nullptr);

  // Instead of the schedule (docs/design.md §3.3): a message goes once at most `in_flight - 1`
  // messages are outstanding, i.e. once `answered(id, deadline)` says the output of the message
  // `in_flight` before it arrived, or `give_up_ns` after that one's send when it never does
  // (single-stream: 1; offline: as many as the graph's queues hold). A message is scheduled when
  // it may go. Before run().
  struct Pacing {
    Scenario scenario = Scenario::kOpenLoop;
    std::function<bool(uint64_t id, int64_t deadline_ns)> answered;
    int64_t give_up_ns = 0;
    std::size_t in_flight = 1;
  };
  void pace(Pacing pacing) { pacing_ = std::move(pacing); }

 private:
  struct Input {
    const msgs::TypeSupport* type;
    std::vector<rmw::MessagePtr> messages;  // one per frame
    bool serialized;                        // msgs::SerializedMessage payloads
    std::shared_ptr<graph::GenericPublisher> publisher;

    rmw::MessagePtr copy_with_stamp(std::size_t frame, int64_t stamp_ns) const;
  };
  std::shared_ptr<graph::Node> node_;
  std::vector<Input> inputs_;
  MessageIds ids_;
  std::vector<int64_t> schedule_ns_;
  Pacing pacing_;
};

class Monitor {
 public:
  // The QoS the Monitor subscribes an output with: the graph's, but keeping everything delivered
  // (a briefly starved Monitor must not turn into loss charged to the graph under test).
  static rmw::QoS subscription_qos(rmw::QoS graph_output);

  // Counts receptions of ids >= `warmup` towards received_measured(). With `isolation`, another
  // run's receptions are counted as foreign and otherwise ignored. A graph's further outputs
  // (graph.yaml `outputs:`) have a Monitor each, of another node name, whose receptions are not
  // traced as the run's outputs (`traced` false): the trace's analysis times the first output.
  Monitor(graph::Context& context, const BoundaryTopic& output, MessageIds ids, std::size_t warmup,
          RunIsolation* isolation = nullptr, const std::string& node_name = "robotperf_monitor",
          bool traced = true);
  std::shared_ptr<graph::Node> node() const { return node_; }

  // Keeps the first reception of each of `ids` for the functional evaluation: a copy of a
  // message shared with the graph (intra), else the message itself. Call before the run starts.
  void keep_outputs(const std::vector<uint64_t>& ids);
  // Also subscribes `topic` (messages of `type` stamped with IDs) and keeps, for the IDs given to
  // keep_outputs, the last message of each: the truth observed during the run. Before the run.
  void keep_observed_truth(const std::string& topic, const msgs::TypeSupport& type);
  // Instead of keeping them, gives the outputs chosen by keep_outputs to `evaluator` as they
  // arrive (the first reception of each; plugin::EvaluatorInfo::on_arrival), output ID k as
  // frame k mod `frames`. Before the run; the evaluator outlives it.
  void evaluate_on_arrival(plugin::FunctionalEvaluator& evaluator, std::size_t frames);

  // Waits until message `id`'s output arrived (true), or `deadline_ns` passes (false).
  bool wait_received(uint64_t id, int64_t deadline_ns);
  // Waits until `expected` measured messages arrived, and the observed truth of every kept one
  // (a node's second output follows its first), or `deadline_ns` passes.
  bool wait_for(std::size_t expected, int64_t deadline_ns);
  // The end of the drain: whatever arrives from now on is ignored (not counted, kept, evaluated
  // or traced), being lost by the run's rules however long the run takes to finish.
  void close();

  struct Tally {
    std::vector<int64_t> received_ns;  // per id, -1 when never received
    std::size_t received_measured = 0;
    std::size_t duplicates = 0;
    std::size_t unknown = 0;
    std::size_t foreign = 0;                                 // another run's (RunIsolation)
    std::vector<std::pair<uint64_t, rmw::MessagePtr>> kept;  // by keep_outputs, in arrival order
    // State outputs: receptions of an ID already received (not duplicates).
    std::size_t repeats = 0;
    std::map<uint64_t, rmw::MessagePtr> observed_truth;  // by keep_observed_truth
    std::size_t evaluated_on_arrival = 0;                // by evaluate_on_arrival
    // What the on-arrival evaluator threw, after which it was given nothing more; empty if none.
    std::string evaluation_error;
  };
  Tally tally() const;
  std::size_t received() const;

 private:
  void on_message(const rmw::MessagePtr& msg, const graph::MessageInfo& info, int64_t now_ns);

  std::shared_ptr<graph::Node> node_;
  const msgs::TypeSupport* type_;
  std::string topic_;
  MessageIds ids_;
  std::size_t warmup_;
  RunIsolation* isolation_;
  bool state_;
  bool traced_;
  std::vector<bool> keep_;               // per id
  std::vector<std::size_t> kept_index_;  // per id: where in tally_.kept, or SIZE_MAX
  bool observing_truth_ = false;         // keep_observed_truth was called
  plugin::FunctionalEvaluator* on_arrival_ = nullptr;
  std::size_t on_arrival_frames_ = 1;
  std::size_t evaluations_pending_ = 0;  // outputs received whose add() has not returned yet
  std::atomic<int64_t> closed_at_ns_{INT64_MAX};  // by close(): later receptions are ignored
  mutable std::mutex mutex_;
  std::mutex evaluate_mutex_;  // one add() at a time, outside mutex_
  mutable std::condition_variable cv_;
  Tally tally_;
  std::size_t received_ = 0;
};

}  // namespace robotperf::harness
