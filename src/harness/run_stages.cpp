#include "run_stages.hpp"

#include <signal.h>
#include <string.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>

#include "control_loop.hpp"
#include "graph_connection.hpp"
#include "robotperf/harness/node_spec_wire.hpp"
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
  t.domain_id = options.transport.domain_id;
  t.user_data = user_data;
  if (!options.transport.keystore.empty())
    t.security = rmw::enclave_files(options.transport.keystore);
  t.ros_distro = options.transport.ros_distro;
  return rmw::make_transport(options.transport.rmw, t);
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

// How many messages the graph's queues hold on their way through it: the shallowest KEEP_LAST
// depth of its inputs and of its nodes' subscriptions (all of them with KEEP_ALL). Offline keeps
// that many in flight, so that it fills the graph without overflowing a queue, which would turn
// the Playback's haste into loss charged to the graph.
std::size_t queued_messages(const BenchmarkSpec& spec, std::size_t count) {
  std::size_t depth = count;
  auto shallowest = [&](const rmw::QoS& qos) {
    if (qos.history == rmw::History::kKeepLast)
      depth = std::min(depth, std::max<std::size_t>(qos.depth, 1));
  };
  for (const auto& input : spec.inputs) shallowest(input.qos);
  for (const auto& node : spec.nodes) shallowest(node.qos);
  return std::max<std::size_t>(depth, 1);
}

// When the Playback sends each message; empty: every period.
std::vector<int64_t> schedule_of(const RunPlan& plan, const RunOptions& options,
                                 const RunResult& r) {
  if (options.load.bag_timeline)
    return timeline_schedule(plan.dataset.frame_times_ns, options.load.rate_scale, r.count);
  if (r.timeline == "fixed" || options.load.scenario != Scenario::kOpenLoop) return {};
  return arrival_schedule(options.load.arrival, plan.period_ns, r.count);
}

// The arguments each node process gets beside its node's name, transport and domain: the graph's
// nodes as resolved here (the overrides applied), and the run's settings.
std::vector<std::string> node_arguments(const BenchmarkSpec& spec, const RunOptions& options,
                                        const RunResult& r) {
  std::vector<std::string> arguments = options.processes.scheduling.node_arguments();
  arguments.insert(arguments.end(), {"--nodes", encode_nodes(spec.nodes)});
  arguments.insert(arguments.end(),
                   {"--callback-timeout", number_text(options.processes.callback_timeout_s),
                    "--run-token", r.run_token});
  if (!r.keystore.empty()) arguments.insert(arguments.end(), {"--security", r.keystore.string()});
  arguments.insert(arguments.end(), {"--ros-distro", rmw::to_string(options.transport.ros_distro)});
  return arguments;
}

}  // namespace

std::optional<plugin::DeviceInfo> device_of(const graph::Node& node, const NodeSpec& spec) {
  const auto* d = dynamic_cast<const plugin::DeviceNode*>(&node);
  if (d == nullptr || spec.backend == "cpu") return std::nullopt;
  return d->device();
}

RunEnvironment::RunEnvironment(const RunPlan& plan, const RunOptions& options, RunResult& r) {
  if (options.processes.layout == ProcessLayout::kSingle)
    scheduling.emplace(options.processes.scheduling);
  if (options.tracing.mode == RunMode::kGrey) grey.emplace(plan.spec(), options, r);
  r.started_unix_ns = rmw::wall_now_ns();
  ids = make_message_ids(plan.period_ns, r.count);
  r.id_base_ns = ids.base_ns;
  r.run_token = make_run_token();
  const std::string user_data = run_user_data(r.run_token, &ids);
  context = std::make_unique<graph::Context>(transport_for(options, user_data));
  isolation.emplace(context->transport(), r.run_token);
  if (options.load.bag.has_value() && options.transport.rmw != "intra")
    playback_context = std::make_unique<graph::Context>(transport_for(options, user_data));
}

Instruments::Instruments(const RunPlan& plan, const RunOptions& options, RunEnvironment& env,
                         const RunResult& r)
    : playback(env.playback_context ? *env.playback_context : *env.context, plan.spec(),
               plan.dataset, env.ids, env.playback_context != nullptr,
               schedule_of(plan, options, r)),
      monitor(*env.context, plan.spec().output, env.ids, r.warmup, &*env.isolation),
      monitor_executor(1, options.transport.monitor_wait) {
  const BenchmarkSpec& spec = plan.spec();
  if (options.load.scenario != Scenario::kOpenLoop) {
    // A lost output holds the next message back for as long as the drain waits.
    playback.pace(
        {options.load.scenario,
         [this](uint64_t id, int64_t deadline) { return monitor.wait_received(id, deadline); },
         static_cast<int64_t>(r.drain_s * 1e9),
         options.load.scenario == Scenario::kOffline ? queued_messages(spec, r.count) : 1});
  }
  if (plan.evaluate_outputs) {
    // A missing truth stream fails before timing.
    auto evaluator = make_evaluator(*spec.functional, plan.dataset);
    functional_ids = functional_sample_ids(r.count, r.warmup, spec.functional->sample);
    monitor.keep_outputs(functional_ids);
    const auto& info = plugin::registry().find_evaluator(spec.functional->evaluator)->info;
    if (info.on_arrival && !spec.output.state && spec.functional->observed_truth_topic.empty()) {
      on_arrival = std::move(evaluator);
      monitor.evaluate_on_arrival(*on_arrival, truth_frames(*spec.functional, plan.dataset));
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
  on_device = uses_other_backend(spec);
  if (on_device && functional_ids.empty() && has_comparison(spec.output.type)) {
    functional_ids = functional_sample_ids(r.count, r.warmup, 16);
    monitor.keep_outputs(functional_ids);
  }
  monitor_executor.add_node(monitor.node());
  for (std::size_t i = 0; i < spec.more_outputs.size(); ++i) {
    more_monitors.push_back(std::make_unique<Monitor>(
        *env.context, spec.more_outputs[i], env.ids, r.warmup, &*env.isolation,
        "robotperf_monitor_" + std::to_string(i + 2), false));
    monitor_executor.add_node(more_monitors.back()->node());
  }
}

GraphUnderTest::GraphUnderTest(const RunPlan& plan, const RunOptions& options, RunEnvironment& env,
                               Instruments& instruments, RunResult& r)
    : executor(std::make_unique<graph::Executor>(plan.spec().executor_threads)),
      local_nodes{instruments.playback.node(), instruments.monitor.node()} {
  const BenchmarkSpec& spec = plan.spec();
  for (const auto& m : instruments.more_monitors) local_nodes.push_back(m->node());
  if (options.processes.layout == ProcessLayout::kSingle) {
    for (const auto& n : spec.nodes) {
      auto node = make_kernel_node(n, *env.context, spec.workload);
      executor->add_node(node);
      local_nodes.push_back(node);
      kernel_nodes.push_back(node);
      r.nodes.push_back(
          {n.name, n.kernel, 0, "ok", -1, -1, {}, "", "", true, n.backend, device_of(*node, n)});
    }
  } else {
    children = std::make_unique<NodeProcesses>(
        spec, options.processes.node_command, options.transport.rmw, options.transport.domain_id,
        node_arguments(spec, options, r), options.processes.host_launchers);
  }
  if (!spec.launch.empty()) {
    launched = std::make_unique<LaunchedProcesses>(
        spec, options.transport.rmw, options.transport.domain_id, options.processes.log_dir,
        spec.id + "-" + r.run_token + ".");
  }
  connect_deadline_ns =
      rmw::steady_now_ns() + static_cast<int64_t>(options.processes.connect_timeout_s * 1e9);
  instruments.monitor_executor.start();
  executor->start();
}

void connect_graph(const RunPlan& plan, const RunOptions& options, const RunEnvironment& env,
                   GraphUnderTest& graph, const RunResult& r) {
  auto interrupted = [&] {
    // A launched process that ends before the graph is up ends the wait with what it said: the
    // graph as given cannot run, as one that never connects.
    if (graph.launched) {
      if (std::string f = graph.launched->failure("before the graph connected"); !f.empty())
        throw GraphNotConnected(f);
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
    return others_on_topic(env.isolation->others(), ours, qos, r.domain_id);
  };
  const int64_t deadline = graph.connect_deadline_ns;
  if ((graph.children && !graph.children->wait_ready(deadline, interrupted)) ||
      !wait_connected(graph.local_nodes, wiring_of(plan.spec()), deadline, interrupted,
                      about_topic)) {
    throw RunInterrupted(interrupted_by(options.interrupted->load()) +
                         " before the run started: nothing was measured");
  }
}

namespace {

// The processes whose resources are the graph's: once ready, each child has said where it runs,
// and is sampled when that is here.
std::vector<metrics::ResourceMonitor::Process> graph_processes(const BenchmarkSpec& spec,
                                                               const GraphUnderTest& graph) {
  std::vector<metrics::ResourceMonitor::Process> processes;
  if (graph.children) {
    for (const auto& [pid, name] : graph.children->processes()) processes.push_back({pid, name});
    // The Playback and Monitor are part of what is measured, not interference.
    processes.push_back({getpid(), "robotperf (Playback, Monitor)"});
  } else {
    processes.push_back({getpid(), spec.nodes.empty() ? "robotperf (Playback, Monitor)"
                                                      : "robotperf (graph, Playback, Monitor)"});
  }
  if (graph.launched) {
    for (const auto& [pid, name] : graph.launched->processes()) processes.push_back({pid, name});
  }
  return processes;
}

// A launched command's own children (`ros2 run`'s node, a wrapper script's program) are its.
std::vector<pid_t> sampled_with_descendants(const GraphUnderTest& graph) {
  std::vector<pid_t> pids;
  if (graph.launched) {
    for (const auto& [pid, name] : graph.launched->processes()) pids.push_back(pid);
  }
  return pids;
}

}  // namespace

MeasurementWindow::MeasurementWindow(const RunOptions& options, const BenchmarkSpec& spec,
                                     const GraphUnderTest& graph)
    : measurement(options, graph_processes(spec, graph), sampled_with_descendants(graph)) {
  if (options.processes.network_link) link_before = options.processes.network_link->counters();
}

void check_before_timing(const RunPlan& plan, const RunOptions& options, RunEnvironment& env,
                         MeasurementWindow& window, RunResult& r) {
  const BenchmarkSpec& spec = plan.spec();
  r.warnings = check_run_rules_for(r, window.measurement.probe_other_load());
  // Discovery has run at least as long as the graph took to connect.
  add_peers(r.domain_peers, env.isolation->others());
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
  for (const auto& line : plan.corrupt_messages) r.warnings.push_back({"corrupt_messages", line});
  if (spec.functional && !plan.evaluate_outputs) {
    r.warnings.push_back({"functional", "outputs not checked for accuracy (" +
                                            spec.functional->evaluator +
                                            "): a bag has no ground truth to check them against"});
  }
}

RunWatch::RunWatch(const RunOptions& options, const Instruments& instruments,
                   const GraphUnderTest& graph, RunResult& r)
    : options_(options), instruments_(instruments), graph_(graph), r_(r) {}

const std::string& RunWatch::must_stop() {
  if (!stop_now_.empty()) return stop_now_;
  const auto callback_limit_ns = static_cast<int64_t>(options_.processes.callback_timeout_s * 1e9);
  if (options_.interrupted && options_.interrupted->load() != 0) {
    r_.interrupted = true;
    stop_now_ = interrupted_by(options_.interrupted->load());
  } else if (auto stuck =
                 graph_.executor->running_longer_than(callback_limit_ns, rmw::steady_now_ns())) {
    stop_now_ = "node '" + stuck->node + "' hung: its callback has run for " +
                number_text(static_cast<double>(stuck->running_ns) * 1e-9) +
                " s, longer than the callback timeout (" +
                number_text(options_.processes.callback_timeout_s) + " s, --callback-timeout)";
  }
  return stop_now_;
}

std::string RunWatch::failure() {
  if (const std::string& why = must_stop(); !why.empty()) return why;
  if (auto e = graph_.executor->error()) return what_of(e);
  if (auto e = instruments_.monitor_executor.error()) return what_of(e);
  if (graph_.launched) {
    if (std::string f = graph_.launched->failure(); !f.empty()) return f;
  }
  if (graph_.children) return graph_.children->failure();
  return {};
}

namespace {

// Discovery shows only our side of an external graph's matches: its warm-up is repeated until
// an output comes back, so that timing starts once its side has matched too. A graph with a
// node on a device repeats it until the device is warm (DeviceWarmup), so that neither its
// program build nor the backlog that made is timed.
std::optional<Playback::DeliveryGate> delivery_gate(const BenchmarkSpec& spec,
                                                    const RunOptions& options,
                                                    const Instruments& instruments,
                                                    DeviceWarmup& device_warmup,
                                                    const RunResult& r) {
  const int64_t deadline =
      rmw::steady_now_ns() + static_cast<int64_t>(options.processes.connect_timeout_s * 1e9);
  const Monitor* monitor = &instruments.monitor;
  if (spec.external()) {
    return Playback::DeliveryGate{
        r.warmup, [monitor] { return monitor->received() > 0; }, deadline,
        [] {
          return std::string(
              "the graph matched every endpoint but delivered no output to its warm-up messages "
              "before --connect-timeout: is it running, and does it publish the output topic?");
        }};
  }
  if (!instruments.on_device) return std::nullopt;
  return Playback::DeliveryGate{
      r.warmup,
      [&device_warmup, monitor] { return device_warmup.ready_after_round(monitor->received()); },
      deadline,
      [monitor, timeout_s = options.processes.connect_timeout_s] {
        const std::size_t answers = monitor->received();
        const std::string within = " within --connect-timeout (" + number_text(timeout_s) + " s)";
        if (answers == 0) {
          return "the graph's nodes on a device answered none of the warm-up messages" + within +
                 ": is the device working? a slow one needs a longer --connect-timeout";
        }
        return "the graph's nodes on a device answered " + std::to_string(answers) +
               " warm-up messages, more every round, and were still not keeping up" + within +
               ": a device this slow to warm up needs a longer --connect-timeout";
      }};
}

}  // namespace

void warm_up_and_measure(const RunPlan& plan, const RunOptions& options, Instruments& instruments,
                         MeasurementWindow& window, RunWatch& watch, RunResult& r) {
  trace_run_begin(plan.spec(), r, plan.period_ns);
  DeviceWarmup device_warmup(r.warmup);
  const std::optional<Playback::DeliveryGate> gate =
      delivery_gate(plan.spec(), options, instruments, device_warmup, r);
  int64_t repeated_ns = 0;
  instruments.playback.run(
      r.records, [&] { return !watch.failure().empty(); },
      [&](std::size_t sent) {
        if (sent == r.warmup + 1) window.measurement.begin();  // the first measured message is out
        if (options.progress) options.progress(sent, r.count, instruments.monitor.received());
      },
      gate ? &*gate : nullptr, &repeated_ns);
  r.warmup_repeated_s = static_cast<double>(repeated_ns) * 1e-9;
  trace_run_end(r.records.size());
  if (r.interrupted && r.records.size() <= r.warmup)
    throw RunInterrupted(watch.must_stop() + " before timing started: nothing was measured");
}

Monitor::Tally drain(const RunPlan& plan, const RunOptions& options, Instruments& instruments,
                     MeasurementWindow& window, RunWatch& watch, RunResult& r) {
  Monitor& monitor = instruments.monitor;
  // Wait for the outstanding outputs, at most drain_s after the last send. A state output keeps
  // reporting after the first reception of each ID: wait the whole drain.
  const std::size_t expected = plan.spec().output.state      ? SIZE_MAX
                               : r.records.size() > r.warmup ? r.records.size() - r.warmup
                                                             : 0;
  const int64_t last_send = r.records.empty() ? rmw::steady_now_ns() : r.records.back().sent_ns;
  const int64_t drain_end = last_send + static_cast<int64_t>(r.drain_s * 1e9);
  // In slices, so that an interrupt or a hung callback ends the drain too.
  while (!monitor.wait_for(expected, std::min(drain_end, rmw::steady_now_ns() + kWatchPeriodNs))) {
    if (rmw::steady_now_ns() >= drain_end || !watch.must_stop().empty()) break;
  }
  // The further outputs within the same drain.
  for (const auto& m : instruments.more_monitors) {
    while (!m->wait_for(expected, std::min(drain_end, rmw::steady_now_ns() + kWatchPeriodNs))) {
      if (rmw::steady_now_ns() >= drain_end || !watch.must_stop().empty()) break;
    }
  }
  // What has not arrived by now is lost, though the window's last readings (an external power
  // meter may take seconds) come before the tally.
  monitor.close();
  for (const auto& m : instruments.more_monitors) m->close();
  window.measurement.end(r);
  if (window.link_before) {
    r.network_link =
        RunResult::LinkUse{options.processes.network_link->description(),
                           options.processes.network_link->counters() - *window.link_before};
  }
  instruments.more_tallies.clear();
  for (const auto& m : instruments.more_monitors) instruments.more_tallies.push_back(m->tally());
  return monitor.tally();
}

namespace {

// Stops the graph's executor. A callback still stuck in it cannot be stopped: its threads, the
// executor and the context they use are left to it (never destroyed), and the caller ends the
// process after writing the result (RunResult::threads_abandoned). Returns the stuck node's name;
// empty when none.
std::string stop_executor(RunEnvironment& env, GraphUnderTest& graph, RunResult& r) {
  std::string stuck_node;
  if (!graph.executor->stop_within(std::chrono::nanoseconds(kStopGraceNs))) {
    if (auto stuck = graph.executor->running_longer_than(0, rmw::steady_now_ns()))
      stuck_node = stuck->node;
    if (r.errors.empty()) {
      r.errors.push_back("node '" + stuck_node +
                         "' did not return from its callback when the "
                         "run ended");
    }
    r.threads_abandoned = true;
    (void)graph.executor.release();
    (void)env.context.release();
    return stuck_node;
  }
  if (auto e = graph.executor->error()) {
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
  return stuck_node;
}

// Stops an external graph's launched processes and the node processes, with their reports.
void stop_processes(GraphUnderTest& graph, const MessageIds& ids, RunResult& r) {
  if (graph.launched) r.launched = graph.launched->stop(2.0);
  if (!graph.children) return;
  r.nodes = graph.children->shutdown(5.0);
  for (const auto& n : r.nodes) {
    if (n.exit_status.starts_with("did not stop"))
      r.errors.push_back("node '" + n.name + "' " + n.exit_status);
  }
  for (const auto& wire : graph.children->control_loops()) {
    try {
      r.control_loops.push_back(control_loop_from_wire(wire, ids, r.records, r.warmup));
    } catch (const nlohmann::json::exception& e) {
      r.errors.push_back("malformed control loop report from a node process: " +
                         std::string(e.what()));
    }
  }
}

// The reports of the kernel nodes that ran in this process: control loops and counters.
void read_kernel_nodes(const GraphUnderTest& graph, const MessageIds& ids,
                       const std::string& stuck_node, RunResult& r) {
  for (std::size_t i = 0; i < graph.kernel_nodes.size(); ++i) {
    // A node still in its callback is not read: its state is in use.
    if (r.nodes[i].name == stuck_node) {
      r.nodes[i].exit_status = "hung: still in its callback when the run ended";
      continue;
    }
    if (auto* loop = dynamic_cast<plugin::ControlLoopSource*>(graph.kernel_nodes[i].get())) {
      const plugin::LoopReport report = loop->stop_and_report();
      ControlLoopResult c = control_loop_timing(report);
      c.command_to_write = command_to_write(report.writes, ids, r.records, r.warmup);
      r.control_loops.push_back(std::move(c));
    }
    if (const auto* c = dynamic_cast<const plugin::NodeCounters*>(graph.kernel_nodes[i].get())) {
      r.nodes[i].counters = c->counters();
    }
  }
}

}  // namespace

void stop_graph(const RunPlan& plan, RunEnvironment& env, Instruments& instruments,
                GraphUnderTest& graph, RunWatch& watch, RunResult& r) {
  if (std::string f = watch.failure(); !f.empty()) r.errors.push_back(f);
  instruments.monitor_executor.stop();
  const std::string stuck_node = stop_executor(env, graph, r);
  stop_processes(graph, env.ids, r);
  read_kernel_nodes(graph, env.ids, stuck_node, r);
  for (auto& n : r.nodes) {
    const auto node = std::ranges::find(plan.spec().nodes, n.name, &NodeSpec::name);
    if (node == plan.spec().nodes.end()) continue;
    n.origin = kernel_of(*node).origin_on(node->backend);
    n.parameters = kernel_config(*node, plan.spec().workload).parameters.effective();
  }
}

namespace {

// One output's figures from what its Monitor received of the run's measured messages.
OutputFigures output_figures(const RunResult& r, const std::string& topic,
                             const std::vector<int64_t>& received_ns) {
  OutputFigures f;
  f.topic = topic;
  std::vector<double> from_scheduled, from_sent;
  std::vector<metrics::TimedEvent> receptions;
  std::vector<int64_t> arrivals;
  std::size_t measured = 0;
  for (const auto& rec : r.records) {
    if (rec.id < r.warmup) continue;
    ++measured;
    const int64_t at = rec.id < received_ns.size() ? received_ns[rec.id] : -1;
    if (at < 0) continue;
    ++f.matched;
    from_scheduled.push_back(static_cast<double>(at - rec.scheduled_ns));
    from_sent.push_back(static_cast<double>(at - rec.sent_ns));
    receptions.push_back({rec.scheduled_ns, at});
    arrivals.push_back(at);
  }
  f.lost = measured - f.matched;
  f.loss_percent =
      measured ? 100.0 * static_cast<double>(f.lost) / static_cast<double>(measured) : 0.0;
  f.latency_from_scheduled = metrics::compute_stats(from_scheduled);
  f.latency_from_sent = metrics::compute_stats(from_sent);
  f.throughput_hz = metrics::event_rate_hz(receptions);
  if (r.timeline == scenario_name(Scenario::kOffline) && !arrivals.empty()) {
    // One deadline for all: outputs over the time from the first measured send (as the run's).
    int64_t first_send = INT64_MAX;
    for (const auto& rec : r.records)
      if (rec.id >= r.warmup) first_send = std::min(first_send, rec.sent_ns);
    const double window_s = static_cast<double>(std::ranges::max(arrivals) - first_send) * 1e-9;
    f.throughput_hz = window_s > 0 ? static_cast<double>(f.matched) / window_s : 0;
  }
  // Jitter against the input period as the Playback achieved it (any arrival pattern).
  const double rate = r.offered_rate_hz > 0 ? r.offered_rate_hz : r.rate_hz;
  f.period_ns = rate > 0 ? 1e9 / rate : 0;
  const metrics::OutputJitter j = metrics::output_jitter(arrivals, f.period_ns);
  f.interval = j.interval;
  f.jitter = j.jitter;
  return f;
}

// Every output's figures, the run's own first; a further output's loss beyond the bound makes the
// run invalid as the first's does.
void summarise_outputs(RunResult& r, const BenchmarkSpec& spec, const Monitor::Tally& tally,
                       const std::vector<Monitor::Tally>& more_tallies) {
  r.outputs.clear();
  r.outputs.push_back(output_figures(r, spec.output.topic, tally.received_ns));
  for (std::size_t i = 0; i < more_tallies.size() && i < spec.more_outputs.size(); ++i) {
    OutputFigures f = output_figures(r, spec.more_outputs[i].topic, more_tallies[i].received_ns);
    if (f.loss_percent > spec.max_loss_percent) {
      char buf[200];
      std::snprintf(buf, sizeof buf, "output %s: %.2f %% lost, above the %.2f %% bound",
                    f.topic.c_str(), f.loss_percent, spec.max_loss_percent);
      r.invalid_reasons.emplace_back(buf);
      r.valid = false;
    }
    r.outputs.push_back(std::move(f));
  }
}

void summarise(RunResult& r, const BenchmarkSpec& spec, const Monitor::Tally& tally) {
  std::vector<double> from_scheduled, from_sent, lateness;
  std::vector<metrics::TimedEvent> sends, receptions;
  // Offline, every measured message is issued at once (LoadGen's Offline): at the first one's
  // send, which the others wait behind in the Playback.
  const bool offline = r.timeline == scenario_name(Scenario::kOffline);
  if (offline) {
    for (auto& rec : r.records) {
      if (rec.id >= r.warmup) {
        const int64_t issued = rec.sent_ns;
        for (auto& later : r.records) {
          if (later.id >= r.warmup) later.scheduled_ns = issued;
        }
        break;
      }
    }
  }
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
  if (offline && !sends.empty()) {
    // One deadline for all: the rates are counts over the time from the first send (LoadGen's
    // samples per second), not intervals between deadlines.
    const auto last = [](const std::vector<metrics::TimedEvent>& events) {
      return std::ranges::max(events, {}, &metrics::TimedEvent::time_ns).time_ns;
    };
    const int64_t first_send = sends.front().time_ns;
    const double send_span_s = static_cast<double>(last(sends) - first_send) * 1e-9;
    r.offered_rate_hz = send_span_s > 0 ? static_cast<double>(sends.size()) / send_span_s : 0;
    r.window_s = receptions.empty() ? 0 : static_cast<double>(last(receptions) - first_send) * 1e-9;
    r.throughput_hz = r.window_s > 0 ? static_cast<double>(receptions.size()) / r.window_s : 0;
  }

  auto invalid = [&](std::string why) { r.invalid_reasons.push_back(std::move(why)); };
  for (const auto& e : r.errors) invalid("run ended early: " + e);
  for (auto& why :
       metrics::delivery_invalid_reasons({r.matched, r.duplicates, r.unknown, r.loss_percent},
                                         spec.min_samples, spec.max_loss_percent))
    invalid(std::move(why));
  r.valid = r.invalid_reasons.empty();
}

// Another run's receptions, and other processes' CPU in the window: warnings, and with --strict
// an invalid result.
void warn_of_interference(const BenchmarkSpec& spec, const RunOptions& options, RunResult& r) {
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
}

}  // namespace

void summarise_run(const RunPlan& plan, const RunOptions& options, RunEnvironment& env,
                   const Monitor::Tally& tally, const std::vector<Monitor::Tally>& more_tallies,
                   RunResult& r) {
  r.completed = r.records.size() == r.count && r.errors.empty();
  summarise(r, plan.spec(), tally);
  summarise_outputs(r, plan.spec(), tally, more_tallies);
  r.repeats = tally.repeats;
  // Grey-box: counts, latencies and validity come from the trace; a trace that cannot be read
  // leaves the Playback's and Monitor's, and says so.
  if (env.grey) {
    try {
      env.grey->finish(r);
    } catch (const std::exception& e) {
      r.invalid_reasons.push_back("grey-box: the trace in " + r.trace_dir.string() +
                                  " could not be analysed (" + e.what() +
                                  "); the figures are the Playback's and Monitor's");
      r.valid = false;
    }
  }
  r.foreign = tally.foreign;
  add_peers(r.domain_peers, env.isolation->others());
  warn_of_interference(plan.spec(), options, r);
}

void check_outputs(const RunPlan& plan, Instruments& instruments, const Monitor::Tally& tally,
                   RunResult& r) {
  const BenchmarkSpec& spec = plan.spec();
  // After timing: the evaluation costs nothing the run measured. These checks call a plug-in's
  // code (its evaluator, its kernels on cpu): one that fails leaves the measured result as it
  // is, saying what could not be checked.
  const std::size_t sampled = instruments.functional_ids.size();
  std::string evaluator_failed = tally.evaluation_error;
  if (plan.evaluate_outputs && evaluator_failed.empty()) {
    try {
      r.functional = instruments.on_arrival
                         ? judge_functional(*spec.functional, *instruments.on_arrival,
                                            tally.evaluated_on_arrival, sampled)
                         : evaluate_functional(*spec.functional, plan.dataset, tally.kept, sampled,
                                               tally.observed_truth);
    } catch (const std::exception& e) {
      evaluator_failed = e.what();
    }
  }
  if (!evaluator_failed.empty()) {
    r.functional = functional_failure(*spec.functional, sampled, tally.evaluated_on_arrival,
                                      "the evaluator failed: " + evaluator_failed);
    r.warnings.push_back({"functional", "outputs not checked for accuracy (" +
                                            spec.functional->evaluator +
                                            "): its evaluator failed: " + evaluator_failed});
  }
  try {
    r.backend_check = check_backend_answers(spec, plan.dataset, tally.kept);
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
}

}  // namespace robotperf::harness
