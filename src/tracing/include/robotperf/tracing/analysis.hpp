// Grey-box analysis of a CTF trace: end-to-end latency of a robotperf run from
// its input and output events matched by message ID (with the black-box
// statistics and validity rules), a per-hop breakdown, callback durations per
// node, and publish→take latencies per topic from the ros2:* events — the
// last two also for traces of real ROS 2 systems recorded with ros2_tracing.
#pragma once

#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <ostream>
#include <set>
#include <string>
#include <vector>

#include "robotperf/metrics/latency_stats.hpp"
#include "robotperf/tracing/paths.hpp"

namespace robotperf::tracing {

// The configuration a run records in its robotperf:run_begin event.
struct RunInfo {
  std::string benchmark;
  std::string rmw;
  uint64_t count = 0;
  uint64_t warmup = 0;
  int64_t period_ns = 0;
  uint64_t min_samples = 0;
  double max_loss_percent = 0;
  // The output is a state stream: later receptions of an ID are repeats, not duplicates (false
  // in traces from before robotperf recorded it).
  bool state_output = false;
  int pid = 0;              // the process that ran it (Playback and Monitor)
  std::set<int> processes;  // it and its per-node children
  bool ended = false;       // robotperf:run_end seen
  uint64_t sent_reported = 0;
};

// One frame the input component sent. Times are trace clock nanoseconds
// (CLOCK_MONOTONIC for LTTng traces).
struct MessageTimes {
  int64_t id = 0;  // the header stamp
  uint64_t index = 0;
  int64_t scheduled_ns = 0;
  int64_t sent_ns = 0;
  int64_t received_ns = -1;  // first output; -1 when lost
  bool warmup = false;
};

// One hop of the message path: a transport hop (published by one node, taken
// by another), a node hop (a node's callback start on its input to its
// publish of the output), a kernel (its computation), or one stage of a kernel on a
// device (upload, compute, download). Nanoseconds.
struct Hop {
  std::string kind;  // "transport", "node", "kernel" or "device"
  std::string node;  // the receiving node (transport) or the node
  std::string from;  // transport: publishing node; node: input topic
  std::string to;    // transport and node: topic; kernel: kernel name; device: the stage
  metrics::SampleStats duration;
  double mean_start_offset_ns = 0;  // mean hop start after the frame's send: orders the path
  std::string label() const;
};

struct CallbackStats {
  std::string node;
  std::string source;             // the topic, or "timer <period>"
  std::string symbol;             // ros2:rclcpp_callback_register's demangled symbol, or empty
  metrics::SampleStats duration;  // ns
};

struct TopicLatency {
  std::string topic;
  std::string publisher;  // node names ("?" when the trace lacks the init events)
  std::string subscriber;
  metrics::SampleStats latency;  // rmw_publish -> rmw_take, ns
};

// A controller manager's controller (the control category), from
// robotperf:controller_update_begin/end.
struct ControllerUpdateStats {
  std::string node;  // the controller manager
  std::string controller;
  metrics::SampleStats duration;  // one update(), ns
};

// One event of a trace's timeline (AnalyzeOptions::timeline): a callback (with its duration), or
// a publish or take (an instant). Times are the trace clock's nanoseconds.
struct TimelineEvent {
  enum class Kind : uint8_t { kCallback, kPublish, kTake };
  Kind kind = Kind::kCallback;
  int64_t ts = 0;
  int64_t duration = 0;  // callbacks
  int32_t pid = 0, tid = 0;
  std::string node;
  std::string what;  // the callback's source (topic or "timer <period>"), or the topic
};

// A tf2 buffer's calls (robotperf/plugin/tf2_buffer.hpp), from robotperf:tf2_begin/end.
struct Tf2CallStats {
  std::string node;               // the buffer's owner
  std::string operation;          // "set" or "lookup"
  metrics::SampleStats duration;  // one call, ns
};

// The tf2 calls' share of a run's latency: the calls that begin between the first measured
// message's send and the last matched output, per matched message.
struct Tf2Share {
  uint64_t calls = 0;  // in that window
  double calls_per_message = 0;
  double per_message_ns = 0;  // their durations together, per message
  double of_latency = 0;      // per_message_ns / the mean latency from the actual send
};

struct TraceAnalysis {
  // The trace.
  std::vector<std::string> traces;  // the CTF folders read
  uint64_t streams = 0;
  uint64_t packets = 0;
  uint64_t events = 0;
  uint64_t discarded_events = 0;
  uint64_t lost_packets = 0;
  // Packets whose event times go back or leave the packet's begin..end (a corrupt trace): their
  // events are left out, and the result is invalid. One line for each of the first ones.
  uint64_t defective_packets = 0;
  std::vector<std::string> packet_defects;
  int64_t first_ns = 0, last_ns = 0;
  double read_seconds = 0;  // wall time of the analysis

  // The robotperf run, when the trace holds one (of the process AnalysisOptions::run_pid names).
  std::optional<RunInfo> run;
  // The processes whose robotperf runs the trace holds, the first begun first.
  std::vector<int> run_pids;
  std::vector<MessageTimes> messages;  // by index
  std::size_t sent = 0, measured = 0, matched = 0, lost = 0, duplicates = 0, unknown = 0;
  std::size_t repeats = 0;  // a state output's further receptions of measured IDs (no error)
  // Measured messages without an output event while the tracer discarded events or lost packets,
  // or while defective packets' events were left out: the output may have been delivered and its
  // event not read, so they are not counted as lost (that alone makes the result invalid).
  std::size_t unobserved = 0;
  double loss_percent = 0;
  metrics::SampleStats latency_from_scheduled, latency_from_sent, send_lateness;  // ns
  double throughput_hz = 0, offered_rate_hz = 0, window_s = 0;
  std::vector<Hop> hops;  // ordered along the path

  // Any trace with ros2:* events.
  std::vector<CallbackStats> callbacks;
  std::vector<TopicLatency> topics;
  // Traces of robotperf control loops.
  std::vector<ControllerUpdateStats> controller_updates;
  // Any trace with the ros2 init events: the graph it shows (for `trace paths`), and the latency
  // of the path AnalyzeOptions::path names, when it names one.
  TracedGraph graph;
  std::optional<PathLatency> path;
  // With AnalyzeOptions::timeline: every callback, publish and take, in time order.
  std::vector<TimelineEvent> timeline;
  // Traces of nodes with a tf2 buffer.
  std::vector<Tf2CallStats> tf2_calls;
  std::optional<Tf2Share> tf2_share;  // a run whose nodes called a tf2 buffer
  // One line per table (or column) the trace cannot provide, saying why: which events it lacks.
  std::vector<std::string> unavailable;

  bool valid = false;
  std::vector<std::string> invalid_reasons;
};

struct AnalyzeOptions {
  // Analyse the run of this process (0: the first run in the trace).
  int run_pid = 0;
  // Processes that belong to the run besides the ones the trace says (per-node children).
  std::set<int> extra_processes;
  // Threads that decode the streams (0: one per core), and the bytes of a stream one of them
  // takes at a time (0: sized so that each thread takes a few parts). The result does not depend
  // on either.
  unsigned decode_threads = 0;
  uint64_t part_bytes = 0;
  // Topics of a path to measure (docs/design.md §3.13); empty: none. Each consecutive pair must be
  // joined by a node of the trace, or analyze_trace throws std::invalid_argument.
  std::vector<std::string> path;
  // Keep every callback, publish and take for a timeline (TraceAnalysis::timeline).
  bool timeline = false;
};

// Reads every CTF trace under `dir` (one per buffer domain) and analyses it.
// Throws ctf::CtfError for an unreadable trace, std::invalid_argument when
// `dir` holds no trace.
TraceAnalysis analyze_trace(const std::filesystem::path& dir, const AnalyzeOptions& options = {});

// The `grey` block of the results JSON: trace, hops, callbacks, topics (milliseconds), and
// controller updates (microseconds).
nlohmann::json to_json(const TraceAnalysis& analysis);

// Breakdown tables for a terminal: hops, callbacks, topics, and the tracer's losses.
std::string breakdown_table(const TraceAnalysis& analysis);

// The full report of `robotperf trace analyze`: run summary (when there is a run) + breakdown.
std::string analysis_summary(const TraceAnalysis& analysis);

// The analysis's timeline (and path instances, when it has a path) as Chrome Trace Event JSON,
// which Perfetto UI and chrome://tracing open: callbacks as complete events on their process and
// thread, publishes and takes as instants, each path instance as an async span.
void write_chrome_trace(const TraceAnalysis& analysis, std::ostream& out);

// Why `analysis` has no run: the trace holds none, or none of process `run_pid` (0: any), naming
// the processes whose runs it holds.
std::string missing_run(const TraceAnalysis& analysis, int run_pid);

}  // namespace robotperf::tracing
