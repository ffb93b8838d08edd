#include "run_plan.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include "black_box.hpp"
#include "node_processes.hpp"

namespace robotperf::harness {
namespace {

// Bounds on what a run may be asked for (docs/design.md §3): the Playback's clock cannot pace
// messages closer than a microsecond, a week is longer than any benchmark needs, and every
// nanosecond figure derived from these must fit in 64 bits.
constexpr double kMinPeriodS = 1e-6;
constexpr double kMaxSpanS = 7 * 24 * 3600.0;
constexpr double kMaxWaitS = 24 * 3600.0;
// What each message costs the run before it starts: its record, the Monitor's reception time, and
// the schedule (bag timelines).
constexpr double kBytesPerMessage =
    sizeof(MessageRecord) + sizeof(int64_t) + sizeof(int64_t) + sizeof(bool);

// A rate in Hz that gives a period the Playback can keep: one line naming `what` otherwise.
void check_rate(double hz, const std::string& what) {
  if (!std::isfinite(hz) || !(hz > 0))
    throw std::invalid_argument(what + " must be a positive number of Hz (got " + number_text(hz) +
                                ")");
  if (1.0 / hz < kMinPeriodS)
    throw std::invalid_argument(what + " " + number_text(hz) +
                                " Hz is a period below 1 us, shorter than the Playback can pace");
  if (1.0 / hz > kMaxSpanS)
    throw std::invalid_argument(what + " " + number_text(hz) +
                                " Hz is a period longer than a week; give a higher rate");
}

void check_seconds(double s, const std::string& what, bool zero_allowed, double max_s) {
  if (!std::isfinite(s) || s < 0 || (!zero_allowed && s == 0))
    throw std::invalid_argument(what + " must be a " +
                                (zero_allowed ? "non-negative" : "positive") +
                                " number of seconds (got " + number_text(s) + ")");
  if (s > max_s)
    throw std::invalid_argument(what + " " + number_text(s) + " s is longer than the " +
                                number_text(max_s) + " s robotperf allows");
}

// The package with the overrides of `options` applied, when it asks for any.
void apply_overrides(RunPlan& plan, const RunOptions& options) {
  if (!options.nodes.any()) return;
  plan.overridden = *plan.package;
  if (options.nodes.update_rate_hz)
    override_update_rate(*plan.overridden, *options.nodes.update_rate_hz);
  if (options.nodes.backend) override_backend(*plan.overridden, *options.nodes.backend);
  if (options.nodes.device_resident) plan.result.device_resident = keep_on_device(*plan.overridden);
}

// The graph's configuration as run, and the layouts, transports and security it cannot run with.
void resolve_layout(const BenchmarkSpec& spec, const RunOptions& options, RunResult& r) {
  r.update_rate_hz = options.nodes.update_rate_hz;
  r.benchmark_id = spec.id;
  r.benchmark_name = spec.name;
  r.sample = spec.sample;
  r.category = spec.category;
  r.rmw = options.transport.rmw;
  r.processes = options.processes.layout == ProcessLayout::kSingle ? "single" : "per-node";
  r.monitor_wait = options.transport.monitor_wait == graph::WaitMode::kSpin ? "spin" : "sleep";
  r.executor_threads = spec.executor_threads;
  r.output_topic = spec.output.topic;
  for (const auto& in : spec.inputs) r.qos.push_back({"playback", in.topic, in.qos});
  r.qos.push_back({"monitor", spec.output.topic, Monitor::subscription_qos(spec.output.qos)});
  for (const auto& out : spec.more_outputs)
    r.qos.push_back({"monitor", out.topic, Monitor::subscription_qos(out.qos)});
  for (const auto& node : spec.nodes) {
    for (const auto& [port, topic] : node.topics) r.qos.push_back({node.name, topic, node.qos});
  }
  if (spec.external() && options.transport.rmw == "intra") {
    throw std::invalid_argument(
        "an external graph (launch: or attach:) is reached through DDS: "
        "use --rmw fastdds or cyclonedds, the RMW of its nodes");
  }
  if (options.processes.layout == ProcessLayout::kPerNode && options.transport.rmw == "intra") {
    throw std::invalid_argument(
        "--processes per-node needs an inter-process transport (--rmw fastdds or cyclonedds)");
  }
  if (spec.security_required && options.transport.keystore.empty()) {
    throw std::invalid_argument(spec.id +
                                " runs with DDS Security: give --security DIR (a keystore; "
                                "robotperf security init DIR makes one)");
  }
  if (!options.transport.keystore.empty()) {
    if (options.transport.rmw == "intra")
      throw std::invalid_argument("--security secures DDS: use --rmw fastdds or cyclonedds");
    if (options.transport.domain_id > rmw::kLastSecuredDomain) {
      throw std::invalid_argument("--security: domain " +
                                  std::to_string(options.transport.domain_id) +
                                  " is beyond the keystore's permissions (domains 0 to " +
                                  std::to_string(rmw::kLastSecuredDomain) + ")");
    }
    // Checked here, before anything starts: a missing file is one line.
    r.security = rmw::describe(rmw::enclave_files(options.transport.keystore));
    r.keystore = std::filesystem::absolute(options.transport.keystore);
  }
  if (options.transport.rmw != "intra") r.ros_distro = rmw::to_string(options.transport.ros_distro);
}

// The hosts the graph places nodes on, each with its launcher.
void resolve_hosts(const BenchmarkSpec& spec, const RunOptions& options, RunResult& r) {
  const auto hosts = spec.hosts();
  if (hosts.empty()) return;
  if (options.processes.layout != ProcessLayout::kPerNode) {
    throw std::invalid_argument("nodes placed on hosts (graph.yaml host: " + hosts.front() +
                                ") run in processes of their own: use --processes per-node");
  }
  if (options.tracing.mode == RunMode::kGrey) {
    // Each host has its own clock and its own LTTng session: one trace cannot hold them.
    throw std::invalid_argument(
        "grey-box runs trace one host, and this graph places nodes on " + hosts.front() +
        ": run it black-box (ping-pong timing stays on the runner's clock)");
  }
  for (const auto& host : hosts)
    r.host_launchers[host] = command_text(host_launcher(host, options.processes.host_launchers));
}

// Everything is loaded before timing starts (docs/design.md §3.4).
void load_dataset_of(RunPlan& plan, const RunOptions& options) {
  const BenchmarkSpec& spec = plan.spec();
  plan.dataset = options.load.bag
                     ? load_bag_dataset(*options.load.bag, spec.inputs, &plan.corrupt_messages)
                     : load_dataset(spec.dataset, spec.workload);
  RunResult& r = plan.result;
  r.dataset = plan.dataset.name;
  r.dataset_hash = plan.dataset.hash;
  r.dataset_frames = plan.dataset.frames;
  r.dataset_parameters = plan.dataset.parameters;
}

// The rate, and when messages are sent at it.
void resolve_timeline(const BenchmarkSpec& spec, const Dataset& dataset, const RunOptions& options,
                      RunResult& r) {
  if (options.load.bag_timeline) {
    if (dataset.frame_times_ns.empty())
      throw std::invalid_argument("--rate bag needs a recorded dataset (--dataset <bag>)");
    // The mean recorded rate: what count, duration and the message IDs go by.
    r.rate_hz = dataset.rate_hz * options.load.rate_scale;
    r.timeline = "bag";
    r.rate_scale = options.load.rate_scale;
    if (!(r.rate_hz > 0))
      throw std::invalid_argument("--rate bag: the bag's frames all have the same time");
    check_rate(r.rate_hz, "the bag's mean rate times --rate-scale,");
    return;
  }
  r.rate_hz = options.load.rate_hz.value_or(spec.rate_hz);
  check_rate(r.rate_hz, options.load.rate_hz ? "--rate" : "the benchmark's rate_hz");
  if (options.load.scenario != Scenario::kOpenLoop) {
    // The rate still spaces the message IDs (and sizes the run by --duration); nothing is sent
    // at it. The timeline names the scenario, so results of different scenarios never pool.
    r.timeline = scenario_name(options.load.scenario);
    return;
  }
  if (options.load.arrival.kind == ArrivalPattern::Kind::kPoisson) {
    r.timeline = "poisson";
    r.arrival_seed = options.load.arrival.seed;
  } else if (options.load.arrival.kind == ArrivalPattern::Kind::kBurst) {
    r.timeline = "burst";
    r.burst = options.load.arrival.burst;
  }
}

// The most bytes one frame of `dataset` takes over `spec`'s inputs together: what the Playback
// copies for each message.
double largest_frame_bytes(const BenchmarkSpec& spec, const Dataset& dataset) {
  double bytes = 0;
  for (const auto& input : spec.inputs) {
    const DatasetStream& stream = dataset.stream(input.stream);
    std::size_t largest = 0;
    for (const auto& m : stream.messages)
      largest = std::max(largest, stream.type->serialized_size(m.get()));
    bytes += static_cast<double>(largest);
  }
  return bytes;
}

// The run as derived (rate from a bag, count from a duration): its schedule must fit in time,
// and in memory its records and the copies of a burst's messages, all prepared before their
// deadline (`frame_bytes` each).
void check_run_size(const RunResult& r, double frame_bytes) {
  const double span_s = static_cast<double>(r.count) / r.rate_hz;
  if (span_s > kMaxSpanS) {
    throw std::invalid_argument(std::to_string(r.count) + " messages at " + number_text(r.rate_hz) +
                                " Hz take " + number_text(span_s) +
                                " s, longer than a week; give a smaller --count or --duration");
  }
  const double bytes = static_cast<double>(r.count) * kBytesPerMessage;
  const double memory =
      static_cast<double>(sysconf(_SC_PHYS_PAGES)) * static_cast<double>(sysconf(_SC_PAGE_SIZE));
  if (bytes > memory / 4) {
    throw std::invalid_argument(
        std::to_string(r.count) + " messages need " + number_text(bytes / (1 << 30)) +
        " GiB for their per-message records, more than a quarter of this machine's " +
        number_text(memory / (1 << 30)) + " GiB; give a smaller --count or --duration");
  }
  const std::size_t at_once = r.timeline == "burst" ? std::min(r.burst, r.count) : 1;
  if (const double burst_bytes = static_cast<double>(at_once) * frame_bytes;
      burst_bytes > memory / 4) {
    throw std::invalid_argument(
        "--arrival burst:" + std::to_string(r.burst) + " prepares " + std::to_string(at_once) +
        " messages of up to " + number_text(frame_bytes / (1 << 20)) + " MiB at once, " +
        number_text(burst_bytes / (1 << 30)) + " GiB, more than a quarter of this machine's " +
        number_text(memory / (1 << 30)) + " GiB; give a smaller burst");
  }
}

// How many messages, how many of them warm up, and how long the drain waits.
void resolve_counts(const BenchmarkSpec& spec, const Dataset& dataset, const RunOptions& options,
                    RunResult& r) {
  if (options.load.count) {
    r.count = *options.load.count;
  } else if (options.load.duration_s) {
    const double count = std::round(*options.load.duration_s * r.rate_hz);
    if (count > kMaxSpanS / kMinPeriodS)
      throw std::invalid_argument("--duration " + number_text(*options.load.duration_s) + " s at " +
                                  number_text(r.rate_hz) + " Hz is too many messages");
    r.count = static_cast<std::size_t>(count);
  } else {
    r.count = spec.count ? spec.count : dataset.frames;
  }
  r.warmup = options.load.warmup.value_or(spec.warmup);
  if (r.warmup >= r.count) {
    // With --duration the count is derived: say from what, since a slow benchmark (c1 sends a
    // goal every few seconds) gives few messages in a short duration.
    std::string derived;
    if (!options.load.count && options.load.duration_s) {
      std::ostringstream text;
      text << " = " << *options.load.duration_s << " s x " << r.rate_hz
           << " Hz; give a longer --duration or a --count";
      derived = text.str();
    }
    throw std::invalid_argument("warm-up (" + std::to_string(r.warmup) +
                                ") must be smaller than the message count (" +
                                std::to_string(r.count) + derived + ")");
  }
  check_run_size(r, r.timeline == "burst" ? largest_frame_bytes(spec, dataset) : 0);
  r.drain_s = options.load.drain_s.value_or(spec.drain_s);
  check_seconds(r.drain_s, options.load.drain_s ? "--drain" : "the benchmark's drain_s", true,
                kMaxWaitS);
}

}  // namespace

std::string number_text(double value) {
  std::ostringstream text;
  text.precision(6);
  text << value;
  return text.str();
}

void LoadOptions::check() const {
  if (rate_hz) check_rate(*rate_hz, "--rate");
  if (duration_s) check_seconds(*duration_s, "--duration", false, kMaxSpanS);
  if (drain_s) check_seconds(*drain_s, "--drain", true, kMaxWaitS);
  if (bag_timeline && (!std::isfinite(rate_scale) || !(rate_scale > 0)))
    throw std::invalid_argument("--rate-scale must be a positive number");
  if (count && *count == 0) throw std::invalid_argument("--count must be at least 1");
  if (bag_timeline && arrival.kind != ArrivalPattern::Kind::kFixed)
    throw std::invalid_argument(
        "--arrival " + arrival.name() +
        " replaces the bag's timeline: give one of --rate bag and --arrival");
  if (scenario != Scenario::kOpenLoop) {
    const std::string which = "--scenario " + scenario_name(scenario);
    if (bag_timeline)
      throw std::invalid_argument(which + " sends at no timeline: give it without --rate bag");
    if (arrival.kind != ArrivalPattern::Kind::kFixed)
      throw std::invalid_argument(which + " sends at no arrival times: give it without --arrival");
  }
}

Scenario parse_scenario(const std::string& text) {
  if (text == "open-loop") return Scenario::kOpenLoop;
  if (text == "single-stream") return Scenario::kSingleStream;
  if (text == "offline") return Scenario::kOffline;
  throw std::invalid_argument("--scenario " + text +
                              ": expected open-loop, single-stream or offline");
}

std::string scenario_name(Scenario scenario) {
  switch (scenario) {
    case Scenario::kSingleStream:
      return "single-stream";
    case Scenario::kOffline:
      return "offline";
    case Scenario::kOpenLoop:
      break;
  }
  return "open-loop";
}

void ProcessOptions::check() const {
  check_seconds(connect_timeout_s, "--connect-timeout", false, kMaxWaitS);
  check_seconds(callback_timeout_s, "--callback-timeout", false, kMaxWaitS);
}

void RunOptions::check() const {
  load.check();
  processes.check();
  if (tracing.mode == RunMode::kGrey && load.scenario != Scenario::kOpenLoop) {
    // The trace's analysis rates sends by their deadlines, which a closed loop does not have.
    throw std::invalid_argument("--scenario " + scenario_name(load.scenario) +
                                " is measured black-box: give it without --mode grey");
  }
  if (nodes.device_resident &&
      (transport.rmw != "intra" || processes.layout != ProcessLayout::kSingle)) {
    throw std::invalid_argument(
        "--device-resident hands images from node to node inside one process: run it with --rmw "
        "intra (and no --processes per-node)");
  }
  if (transport.monitor_wait == graph::WaitMode::kSpin) {
    // A single-process run's --cpus hold the Monitor too; per node, it runs where this process
    // may. On one CPU, the spinning Monitor and everything else would take turns by time slice.
    const std::size_t cpus =
        !processes.scheduling.cpus.empty() && processes.layout == ProcessLayout::kSingle
            ? processes.scheduling.cpus.size()
            : allowed_cpus().size();
    if (cpus < 2)
      throw std::invalid_argument(
          "--monitor-wait spin keeps a CPU busy for the whole run, and this run's Monitor may "
          "use only one: give it two or more (--cpus), or let it sleep");
  }
}

RunPlan plan_run(const BenchmarkSpec& package_spec, const RunOptions& options) {
  options.check();
  RunPlan plan;
  plan.package = &package_spec;
  apply_overrides(plan, options);
  const BenchmarkSpec& spec = plan.spec();
  RunResult& r = plan.result;
  resolve_layout(spec, options, r);
  resolve_hosts(spec, options, r);
  load_dataset_of(plan, options);
  resolve_timeline(spec, plan.dataset, options, r);
  resolve_counts(spec, plan.dataset, options, r);
  r.domain_id = options.transport.domain_id;
  r.scheduling = options.processes.scheduling;
  plan.period_ns = static_cast<int64_t>(std::llround(1e9 / r.rate_hz));
  // A bag brings no ground truth to check the outputs against.
  plan.evaluate_outputs = spec.functional && !options.load.bag;
  return plan;
}

}  // namespace robotperf::harness
