// Running a benchmark black-box: Playback -> graph under test -> Monitor.
#pragma once

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "robotperf/graph/node.hpp"
#include "robotperf/harness/backend_check.hpp"
#include "robotperf/harness/benchmark_spec.hpp"
#include "robotperf/harness/dataset.hpp"
#include "robotperf/harness/functional.hpp"
#include "robotperf/harness/network_link.hpp"
#include "robotperf/harness/run_options.hpp"
#include "robotperf/harness/scheduling.hpp"
#include "robotperf/metrics/latency_stats.hpp"
#include "robotperf/metrics/power.hpp"
#include "robotperf/metrics/resources.hpp"
#include "robotperf/plugin/kernel.hpp"
#include "robotperf/rmw/transport.hpp"
#include "robotperf/sysinfo/run_rules.hpp"
#include "robotperf/tracing/analysis.hpp"

namespace robotperf::harness {

// One message the Playback sent. Times are CLOCK_MONOTONIC nanoseconds.
struct MessageRecord {
  uint64_t id = 0;
  int64_t scheduled_ns = 0;
  int64_t sent_ns = 0;
  int64_t received_ns = -1;  // first reception; -1 when lost
  bool warmup = false;
};

// A backend's device as results, sysinfo and a per-node child's report to the runner write it.
nlohmann::json device_to_json(const plugin::DeviceInfo& device);
plugin::DeviceInfo device_from_json(const nlohmann::json& j);

struct NodeReport {
  std::string name;
  std::string kernel;
  int pid = 0;              // 0 when it ran in the runner's process
  std::string exit_status;  // "ok" or how it ended
  double cpu_user_s = -1;   // -1 when unknown
  double cpu_system_s = -1;
  // What the kernel counted (plugin::NodeCounters), e.g. inputs that never paired.
  std::map<std::string, uint64_t> counters;
  std::string host;             // graph.yaml `host:`; empty: the runner's
  std::string hostname;         // of the machine it ran on, as it reported (per-node runs)
  bool same_machine = true;     // as the runner's (same boot id): its pid's resources were sampled
  std::string backend = "cpu";  // where its kernel ran (graph.yaml `backend:`)
  // The device of a backend other than the host CPU (plugin::DeviceNode), for nodes in the
  // runner's process.
  std::optional<plugin::DeviceInfo> device;
  // What it computed with: its parameters as its kernel read them (graph.yaml's, the declared
  // defaults filled in), and where its kernel came from ("built-in perception", a plug-in file).
  std::map<std::string, std::string> parameters{};
  std::string origin{};
};

// A process of an external graph (graph.yaml `launch:`), as it ended.
struct LaunchedReport {
  std::string name;
  std::string command;  // as run
  int pid = 0;
  std::string exit_status;  // as NodeReport's
  std::string log;          // its stdout and stderr
  std::string stopped_by;   // "stopped by SIGINT", ..., or "ended during the run"
};

// The control loop of a kernel that runs one (plugin::ControlLoopSource), over the whole run:
// nanoseconds.
struct ControlLoopResult {
  std::string node;
  double update_rate_hz = 0;
  int cpu = -1;         // the loop thread's CPU, -1 when not pinned
  int rt_priority = 0;  // its SCHED_FIFO priority, 0 when none
  uint64_t cycles = 0;
  uint64_t recorded_cycles = 0;  // with timestamps (the buffer's capacity bounds it)
  uint64_t deadline_misses = 0;  // cycles whose hardware write ended after the next period began
  metrics::SampleStats update_duration;  // all controllers' update() of one cycle
  metrics::SampleStats cycle_duration;   // wake-up to the end of the hardware write
  metrics::SampleStats period_jitter;    // actual period (wake to wake) minus the nominal one
  metrics::SampleStats wake_latency;     // wake-up minus the cycle's deadline
  // Measured commands: hardware interface written with the command minus its scheduled send.
  metrics::SampleStats command_to_write;
};

// One rate a peak-throughput search tried (peak_search.hpp).
struct PeakStep {
  double rate_hz = 0;     // asked for
  double offered_hz = 0;  // the Playback achieved
  double output_hz = 0;
  double loss_percent = 0;
  double latency_ms = 0;  // the bounded percentile of latency from the scheduled send (NaN: none)
  bool passed = false;
  std::string reason;  // why it did not meet the bounds; empty when it did
};

// The search that found a run's rate, kept with the run at the peak.
struct PeakSearchRecord {
  double loss_bound_percent = 0;
  std::optional<double> latency_bound_ms;
  double latency_percentile = 99;
  double rate_low_hz = 0, rate_high_hz = 0;
  double resolution_percent = 0;
  double step_duration_s = 0;
  std::vector<PeakStep> steps;  // in the order tried
  // Why the search ended where it did: the next rate's failure, the top of the range, ...
  std::string stop_reason;
  // False when an interrupt or an error ended it before its bounds did: the best rate it had
  // then is only a rate the graph sustained, not its peak.
  bool finished = true;
};

// One monitored output's figures (graph.yaml `outputs:`; the first is the run's own).
struct OutputFigures {
  std::string topic;
  std::size_t matched = 0;
  std::size_t lost = 0;
  double loss_percent = 0;
  metrics::SampleStats latency_from_scheduled, latency_from_sent;  // ns
  double throughput_hz = 0;
  // Output jitter: the intervals between consecutive outputs of measured messages, in arrival
  // order, and how far each is from the input period (|interval - period|). Nanoseconds.
  metrics::SampleStats interval, jitter;
  double period_ns = 0;  // the input period they are compared with
};

struct RunResult {
  std::string benchmark_id;
  std::string benchmark_name;
  std::string sample;  // the package's `sample:` (BenchmarkSpec::sample)
  // run --label KEY=VALUE and the automatic ones (robotperf's version and revision, an external
  // package's git revision): series keys in reports and filters of every read verb.
  std::map<std::string, std::string> labels;
  std::string
      system;  // run --system: what reports call the hardware; empty: named from the machine
  std::string category;
  // Configuration as run.
  double rate_hz = 0;  // with the bag's timeline: its mean recorded rate times rate_scale
  // When frames are sent: "fixed" (every 1/rate_hz), "poisson", "burst" (ArrivalPattern) or
  // "bag" (the bag's recorded intervals divided by rate_scale).
  std::string timeline = "fixed";
  std::size_t burst = 1;      // "burst": messages per burst
  uint64_t arrival_seed = 0;  // "poisson": the generator's seed
  double rate_scale = 1.0;
  std::size_t count = 0;
  std::size_t warmup = 0;
  double drain_s = 0;
  // An external graph's warm-up sent again until the graph delivered (Playback::DeliveryGate):
  // how long timing waited for it.
  double warmup_repeated_s = 0;
  std::string rmw;
  std::string processes;               // "single" or "per-node"
  std::string monitor_wait = "sleep";  // "sleep" or "spin" (RunOptions::monitor_wait)
  // The topics a device-resident run kept on the device (keep_on_device); empty otherwise.
  std::vector<ResidentTopic> device_resident;
  // DDS Security as run: the keystore (absolute) and rmw::describe() of its enclave; empty when
  // unsecured.
  std::filesystem::path keystore;
  std::string security;
  std::string ros_distro;  // RunOptions::ros_distro, for DDS transports
  std::size_t executor_threads = 1;
  std::string output_topic;
  // The QoS of every endpoint robotperf made: the Playback's inputs, the Monitor's output and
  // each node's topics ("playback", "monitor" or the node name).
  struct EndpointQos {
    std::string owner;
    std::string topic;
    rmw::QoS qos;
  };
  std::vector<EndpointQos> qos;
  // Dataset.
  std::string dataset;
  std::string dataset_hash;
  std::size_t dataset_frames = 0;
  std::map<std::string, std::string> dataset_parameters;  // generated datasets: seed, requests, ...
  // Counts over the measured (post-warm-up) messages, except unknown and
  // duplicates, which count every reception.
  std::size_t sent = 0;
  std::size_t measured = 0;
  std::size_t matched = 0;
  std::size_t lost = 0;
  // Grey-box: measured messages whose output event the tracer may have discarded (not lost).
  std::size_t unobserved = 0;
  std::size_t duplicates = 0;
  std::size_t unknown = 0;
  std::size_t repeats = 0;  // state outputs: further receptions of an ID (not an error)
  // Receptions that belong to another run on the same domain (written by its participants, or
  // our graph's answers to its inputs): neither matched nor unknown.
  std::size_t foreign = 0;
  double loss_percent = 0;
  // Nanoseconds, over matched measured messages.
  metrics::SampleStats latency_from_scheduled;
  metrics::SampleStats latency_from_sent;
  // Sending lateness: actual minus scheduled send time.
  metrics::SampleStats send_lateness;
  double throughput_hz = 0;  // output rate: (matched - 1) / (last - first reception)
  // "offered": the graph was fed at a rate and kept up with it; "peak": the highest rate a
  // peak-throughput search found it sustains (peak_search then says how).
  std::string throughput_kind = "offered";
  std::optional<PeakSearchRecord> peak_search;
  double offered_rate_hz = 0;  // input rate actually achieved by the Playback
  double window_s = 0;         // from the first measured send to the last reception
  // Every monitored output, the run's own first, with its jitter (docs/design.md §3.5).
  std::vector<OutputFigures> outputs;
  // Grey-box: the outputs carried header stamps of their own, and the counts and latencies were
  // measured along the graph's path from the trace instead (docs/design.md §3.13).
  bool outputs_restamped = false;
  int64_t started_unix_ns = 0;
  bool completed = false;    // false when the run was cut short
  bool interrupted = false;  // cut short by SIGINT/SIGTERM (RunOptions::interrupted)
  // A callback never returned: its threads still run, using objects the run left alive for them.
  // End the process (std::_Exit) once the result is written; never destroy it normally.
  bool threads_abandoned = false;
  std::vector<std::string> errors;
  bool valid = false;
  std::vector<std::string> invalid_reasons;
  std::vector<NodeReport> nodes;
  std::vector<LaunchedReport> launched;  // graph.yaml `launch:`
  // The launcher of each host the graph placed nodes on (graph.yaml `host:`), as run.
  std::map<std::string, std::string> host_launchers;
  // The link robotperf made between the hosts (--netns), and what crossed it during the run
  // (discovery and warm-up included; bytes on the wire, headers and repairs included).
  struct LinkUse {
    NetworkLink::Description link;
    NetworkLink::Counters traffic;
  };
  std::optional<LinkUse> network_link;
  std::vector<MessageRecord> records;
  int domain_id = 0;
  // What tells this run's messages and participants from another's: the stamp of message k is
  // id_base_ns + k * period (a random base), and its participants carry run_token.
  int64_t id_base_ns = 0;
  std::string run_token;
  // The other participants seen on the domain, before and during the run.
  std::vector<rmw::PeerParticipant> domain_peers;
  SchedulingOptions scheduling;
  // Run rules broken before or during the run (docs/design.md §3.11).
  std::vector<sysinfo::RunWarning> warnings;
  // Over the measured window: from the first measured send to the end of the drain.
  metrics::PowerReport power;
  metrics::ResourceUsage resources;
  // Accuracy of the outputs against the dataset's ground truth; absent when the benchmark
  // names no functional evaluator.
  std::optional<FunctionalResult> functional;
  // Nodes on another backend than cpu: their sampled answers against the cpu's to the same inputs
  // (harness/backend_check.hpp); a drift makes the result functionally invalid.
  std::optional<BackendCheck> backend_check;
  // Control kernels: their loops' timing (empty for other benchmarks).
  std::vector<ControlLoopResult> control_loops;
  std::optional<double> update_rate_hz;  // the loop rate given with --update-rate
  // Grey-box runs: the analysis of the recorded trace (counts, latencies and
  // validity above then come from it) and where the trace is.
  std::optional<tracing::TraceAnalysis> grey;
  std::filesystem::path trace_dir;
  std::size_t trace_subbuf_bytes = 0;
};

// The latency from the scheduled send of every matched measured message, in ms, in message order.
std::vector<double> scheduled_latencies_ms(const RunResult& result);

// Moves a grey run's trace from where it was recorded (result.trace_dir) to `to`, and rewrites the
// recorded path in every line of the result that names it (invalid reasons, errors, the trace
// analysis' folders and defects), so that none points at the temporary folder once it is gone.
// Throws std::filesystem::filesystem_error when the rename fails.
void move_trace(RunResult& result, const std::filesystem::path& to);

// Thrown by run_benchmark with --strict when a run rule is broken; what() lists them.
class RunRefused : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The graph did not connect within the connect timeout: one line per endpoint without its peer.
class GraphNotConnected : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// "interrupted by SIGINT": how a result and a summary name the signal that ended a run.
std::string interrupted_by(int signal_number);

// An interrupt (RunOptions::interrupted) came before timing started: nothing was measured.
class RunInterrupted : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Runs the benchmark. Problems that stop the run before timing (bad spec,
// unknown transport, graph that never connects) throw; problems during the
// run (a node that dies or throws) end it early and are reported in
// `errors`, with what was measured until then.
RunResult run_benchmark(const BenchmarkSpec& spec, const RunOptions& options);

// Kills the node processes of a per-node run under way, and an external graph's launched
// processes, at once; async-signal-safe, for a process that must end now (a second Ctrl-C).
void kill_node_processes() noexcept;

// The per-node child side: builds one node of `spec`, reports "ready" on
// stdout once its endpoints are matched, runs until stdin closes, then prints
// a final "stats" line. It waits for its peers as long as the runner does (its
// --connect-timeout): until they are matched or stdin closes. Returns the process exit code. A
// callback stuck longer than `callback_timeout_s` is reported on a "hung" line, and the process
// ends at once. `run_token` marks its participant as one of the runner's run
// (RunResult::run_token). `keystore`: DDS Security as RunOptions::keystore; `ros_distro` as
// RunOptions::ros_distro.
int run_node_process(const BenchmarkSpec& spec, const std::string& node_name,
                     const std::string& rmw, int domain_id,
                     const SchedulingOptions& scheduling = {}, double callback_timeout_s = 30.0,
                     const std::string& run_token = {}, const std::filesystem::path& keystore = {},
                     rmw::RosDistro ros_distro = rmw::RosDistro::kJazzy);

}  // namespace robotperf::harness
