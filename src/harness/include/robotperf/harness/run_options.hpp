// What run_benchmark is asked to do, grouped by concern: the load (what is sent and when), the
// nodes' overrides, the transport, the processes, the recording and the power sampling. Each
// group checks its own values (check()); RunOptions::check() adds the rules that join groups
// (docs/design.md §4).
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "robotperf/graph/node.hpp"
#include "robotperf/harness/dataset.hpp"
#include "robotperf/harness/network_link.hpp"
#include "robotperf/harness/scheduling.hpp"
#include "robotperf/metrics/power.hpp"
#include "robotperf/rmw/transport.hpp"

namespace robotperf::harness {

enum class ProcessLayout { kSingle, kPerNode };

// Black-box: Playback and Monitor measure around the graph. Grey-box: the run
// is also recorded with LTTng and the results come from the trace (src/tracing).
enum class RunMode { kBlack, kGrey };

// When the Playback sends, beside a bag's recorded timeline (MLPerf LoadGen's scenarios).
struct ArrivalPattern {
  enum class Kind {
    kFixed,    // every 1/rate
    kPoisson,  // exponential intervals of mean 1/rate (a server's random clients)
    kBurst     // `burst` messages back to back every burst/rate
  };
  Kind kind = Kind::kFixed;
  std::size_t burst = 1;
  uint64_t seed = 1;  // Poisson: the same seed gives the same schedule on every machine

  // "fixed", "poisson" or "burst:N"; throws std::invalid_argument otherwise.
  static ArrivalPattern parse(const std::string& text);
  std::string name() const;  // as parse() reads it
};

// Whether the Playback paces itself or follows the graph (MLPerf LoadGen's scenarios, named as it
// names them; docs/design.md §3.3).
enum class Scenario {
  kOpenLoop,      // messages at their arrival times whatever the graph does (LoadGen's Server
                  // with Poisson arrivals; with fixed ones, a camera)
  kSingleStream,  // the next message when the previous one's output arrived: latency with no
                  // queueing (LoadGen's SingleStream)
  kOffline,       // every message at once, back to back: throughput (LoadGen's Offline)
};
// "open-loop", "single-stream" or "offline"; parse throws std::invalid_argument otherwise.
Scenario parse_scenario(const std::string& text);
std::string scenario_name(Scenario scenario);

// The stages of run_benchmark, in their order: each acquires what it needs for the run, and an
// exception or interrupt at any point releases what the stages before it acquired.
enum class RunStage {
  kPlan,        // the options checked against the benchmark and resolved; the dataset loaded
  kPrepare,     // scheduling, grey-box recording, transport, Playback and Monitor
  kStartGraph,  // the graph's nodes: in this process, per node, or an external graph's launched
  kConnect,     // discovery, the run rules (--strict)
  kMeasure,     // the warm-up, then the measured messages
  kDrain,       // the outputs still on their way
  kStopGraph,   // executors, node processes, the nodes' reports
  kSummarise,   // the figures, and the warnings about the run
  kCheck        // the outputs against ground truth, other backends' against the cpu's
};
std::string to_string(RunStage stage);

// What the Playback sends and when; every value left out is the benchmark's.
struct LoadOptions {
  std::optional<double> rate_hz;
  std::optional<std::size_t> count;   // messages to send, warm-up included
  std::optional<double> duration_s;   // alternative to count: rate * duration
  std::optional<std::size_t> warmup;  // messages sent before timing
  std::optional<double> drain_s;      // how long outputs still on their way are waited for
  // Replay this bag's topics instead of the benchmark's built-in dataset.
  std::optional<BagSelection> bag;
  // Bags: send frames on the bag's recorded timeline, `rate_scale` times as fast, instead of at
  // a fixed rate.
  bool bag_timeline = false;
  double rate_scale = 1.0;
  // Otherwise, when messages are sent at the rate.
  ArrivalPattern arrival;
  // Or not at arrival times at all: closed loop, or everything at once.
  Scenario scenario = Scenario::kOpenLoop;

  // Throws std::invalid_argument naming the option (--rate, --count, ...) that is out of range.
  void check() const;
};

// Changes to what the graph's nodes compute on, each a configuration of its own.
struct NodeOverrides {
  // Control benchmarks: the controller managers' loop rate in Hz (default: the graph's).
  std::optional<double> update_rate_hz;
  // --backend: the nodes whose kernel has this backend run on it (override_backend).
  std::optional<std::string> backend;
  // --device-resident: images stay on the device between nodes that can hand them over there
  // (keep_on_device); single-process intra runs only.
  bool device_resident = false;

  bool any() const { return update_rate_hz || backend || device_resident; }
};

// How messages travel between the Playback, the nodes and the Monitor.
struct TransportOptions {
  std::string rmw = "intra";
  int domain_id = 0;
  // DDS Security: the keystore whose enclave rmw::kDefaultEnclave every participant of the run
  // (Playback, Monitor, nodes, children) presents; empty: unsecured.
  std::filesystem::path keystore;
  // Whose ROS 2 graph conventions the DDS participants follow (GID layout on ros_discovery_info,
  // endpoint type hashes): the release of the nodes they meet (--ros-distro).
  rmw::RosDistro ros_distro = rmw::RosDistro::kJazzy;
  // How the Monitor waits for the graph's outputs. Asleep (the default), an output's latency
  // includes the Monitor thread's wake-up, as a downstream ROS 2 node would pay it; spinning, it
  // does not, and the Monitor keeps one core busy for the whole run (--monitor-wait spin).
  graph::WaitMode monitor_wait = graph::WaitMode::kSleep;
};

// Where the graph's nodes run and how long they may take.
struct ProcessOptions {
  ProcessLayout layout = ProcessLayout::kSingle;
  // For per-node runs: the robotperf executable and the arguments that make it
  // run one node ("node" subcommand); the runner appends its own.
  std::vector<std::string> node_command;
  // The command prefix that runs a command on each host nodes are placed on (graph.yaml
  // `host:`), e.g. {"ssh", "robot-b", "--"} (the default) or {"ip", "netns", "exec", "ns"}.
  std::map<std::string, std::vector<std::string>> host_launchers;
  // The link between the runner's host and the others, when robotperf made it (--netns).
  const NetworkLink* network_link = nullptr;
  // Where the logs of an external graph's processes go (graph.yaml `launch:`); default: the
  // working folder.
  std::filesystem::path log_dir = ".";
  // Pinned CPUs, real-time priority, locked memory. In a single-process run they apply to the
  // whole process (Playback and Monitor too); per node, to the children.
  SchedulingOptions scheduling;
  double connect_timeout_s = 15.0;  // discovery and node start-up, before timing
  // A callback running longer than this ends the run with its node named as hung.
  double callback_timeout_s = 30.0;

  void check() const;
};

// Grey-box recording.
struct TracingOptions {
  RunMode mode = RunMode::kBlack;
  // The folder the CTF trace is written to (must not exist yet), and the per-CPU sub-buffer size
  // (0: sized for the workload).
  std::filesystem::path trace_dir;
  std::size_t subbuf_bytes = 0;
};

struct RunOptions {
  LoadOptions load;
  NodeOverrides nodes;
  TransportOptions transport;
  ProcessOptions processes;
  TracingOptions tracing;
  // Power sources and their sampling period; sampled during the measured window only.
  metrics::PowerOptions power;
  // Refuse to run (RunRefused) when a run rule is broken, instead of recording a warning.
  bool strict = false;
  // Set (to the signal's number) by whoever handles SIGINT/SIGTERM: the run ends at once, keeping
  // what it measured, marked interrupted.
  const std::atomic<int>* interrupted = nullptr;
  // Called from the playback thread after each send.
  std::function<void(std::size_t sent, std::size_t total, std::size_t received)> progress;
  // Called from the thread of run_benchmark as each stage begins.
  std::function<void(RunStage)> on_stage;

  // Each group's check(), then the rules between groups (a device-resident run is intra and in
  // one process; a spinning Monitor needs a CPU of its own).
  void check() const;
};

}  // namespace robotperf::harness
