#include "robotperf/harness/run.hpp"

#include <signal.h>
#include <string.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <iostream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <thread>

#include "black_box.hpp"
#include "control_loop.hpp"
#include "grey_box.hpp"
#include "launched_processes.hpp"
#include "measurement.hpp"
#include "node_processes.hpp"
#include "robotperf/graph/executor.hpp"
#include "robotperf/metrics/delivery_validity.hpp"
#include "robotperf/msgs/known_types.hpp"
#include "robotperf/plugin/control_loop.hpp"
#include "robotperf/plugin/registry.hpp"

namespace robotperf::harness {
namespace {

// How often the run looks for an interrupt or a stuck callback while it waits.
constexpr int64_t kWatchPeriodNs = 100'000'000;
// How long the graph's executor gets to stop after the run before its threads are given up.
constexpr int64_t kStopGraceNs = 2'000'000'000;
// The exit status of a node process whose watchdog found a callback stuck.
constexpr int kNodeHungExit = 5;

std::string number_text(double s) {
  std::ostringstream text;
  text.precision(6);
  text << s;
  return text.str();
}

struct Wiring {
  std::set<std::string> published;   // topics someone in the whole graph publishes
  std::set<std::string> subscribed;  // topics someone in the whole graph subscribes
};

Wiring wiring_of(const BenchmarkSpec& spec) {
  Wiring w;
  for (const auto& in : spec.inputs) w.published.insert(in.topic);
  w.subscribed.insert(spec.output.topic);
  if (spec.external()) {
    // An external graph's endpoints are not declared: it reads every input and writes the output.
    for (const auto& in : spec.inputs) w.subscribed.insert(in.topic);
    w.published.insert(spec.output.topic);
  }
  for (const auto& node : spec.nodes) {
    const plugin::KernelInfo& info = kernel_of(node).info;
    for (const auto& [port, topic] : node.topics) {
      const bool is_input = std::ranges::count(info.inputs, port, &plugin::PortInfo::name) > 0;
      (is_input ? w.subscribed : w.published).insert(topic);
    }
  }
  return w;
}

// The endpoints of `nodes` still waiting for a peer they will have once the whole graph is up, one
// line each: who, the topic and its type, and what `about_topic` knows of others on it.
std::vector<std::string> unconnected_endpoints(
    const std::vector<std::shared_ptr<graph::Node>>& nodes, const Wiring& w,
    const std::function<std::string(const graph::EndpointStatus&)>& about_topic) {
  std::vector<std::string> out;
  for (const auto& node : nodes) {
    for (const auto& e : node->endpoints()) {
      const bool expects_peer =
          e.is_publisher ? w.subscribed.contains(e.topic) : w.published.contains(e.topic);
      if (expects_peer && e.matched == 0) {
        std::string line = node->name() + (e.is_publisher ? " publishing " : " subscribing ") +
                           e.topic + " [" + e.type + "] has no peer";
        if (about_topic) line += ": " + about_topic(e);
        out.push_back(std::move(line));
      }
    }
  }
  return out;
}

// The name of `peer`'s node that owns the endpoint `gid`, else the participant's name.
std::string owner_of(const rmw::PeerParticipant& peer, const rmw::Gid& gid) {
  for (const auto& node : peer.nodes) {
    if (std::ranges::find(node.readers, gid) != node.readers.end() ||
        std::ranges::find(node.writers, gid) != node.writers.end()) {
      return "node " + node.path();
    }
  }
  return "participant '" + (peer.name.empty() ? std::string("unnamed") : peer.name) + "'";
}

// Why an endpoint of another participant does not match ours (`our_qos`) on `ours.topic`: its
// type, or the QoS request a subscription makes of a publisher (DDS's requested/offered rules);
// empty when neither.
std::string mismatch(const rmw::PeerEndpoint& theirs, const graph::EndpointStatus& ours,
                     const rmw::QoS& our_qos) {
  const std::string their_type = msgs::ros_type_name(theirs.dds_type);
  if (their_type != ours.type) return "its type is " + their_type;
  const rmw::QoS& writer = ours.is_publisher ? our_qos : theirs.qos;
  const rmw::QoS& reader = ours.is_publisher ? theirs.qos : our_qos;
  return rmw::qos_incompatibility(writer, reader);
}

// What the other participants of the domain have on `ours.topic`: each opposite endpoint with
// its type, its QoS and why it does not match ours.
std::string others_on_topic(const std::vector<rmw::PeerParticipant>& peers,
                            const graph::EndpointStatus& ours, const rmw::QoS& our_qos,
                            int domain_id) {
  std::string seen;
  for (const auto& peer : peers) {
    for (const auto& e : peer.endpoints) {
      if (e.topic != ours.topic || e.writer == ours.is_publisher) continue;
      const std::string why = mismatch(e, ours, our_qos);
      seen += std::string(seen.empty() ? "" : "; ") + owner_of(peer, e.gid) +
              (e.writer ? " publishes it" : " subscribes it") + " as " +
              msgs::ros_type_name(e.dds_type) + " (" + rmw::to_string(e.qos.reliability) + ", " +
              rmw::to_string(e.qos.durability) +
              "): " + (why.empty() ? "compatible, not matched yet" : why);
    }
  }
  if (seen.empty()) {
    for (const auto& peer : peers) {
      if (peer.topics.contains(ours.topic)) {
        seen = "participant(s) on the domain have it, but no " +
               std::string(ours.is_publisher ? "subscription" : "publisher");
      }
    }
  }
  if (seen.empty()) {
    return "no other participant on domain " + std::to_string(domain_id) +
           " has an endpoint on it (is the graph running, with this domain and RMW?)";
  }
  return seen + " (ours: " + rmw::to_string(our_qos) + ")";
}

// Polls matched counts: discovery offers no single event for "graph complete".
// Returns false as soon as `abandon` returns true; throws GraphNotConnected at the deadline.
bool wait_connected(
    const std::vector<std::shared_ptr<graph::Node>>& nodes, const Wiring& w, int64_t deadline_ns,
    const std::function<bool()>& abandon = [] { return false; },
    const std::function<std::string(const graph::EndpointStatus&)>& about_topic = {}) {
  while (true) {
    if (unconnected_endpoints(nodes, w, {}).empty()) return true;
    if (abandon()) return false;
    if (rmw::steady_now_ns() > deadline_ns) {
      std::string lines;
      for (const auto& line : unconnected_endpoints(nodes, w, about_topic)) lines += "\n  " + line;
      throw GraphNotConnected("graph did not connect in time (--connect-timeout):" + lines);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

// Bounds on what a run may be asked for (DESIGN.md §3): the Playback's clock cannot pace
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

// The values given to the run, before anything is loaded.
void check_run_options(const RunOptions& o) {
  if (o.rate_hz) check_rate(*o.rate_hz, "--rate");
  if (o.duration_s) check_seconds(*o.duration_s, "--duration", false, kMaxSpanS);
  if (o.drain_s) check_seconds(*o.drain_s, "--drain", true, kMaxWaitS);
  check_seconds(o.connect_timeout_s, "--connect-timeout", false, kMaxWaitS);
  check_seconds(o.callback_timeout_s, "--callback-timeout", false, kMaxWaitS);
  if (o.bag_timeline && (!std::isfinite(o.rate_scale) || !(o.rate_scale > 0)))
    throw std::invalid_argument("--rate-scale must be a positive number");
  if (o.count && *o.count == 0) throw std::invalid_argument("--count must be at least 1");
  if (o.bag_timeline && o.arrival.kind != ArrivalPattern::Kind::kFixed)
    throw std::invalid_argument(
        "--arrival " + o.arrival.name() +
        " replaces the bag's timeline: give one of --rate bag and --arrival");
  if (o.device_resident && (o.rmw != "intra" || o.processes != ProcessLayout::kSingle)) {
    throw std::invalid_argument(
        "--device-resident hands images from node to node inside one process: run it with --rmw "
        "intra (and no --processes per-node)");
  }
  if (o.monitor_wait == graph::WaitMode::kSpin) {
    // A single-process run's --cpus hold the Monitor too; per node, it runs where this process
    // may. On one CPU, the spinning Monitor and everything else would take turns by time slice.
    const std::size_t cpus = !o.scheduling.cpus.empty() && o.processes == ProcessLayout::kSingle
                                 ? o.scheduling.cpus.size()
                                 : allowed_cpus().size();
    if (cpus < 2)
      throw std::invalid_argument(
          "--monitor-wait spin keeps a CPU busy for the whole run, and this run's Monitor may "
          "use only one: give it two or more (--cpus), or let it sleep");
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

std::string what_of(const std::exception_ptr& e) {
  try {
    std::rethrow_exception(e);
  } catch (const std::exception& ex) {
    return ex.what();
  } catch (...) {
    return "unknown error";
  }
}

std::unique_ptr<rmw::Transport> transport_for(const RunOptions& options,
                                              const std::string& user_data) {
  rmw::TransportOptions t;
  t.domain_id = options.domain_id;
  t.user_data = user_data;
  if (!options.keystore.empty()) t.security = rmw::enclave_files(options.keystore);
  t.ros_distro = options.ros_distro;
  return rmw::make_transport(options.rmw, t);
}

// The participants of `more` not yet in `seen`, added to it.
void add_peers(std::vector<rmw::PeerParticipant>& seen, std::vector<rmw::PeerParticipant> more) {
  for (auto& peer : more) {
    auto it = std::ranges::find(seen, peer.id, &rmw::PeerParticipant::id);
    if (it == seen.end()) {
      seen.push_back(std::move(peer));
    } else {
      it->topics.insert(peer.topics.begin(), peer.topics.end());
      // Its nodes as it announced them last.
      if (!peer.nodes.empty()) it->nodes = std::move(peer.nodes);
    }
  }
}

void summarise(RunResult& r, const BenchmarkSpec& spec, const Monitor::Tally& tally) {
  std::vector<double> from_scheduled, from_sent, lateness;
  std::vector<metrics::TimedEvent> sends, receptions;
  for (auto& rec : r.records) {
    rec.received_ns = tally.received_ns[rec.id];
    rec.warmup = rec.id < r.warmup;
    lateness.push_back(static_cast<double>(rec.sent_ns - rec.scheduled_ns));
    if (rec.warmup) continue;
    ++r.measured;
    sends.push_back({rec.scheduled_ns, rec.sent_ns});
    if (rec.received_ns < 0) continue;
    ++r.matched;
    from_scheduled.push_back(static_cast<double>(rec.received_ns - rec.scheduled_ns));
    from_sent.push_back(static_cast<double>(rec.received_ns - rec.sent_ns));
    receptions.push_back({rec.scheduled_ns, rec.received_ns});
  }
  r.sent = r.records.size();
  r.lost = r.measured - r.matched;
  r.loss_percent =
      r.measured ? 100.0 * static_cast<double>(r.lost) / static_cast<double>(r.measured) : 0.0;
  r.duplicates = tally.duplicates;
  r.unknown = tally.unknown;
  r.latency_from_scheduled = metrics::compute_stats(from_scheduled);
  r.latency_from_sent = metrics::compute_stats(from_sent);
  r.send_lateness = metrics::compute_stats(lateness);

  const metrics::DeliveryRates rates = metrics::delivery_rates(sends, receptions);
  r.throughput_hz = rates.output_hz;
  r.offered_rate_hz = rates.offered_hz;
  r.window_s = rates.window_s;

  auto invalid = [&](std::string why) { r.invalid_reasons.push_back(std::move(why)); };
  for (const auto& e : r.errors) invalid("run ended early: " + e);
  for (auto& why :
       metrics::delivery_invalid_reasons({r.matched, r.duplicates, r.unknown, r.loss_percent},
                                         spec.min_samples, spec.max_loss_percent))
    invalid(std::move(why));
  r.valid = r.invalid_reasons.empty();
}

}  // namespace

std::vector<double> scheduled_latencies_ms(const RunResult& r) {
  std::vector<double> out;
  out.reserve(r.records.size());
  for (const auto& rec : r.records) {
    if (!rec.warmup && rec.received_ns >= 0)
      out.push_back(static_cast<double>(rec.received_ns - rec.scheduled_ns) / 1e6);
  }
  return out;
}

namespace {

// The device a built kernel node computes on, when its backend is not the host CPU.
std::optional<plugin::DeviceInfo> device_of(const graph::Node& node, const NodeSpec& spec) {
  const auto* d = dynamic_cast<const plugin::DeviceNode*>(&node);
  if (d == nullptr || spec.backend == "cpu") return std::nullopt;
  return d->device();
}

}  // namespace

nlohmann::json device_to_json(const plugin::DeviceInfo& device) {
  return {{"name", device.name},
          {"vendor", device.vendor},
          {"driver", device.driver},
          {"runtime", device.runtime},
          {"memory_bytes", device.memory_bytes}};
}

plugin::DeviceInfo device_from_json(const nlohmann::json& j) {
  return {j.value("name", ""), j.value("vendor", ""), j.value("driver", ""), j.value("runtime", ""),
          j.value("memory_bytes", uint64_t{0})};
}

RunResult run_benchmark(const BenchmarkSpec& package_spec, const RunOptions& options) {
  check_run_options(options);
  std::optional<BenchmarkSpec> overridden;
  std::vector<ResidentTopic> resident;
  if (options.update_rate_hz || options.backend || options.device_resident) {
    overridden = package_spec;
    if (options.update_rate_hz) override_update_rate(*overridden, *options.update_rate_hz);
    if (options.backend) override_backend(*overridden, *options.backend);
    if (options.device_resident) resident = keep_on_device(*overridden);
  }
  const BenchmarkSpec& spec = overridden ? *overridden : package_spec;
  RunResult r;
  r.device_resident = std::move(resident);
  r.update_rate_hz = options.update_rate_hz;
  r.benchmark_id = spec.id;
  r.benchmark_name = spec.name;
  r.category = spec.category;
  r.rmw = options.rmw;
  r.processes = options.processes == ProcessLayout::kSingle ? "single" : "per-node";
  r.monitor_wait = options.monitor_wait == graph::WaitMode::kSpin ? "spin" : "sleep";
  r.executor_threads = spec.executor_threads;
  r.output_topic = spec.output.topic;
  for (const auto& in : spec.inputs) r.qos.push_back({"playback", in.topic, in.qos});
  r.qos.push_back({"monitor", spec.output.topic, Monitor::subscription_qos(spec.output.qos)});
  for (const auto& node : spec.nodes) {
    for (const auto& [port, topic] : node.topics) r.qos.push_back({node.name, topic, node.qos});
  }
  if (spec.external() && options.rmw == "intra") {
    throw std::invalid_argument(
        "an external graph (launch: or attach:) is reached through DDS: "
        "use --rmw fastdds or cyclonedds, the RMW of its nodes");
  }
  if (options.processes == ProcessLayout::kPerNode && options.rmw == "intra") {
    throw std::invalid_argument(
        "--processes per-node needs an inter-process transport (--rmw fastdds or cyclonedds)");
  }
  if (spec.security_required && options.keystore.empty()) {
    throw std::invalid_argument(spec.id +
                                " runs with DDS Security: give --security DIR (a keystore; "
                                "robotperf security init DIR makes one)");
  }
  if (!options.keystore.empty()) {
    if (options.rmw == "intra")
      throw std::invalid_argument("--security secures DDS: use --rmw fastdds or cyclonedds");
    if (options.domain_id > rmw::kLastSecuredDomain) {
      throw std::invalid_argument("--security: domain " + std::to_string(options.domain_id) +
                                  " is beyond the keystore's permissions (domains 0 to " +
                                  std::to_string(rmw::kLastSecuredDomain) + ")");
    }
    // Checked here, before anything starts: a missing file is one line.
    r.security = rmw::describe(rmw::enclave_files(options.keystore));
    r.keystore = std::filesystem::absolute(options.keystore);
  }
  if (options.rmw != "intra") r.ros_distro = rmw::to_string(options.ros_distro);
  if (const auto hosts = spec.hosts(); !hosts.empty()) {
    if (options.processes != ProcessLayout::kPerNode) {
      throw std::invalid_argument("nodes placed on hosts (graph.yaml host: " + hosts.front() +
                                  ") run in processes of their own: use --processes per-node");
    }
    if (options.mode == RunMode::kGrey) {
      // Each host has its own clock and its own LTTng session: one trace cannot hold them.
      throw std::invalid_argument(
          "grey-box runs trace one host, and this graph places nodes on " + hosts.front() +
          ": run it black-box (ping-pong timing stays on the runner's clock)");
    }
    for (const auto& host : hosts)
      r.host_launchers[host] = command_text(host_launcher(host, options.host_launchers));
  }

  // Everything is loaded before timing starts (DESIGN.md §3.4).
  std::vector<std::string> corrupt_messages;
  const Dataset dataset = options.bag
                              ? load_bag_dataset(*options.bag, spec.inputs, &corrupt_messages)
                              : load_dataset(spec.dataset, spec.workload);
  r.dataset = dataset.name;
  r.dataset_hash = dataset.hash;
  r.dataset_frames = dataset.frames;
  r.dataset_parameters = dataset.parameters;

  if (options.bag_timeline) {
    if (dataset.frame_times_ns.empty())
      throw std::invalid_argument("--rate bag needs a recorded dataset (--dataset <bag>)");
    // The mean recorded rate: what count, duration and the message IDs go by.
    r.rate_hz = dataset.rate_hz * options.rate_scale;
    r.timeline = "bag";
    r.rate_scale = options.rate_scale;
    if (!(r.rate_hz > 0))
      throw std::invalid_argument("--rate bag: the bag's frames all have the same time");
    check_rate(r.rate_hz, "the bag's mean rate times --rate-scale,");
  } else {
    r.rate_hz = options.rate_hz.value_or(spec.rate_hz);
    check_rate(r.rate_hz, options.rate_hz ? "--rate" : "the benchmark's rate_hz");
    if (options.arrival.kind == ArrivalPattern::Kind::kPoisson) {
      r.timeline = "poisson";
      r.arrival_seed = options.arrival.seed;
    } else if (options.arrival.kind == ArrivalPattern::Kind::kBurst) {
      r.timeline = "burst";
      r.burst = options.arrival.burst;
    }
  }
  if (options.count) {
    r.count = *options.count;
  } else if (options.duration_s) {
    const double count = std::round(*options.duration_s * r.rate_hz);
    if (count > kMaxSpanS / kMinPeriodS)
      throw std::invalid_argument("--duration " + number_text(*options.duration_s) + " s at " +
                                  number_text(r.rate_hz) + " Hz is too many messages");
    r.count = static_cast<std::size_t>(count);
  } else {
    r.count = spec.count ? spec.count : dataset.frames;
  }
  r.warmup = options.warmup.value_or(spec.warmup);
  if (r.warmup >= r.count) {
    // With --duration the count is derived: say from what, since a slow benchmark (c1 sends a
    // goal every few seconds) gives few messages in a short duration.
    std::string derived;
    if (!options.count && options.duration_s) {
      std::ostringstream text;
      text << " = " << *options.duration_s << " s x " << r.rate_hz
           << " Hz; give a longer --duration or a --count";
      derived = text.str();
    }
    throw std::invalid_argument("warm-up (" + std::to_string(r.warmup) +
                                ") must be smaller than the message count (" +
                                std::to_string(r.count) + derived + ")");
  }
  check_run_size(r, r.timeline == "burst" ? largest_frame_bytes(spec, dataset) : 0);
  r.drain_s = options.drain_s.value_or(spec.drain_s);
  check_seconds(r.drain_s, options.drain_s ? "--drain" : "the benchmark's drain_s", true,
                kMaxWaitS);
  r.domain_id = options.domain_id;
  r.scheduling = options.scheduling;

  // In one process the scheduling options cover every thread created from here on.
  std::optional<ScopedScheduling> scheduling;
  if (options.processes == ProcessLayout::kSingle) scheduling.emplace(options.scheduling);

  std::optional<GreyBoxRecording> grey;
  if (options.mode == RunMode::kGrey) grey.emplace(spec, options, r);

  // On the heap: a callback that never returns keeps using the context and the graph's executor,
  // which are then left alive (see abandon below).
  const auto period_ns = static_cast<int64_t>(std::llround(1e9 / r.rate_hz));
  r.started_unix_ns = rmw::wall_now_ns();
  const MessageIds ids = make_message_ids(period_ns, r.count);
  r.id_base_ns = ids.base_ns;
  r.run_token = make_run_token();
  const std::string user_data = run_user_data(r.run_token, &ids);
  auto context = std::make_unique<graph::Context>(transport_for(options, user_data));
  RunIsolation isolation(context->transport(), r.run_token);

  // Bag payloads go on the wire as recorded. They need a participant of their
  // own: a DDS participant knows one TopicDataType per type name, and the
  // graph's typed endpoints need theirs.
  const bool publish_serialized = options.bag.has_value() && options.rmw != "intra";
  std::unique_ptr<graph::Context> playback_context;
  if (publish_serialized)
    playback_context = std::make_unique<graph::Context>(transport_for(options, user_data));
  Playback playback(
      publish_serialized ? *playback_context : *context, spec, dataset, ids, publish_serialized,
      options.bag_timeline ? timeline_schedule(dataset.frame_times_ns, options.rate_scale, r.count)
      : r.timeline == "fixed" ? std::vector<int64_t>{}
                              : arrival_schedule(options.arrival, period_ns, r.count));
  Monitor monitor(*context, spec.output, ids, r.warmup, &isolation);
  std::vector<uint64_t> functional_ids;
  // A bag brings no ground truth to check the outputs against.
  const bool evaluate_outputs = spec.functional && !options.bag;
  // An evaluator that checks each output as it arrives (a state output's later receptions, or a
  // truth observed during the run, need the outputs kept to the end instead).
  std::unique_ptr<plugin::FunctionalEvaluator> on_arrival;
  if (evaluate_outputs) {
    // A missing truth stream fails before timing.
    auto evaluator = make_evaluator(*spec.functional, dataset);
    functional_ids = functional_sample_ids(r.count, r.warmup, spec.functional->sample);
    monitor.keep_outputs(functional_ids);
    const auto& info = plugin::registry().find_evaluator(spec.functional->evaluator)->info;
    if (info.on_arrival && !spec.output.state && spec.functional->observed_truth_topic.empty()) {
      on_arrival = std::move(evaluator);
      monitor.evaluate_on_arrival(*on_arrival, truth_frames(*spec.functional, dataset));
    }
    if (const auto& topic = spec.functional->observed_truth_topic; !topic.empty()) {
      const std::string& type = info.observed_truth_type;
      const msgs::TypeSupport* ts = nullptr;
      msgs::with_message_type(type, [&]<class T>() { ts = &msgs::type_support<T>(); });
      if (ts == nullptr || !ts->stamped())
        throw BenchmarkError("observed truth type " + type + " cannot carry message IDs");
      monitor.keep_observed_truth(topic, *ts);
    }
  }
  // Answers of nodes on another backend are compared with the cpu's afterwards: keep a sample
  // where the functional check keeps none.
  const bool on_device = uses_other_backend(spec);
  if (on_device && functional_ids.empty() && has_comparison(spec.output.type)) {
    functional_ids = functional_sample_ids(r.count, r.warmup, 16);
    monitor.keep_outputs(functional_ids);
  }
  graph::Executor monitor_executor(1, options.monitor_wait);
  monitor_executor.add_node(monitor.node());

  auto graph_executor = std::make_unique<graph::Executor>(spec.executor_threads);
  std::vector<std::shared_ptr<graph::Node>> local_nodes{playback.node(), monitor.node()};
  std::unique_ptr<NodeProcesses> children;
  std::vector<std::shared_ptr<graph::Node>> kernel_nodes;
  if (options.processes == ProcessLayout::kSingle) {
    for (const auto& n : spec.nodes) {
      auto node = make_kernel_node(n, *context, spec.workload);
      graph_executor->add_node(node);
      local_nodes.push_back(node);
      kernel_nodes.push_back(node);
      r.nodes.push_back(
          {n.name, n.kernel, 0, "ok", -1, -1, {}, "", "", true, n.backend, device_of(*node, n)});
    }
  } else {
    std::vector<std::string> node_arguments = options.scheduling.node_arguments();
    if (options.update_rate_hz) {
      // The children load the package themselves: they get the override to apply.
      std::ostringstream hz;
      hz.precision(17);
      hz << *options.update_rate_hz;
      node_arguments.insert(node_arguments.end(), {"--update-rate", hz.str()});
    }
    if (options.backend)
      node_arguments.insert(node_arguments.end(), {"--backend", *options.backend});
    node_arguments.insert(node_arguments.end(),
                          {"--callback-timeout", number_text(options.callback_timeout_s),
                           "--run-token", r.run_token});
    if (!r.keystore.empty())
      node_arguments.insert(node_arguments.end(), {"--security", r.keystore.string()});
    node_arguments.insert(node_arguments.end(),
                          {"--ros-distro", rmw::to_string(options.ros_distro)});
    children =
        std::make_unique<NodeProcesses>(spec, options.node_command, options.rmw, options.domain_id,
                                        node_arguments, options.host_launchers);
  }

  std::unique_ptr<LaunchedProcesses> launched;
  if (!spec.launch.empty()) {
    launched = std::make_unique<LaunchedProcesses>(
        spec, options.rmw, options.domain_id, options.log_dir, spec.id + "-" + r.run_token + ".");
  }

  const int64_t connect_deadline =
      rmw::steady_now_ns() + static_cast<int64_t>(options.connect_timeout_s * 1e9);
  monitor_executor.start();
  graph_executor->start();
  auto interrupted = [&] {
    // A launched process that ends before the graph is up ends the wait with what it said.
    if (launched) {
      if (std::string f = launched->failure(); !f.empty())
        throw std::runtime_error(f + " (before the graph was connected)");
    }
    return options.interrupted && options.interrupted->load() != 0;
  };
  // For a graph that does not connect: who else is on the topic, as what, and why it does not
  // match the QoS we offer or ask.
  auto about_topic = [&](const graph::EndpointStatus& ours) {
    rmw::QoS qos;
    for (const auto& e : r.qos) {
      if (e.topic == ours.topic) qos = e.qos;
    }
    return others_on_topic(isolation.others(), ours, qos, r.domain_id);
  };
  if ((children && !children->wait_ready(connect_deadline, interrupted)) ||
      !wait_connected(local_nodes, wiring_of(spec), connect_deadline, interrupted, about_topic)) {
    throw RunInterrupted(std::string("interrupted by SIG") +
                         sigabbrev_np(options.interrupted->load()) +
                         " before the run started: nothing was measured");
  }
  // Once ready, each child has said where it runs: its resources are sampled when that is here.
  std::vector<metrics::ResourceMonitor::Process> graph_processes;
  if (children) {
    for (const auto& [pid, name] : children->processes()) graph_processes.push_back({pid, name});
    // The Playback and Monitor are part of what is measured, not interference.
    graph_processes.push_back({getpid(), "robotperf (Playback, Monitor)"});
  } else {
    graph_processes.push_back({getpid(), spec.nodes.empty()
                                             ? "robotperf (Playback, Monitor)"
                                             : "robotperf (graph, Playback, Monitor)"});
  }
  // A launched command's own children (`ros2 run`'s node, a wrapper script's program) are its.
  std::vector<pid_t> with_descendants;
  if (launched) {
    for (const auto& [pid, name] : launched->processes()) {
      graph_processes.push_back({pid, name});
      with_descendants.push_back(pid);
    }
  }
  WindowMeasurement measurement(options, graph_processes, with_descendants);
  std::optional<NetworkLink::Counters> link_before;
  if (options.network_link) link_before = options.network_link->counters();

  r.warnings = check_run_rules_for(r, measurement.probe_other_load());
  // Discovery has run at least as long as the graph took to connect.
  add_peers(r.domain_peers, isolation.others());
  // An external graph's own participants are on the domain by design: only the others warn (and
  // refuse a --strict run).
  std::vector<rmw::PeerParticipant> others = r.domain_peers;
  if (spec.external()) {
    Wiring w = wiring_of(spec);
    w.published.merge(w.subscribed);
    others = outside_graph(others, std::move(w.published));
  }
  if (!others.empty()) {
    const std::size_t graphs_own = r.domain_peers.size() - others.size();
    r.warnings.push_back(
        {"other_participants",
         std::to_string(others.size()) + " other DDS participant(s) on domain " +
             std::to_string(r.domain_id) +
             (graphs_own > 0 ? " besides the external graph's " + std::to_string(graphs_own)
                             : std::string()) +
             ": " + describe_peers(others, 3) +
             "; their messages are told apart, but they share the machine and the network "
             "(--domain auto picks an empty domain)"});
  }
  if (options.strict && !r.warnings.empty()) {
    std::string broken;
    for (const auto& w : r.warnings) broken += "\n  " + w.rule + ": " + w.message;
    throw RunRefused("--strict: not running, run rules broken:" + broken);
  }
  for (const auto& line : corrupt_messages) r.warnings.push_back({"corrupt_messages", line});
  if (spec.functional && !evaluate_outputs) {
    r.warnings.push_back({"functional", "outputs not checked for accuracy (" +
                                            spec.functional->evaluator +
                                            "): a bag has no ground truth to check them against"});
  }

  const auto callback_limit_ns = static_cast<int64_t>(options.callback_timeout_s * 1e9);
  // Why the run must end now: an interrupt, a callback stuck past the timeout, or a failure.
  std::string stop_now;
  auto must_stop = [&]() -> const std::string& {
    if (stop_now.empty()) {
      if (options.interrupted && options.interrupted->load() != 0) {
        r.interrupted = true;
        stop_now = std::string("interrupted by SIG") + sigabbrev_np(options.interrupted->load());
      } else if (auto stuck =
                     graph_executor->running_longer_than(callback_limit_ns, rmw::steady_now_ns())) {
        stop_now = "node '" + stuck->node + "' hung: its callback has run for " +
                   number_text(static_cast<double>(stuck->running_ns) * 1e-9) +
                   " s, longer than the callback timeout (" +
                   number_text(options.callback_timeout_s) + " s, --callback-timeout)";
      }
    }
    return stop_now;
  };
  auto failure = [&]() -> std::string {
    if (const std::string& why = must_stop(); !why.empty()) return why;
    if (auto e = graph_executor->error()) return what_of(e);
    if (auto e = monitor_executor.error()) return what_of(e);
    if (launched) {
      if (std::string f = launched->failure(); !f.empty()) return f;
    }
    if (children) return children->failure();
    return {};
  };
  trace_run_begin(spec, r, period_ns);
  // Discovery shows only our side of an external graph's matches: its warm-up is repeated until
  // an output comes back, so that timing starts once its side has matched too. A graph with a
  // node on a device repeats it until the device is warm (DeviceWarmup), so that neither its
  // program build nor the backlog that made is timed.
  std::optional<Playback::DeliveryGate> gate;
  const int64_t gate_deadline =
      rmw::steady_now_ns() + static_cast<int64_t>(options.connect_timeout_s * 1e9);
  DeviceWarmup device_warmup(r.warmup);
  if (spec.external()) {
    gate = Playback::DeliveryGate{
        r.warmup, [&] { return monitor.received() > 0; }, gate_deadline,
        [] {
          return std::string(
              "the graph matched every endpoint but delivered no output to its warm-up messages "
              "before --connect-timeout: is it running, and does it publish the output topic?");
        }};
  } else if (on_device) {
    gate = Playback::DeliveryGate{
        r.warmup, [&] { return device_warmup.ready_after_round(monitor.received()); },
        gate_deadline,
        [&] {
          const std::size_t answers = monitor.received();
          const std::string within =
              " within --connect-timeout (" + number_text(options.connect_timeout_s) + " s)";
          if (answers == 0) {
            return "the graph's nodes on a device answered none of the warm-up messages" + within +
                   ": is the device working? a slow one needs a longer --connect-timeout";
          }
          return "the graph's nodes on a device answered " + std::to_string(answers) +
                 " warm-up messages, more every round, and were still not keeping up" + within +
                 ": a device this slow to warm up needs a longer --connect-timeout";
        }};
  }
  int64_t repeated_ns = 0;
  playback.run(
      r.records, [&] { return !failure().empty(); },
      [&](std::size_t sent) {
        if (sent == r.warmup + 1) measurement.begin();  // the first measured message is out
        if (options.progress) options.progress(sent, r.count, monitor.received());
      },
      gate ? &*gate : nullptr, &repeated_ns);
  r.warmup_repeated_s = static_cast<double>(repeated_ns) * 1e-9;
  trace_run_end(r.records.size());
  if (r.interrupted && r.records.size() <= r.warmup)
    throw RunInterrupted(stop_now + " before timing started: nothing was measured");

  // Drain: wait for the outstanding outputs, at most drain_s after the last send.
  // A state output keeps reporting after the first reception of each ID: wait the whole drain.
  const std::size_t expected = spec.output.state             ? SIZE_MAX
                               : r.records.size() > r.warmup ? r.records.size() - r.warmup
                                                             : 0;
  const int64_t last_send = r.records.empty() ? rmw::steady_now_ns() : r.records.back().sent_ns;
  const int64_t drain_end = last_send + static_cast<int64_t>(r.drain_s * 1e9);
  // In slices, so that an interrupt or a hung callback ends the drain too.
  while (!monitor.wait_for(expected, std::min(drain_end, rmw::steady_now_ns() + kWatchPeriodNs))) {
    if (rmw::steady_now_ns() >= drain_end || !must_stop().empty()) break;
  }
  // What has not arrived by now is lost, though the window's last readings (an external power
  // meter may take seconds) come before the tally.
  monitor.close();
  measurement.end(r);
  if (link_before) {
    r.network_link = RunResult::LinkUse{options.network_link->description(),
                                        options.network_link->counters() - *link_before};
  }
  const Monitor::Tally tally = monitor.tally();

  if (std::string f = failure(); !f.empty()) r.errors.push_back(f);
  monitor_executor.stop();
  // A callback still stuck in the graph cannot be stopped: its threads, its executor and the
  // context they use are left to it (never destroyed), and the caller ends the process after
  // writing the result (RunResult::threads_abandoned).
  std::string stuck_node;
  if (!graph_executor->stop_within(std::chrono::nanoseconds(kStopGraceNs))) {
    if (auto stuck = graph_executor->running_longer_than(0, rmw::steady_now_ns()))
      stuck_node = stuck->node;
    if (r.errors.empty()) {
      r.errors.push_back("node '" + stuck_node +
                         "' did not return from its callback when the "
                         "run ended");
    }
    r.threads_abandoned = true;
    (void)graph_executor.release();
    (void)context.release();
  }
  if (auto e = r.threads_abandoned ? nullptr : graph_executor->error()) {
    // The node whose callback threw ended the run: say so in its report, as for a child.
    try {
      std::rethrow_exception(e);
    } catch (const graph::NodeError& failed) {
      for (auto& n : r.nodes) {
        if (n.name == failed.node()) n.exit_status = "its callback threw during the run";
      }
    } catch (...) {
    }
  }
  if (launched) r.launched = launched->stop(2.0);
  if (children) {
    r.nodes = children->shutdown(5.0);
    for (const auto& n : r.nodes) {
      if (n.exit_status.starts_with("did not stop"))
        r.errors.push_back("node '" + n.name + "' " + n.exit_status);
    }
    for (const auto& wire : children->control_loops()) {
      try {
        r.control_loops.push_back(control_loop_from_wire(wire, ids, r.records, r.warmup));
      } catch (const nlohmann::json::exception& e) {
        r.errors.push_back("malformed control loop report from a node process: " +
                           std::string(e.what()));
      }
    }
  }
  for (std::size_t i = 0; i < kernel_nodes.size(); ++i) {
    // A node still in its callback is not read: its state is in use.
    if (r.nodes[i].name == stuck_node) {
      r.nodes[i].exit_status = "hung: still in its callback when the run ended";
      continue;
    }
    if (auto* loop = dynamic_cast<plugin::ControlLoopSource*>(kernel_nodes[i].get())) {
      const plugin::LoopReport report = loop->stop_and_report();
      ControlLoopResult c = control_loop_timing(report);
      c.command_to_write = command_to_write(report.writes, ids, r.records, r.warmup);
      r.control_loops.push_back(std::move(c));
    }
    if (const auto* c = dynamic_cast<const plugin::NodeCounters*>(kernel_nodes[i].get())) {
      r.nodes[i].counters = c->counters();
    }
  }
  for (auto& n : r.nodes) {
    const auto node = std::ranges::find(spec.nodes, n.name, &NodeSpec::name);
    if (node == spec.nodes.end()) continue;
    n.origin = kernel_of(*node).origin;
    n.parameters = kernel_config(*node, spec.workload).parameters.effective();
  }
  r.completed = r.records.size() == r.count && r.errors.empty();
  summarise(r, spec, tally);
  r.repeats = tally.repeats;
  // Grey-box: counts, latencies and validity come from the trace; a trace that cannot be read
  // leaves the Playback's and Monitor's, and says so.
  if (grey) {
    try {
      grey->finish(r);
    } catch (const std::exception& e) {
      r.invalid_reasons.push_back("grey-box: the trace in " + r.trace_dir.string() +
                                  " could not be analysed (" + e.what() +
                                  "); the figures are the Playback's and Monitor's");
      r.valid = false;
    }
  }
  r.foreign = tally.foreign;
  add_peers(r.domain_peers, isolation.others());
  if (r.foreign > 0) {
    r.warnings.push_back({"foreign_traffic",
                          std::to_string(r.foreign) + " receptions on " + spec.output.topic +
                              " belonged to another run on domain " + std::to_string(r.domain_id) +
                              " (" + describe_peers(r.domain_peers, 3) +
                              "); they were not counted, but the graph may have worked for them"});
    if (options.strict) {
      r.invalid_reasons.push_back("foreign traffic on the run's topics (--strict)");
      r.valid = false;
    }
  }
  if (r.resources.other_cpu_percent &&
      *r.resources.other_cpu_percent > sysinfo::kBusyThresholdPercent) {
    char message[200];
    std::snprintf(message, sizeof message,
                  "other processes used %.0f %% of a core during the measured "
                  "window",
                  *r.resources.other_cpu_percent);
    r.warnings.push_back({"interference", message});
    if (options.strict) {
      r.invalid_reasons.push_back(std::string(message) + " (--strict)");
      r.valid = false;
    }
  }
  // After timing: the evaluation costs nothing the run measured. These checks call a plug-in's
  // code (its evaluator, its kernels on cpu): one that fails leaves the measured result as it
  // is, saying what could not be checked.
  std::string evaluator_failed = tally.evaluation_error;
  if (evaluate_outputs && evaluator_failed.empty()) {
    try {
      r.functional = on_arrival
                         ? judge_functional(*spec.functional, *on_arrival,
                                            tally.evaluated_on_arrival, functional_ids.size())
                         : evaluate_functional(*spec.functional, dataset, tally.kept,
                                               functional_ids.size(), tally.observed_truth);
    } catch (const std::exception& e) {
      evaluator_failed = e.what();
    }
  }
  if (!evaluator_failed.empty()) {
    r.functional =
        functional_failure(*spec.functional, functional_ids.size(), tally.evaluated_on_arrival,
                           "the evaluator failed: " + evaluator_failed);
    r.warnings.push_back({"functional", "outputs not checked for accuracy (" +
                                            spec.functional->evaluator +
                                            "): its evaluator failed: " + evaluator_failed});
  }
  try {
    r.backend_check = check_backend_answers(spec, dataset, tally.kept);
  } catch (const std::exception& e) {
    r.warnings.push_back(
        {"backend_check", std::string("answers not compared with cpu's: ") + e.what()});
  }
  if (r.backend_check && !r.backend_check->passed) {
    // A backend that computes another answer is functionally invalid, ground truth or not.
    if (!r.functional) {
      r.functional.emplace();
      r.functional->evaluator = "backend check";
    }
    r.functional->valid = false;
    for (const auto& why : r.backend_check->reasons) r.functional->reasons.push_back(why);
  }
  return r;
}

int run_node_process(const BenchmarkSpec& spec, const std::string& node_name,
                     const std::string& rmw, int domain_id, const SchedulingOptions& scheduling,
                     double callback_timeout_s, const std::string& run_token,
                     const std::filesystem::path& keystore, rmw::RosDistro ros_distro) {
  // Ctrl-C in a terminal reaches the whole process group: the runner stops us when it is done.
  signal(SIGINT, SIG_IGN);
  const NodeSpec* node_spec = spec.find_node(node_name);
  if (node_spec == nullptr) {
    std::cerr << "robotperf node: benchmark " << spec.id << " has no node '" << node_name << "'\n";
    return 2;
  }
  // Before the transport and executor start their threads, so that they all inherit it.
  std::optional<ScopedScheduling> scheduled;
  try {
    scheduled.emplace(scheduling);
  } catch (const std::exception& e) {
    std::cerr << "robotperf node " << node_name << ": " << e.what() << "\n";
    return 2;
  }
  // First, so that the runner knows where we run even if we fail to start.
  std::cout << "host " << this_host_identity().dump() << std::endl;
  rmw::TransportOptions t;
  t.domain_id = domain_id;
  if (!run_token.empty()) t.user_data = run_user_data(run_token);
  if (!keystore.empty()) t.security = rmw::enclave_files(keystore);
  t.ros_distro = ros_distro;
  graph::Context context(rmw::make_transport(rmw, t));
  trace_run_join();
  auto node = make_kernel_node(*node_spec, context, spec.workload);
  if (const auto device = device_of(*node, *node_spec))
    std::cout << "device " << device_to_json(*device).dump() << std::endl;
  graph::Executor executor(spec.executor_threads);
  executor.add_node(node);

  // The runner closes our stdin to stop us; a dead runner does the same.
  std::atomic<bool> stdin_closed = false;
  std::thread watcher([&] {
    char buf[256];
    while (std::cin.read(buf, sizeof buf) || std::cin.gcount() > 0) {
    }
    stdin_closed = true;
    executor.cancel();
  });

  // A callback stuck past the timeout: tell the runner, then end, since it will not return.
  std::atomic<bool> done = false;
  const auto limit_ns = static_cast<int64_t>(callback_timeout_s * 1e9);
  std::thread watchdog([&] {
    while (!done) {
      std::this_thread::sleep_for(std::chrono::nanoseconds(kWatchPeriodNs));
      if (auto stuck = executor.running_longer_than(limit_ns, rmw::steady_now_ns())) {
        std::cout << "hung its callback has run for "
                  << number_text(static_cast<double>(stuck->running_ns) * 1e-9)
                  << " s, longer than the callback timeout (" << number_text(callback_timeout_s)
                  << " s, --callback-timeout)" << std::endl;
        std::_Exit(kNodeHungExit);
      }
    }
  });

  int code = 0;
  try {
    // Matching happens in the transport's threads; messages that arrive
    // before spin() wait in the subscriptions' queues. The runner's --connect-timeout bounds the
    // wait: when it gives up, it closes our stdin.
    if (wait_connected({node}, wiring_of(spec), INT64_MAX, [&] { return stdin_closed.load(); })) {
      std::cout << "ready" << std::endl;
      executor.spin();  // until the watcher cancels it, or a callback throws
    }
  } catch (const std::exception& e) {
    std::cerr << "robotperf node " << node_name << ": " << e.what() << "\n";
    // The runner records it with the node's exit status (one line on the wire).
    std::string what = e.what();
    std::ranges::replace(what, '\n', ' ');
    std::cout << "error " << what << std::endl;
    code = 3;
  }
  done = true;
  watchdog.join();
  if (!stdin_closed) {
    // Failed on our own: leave without waiting for the runner.
    std::cout.flush();
    std::_Exit(code);
  }
  watcher.join();
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  auto seconds = [](timeval tv) { return static_cast<double>(tv.tv_sec) + tv.tv_usec * 1e-6; };
  nlohmann::json stats = {{"cpu_user_s", seconds(usage.ru_utime)},
                          {"cpu_system_s", seconds(usage.ru_stime)},
                          {"counters", nlohmann::json::object()}};
  // The loop's metrics are read here, where the loop ran, and go to the runner with the stats;
  // stopping the loop first, so that the counters below are not read while it runs.
  if (auto* loop = dynamic_cast<plugin::ControlLoopSource*>(node.get()))
    stats["control_loop"] = control_loop_to_wire(loop->stop_and_report());
  if (const auto* c = dynamic_cast<const plugin::NodeCounters*>(node.get())) {
    for (const auto& [name, value] : c->counters()) stats["counters"][name] = value;
  }
  std::cout << "stats " << stats.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace)
            << std::endl;
  return code;
}

}  // namespace robotperf::harness
