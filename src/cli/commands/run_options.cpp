// The harness's options for `run`, made of its arguments and checked before anything is
// measured; each check says what is wrong in one line (std::invalid_argument).
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

#include "../interrupts.hpp"
#include "robotperf/harness/backend_check.hpp"
#include "robotperf/harness/dataset.hpp"
#include "robotperf/rmw/transport.hpp"
#include "robotperf/tracing/session.hpp"
#include "run.hpp"

namespace robotperf::cli {

namespace {

// "--remap from:=to" and "--window START:END" (seconds, either may be empty).
harness::BagSelection bag_selection(const RunArgs& a) {
  harness::BagSelection bag;
  bag.path = *a.dataset;
  for (const auto& r : a.remaps) {
    const auto sep = r.find(":=");
    if (sep == std::string::npos || sep == 0 || sep + 2 == r.size())
      throw std::invalid_argument("--remap " + r + ": expected <bag topic>:=<benchmark topic>");
    bag.remaps[r.substr(0, sep)] = r.substr(sep + 2);
  }
  if (a.window) {
    const auto sep = a.window->find(':');
    auto seconds = [&](const std::string& text) -> std::optional<double> {
      if (text.empty()) return std::nullopt;
      const std::optional<double> v = decimal<double>(text);
      if (!v || !(*v >= 0))
        throw std::invalid_argument("--window " + *a.window + ": expected START:END in seconds");
      return v;
    };
    if (sep == std::string::npos)
      throw std::invalid_argument("--window " + *a.window + ": expected START:END in seconds");
    bag.start_s = seconds(a.window->substr(0, sep));
    bag.end_s = seconds(a.window->substr(sep + 1));
  }
  return bag;
}

// --host NAME=COMMAND for the hosts the graph names, checked; --netns replaces them.
std::map<std::string, std::vector<std::string>> host_launchers(const harness::BenchmarkSpec& spec,
                                                               const RunArgs& a) {
  const auto hosts = spec.hosts();
  if (a.netns && hosts.empty()) {
    throw std::invalid_argument("--netns puts the graph's hosts in network namespaces, but " +
                                spec.id + " places no node on a host (graph.yaml host:)");
  }
  if (a.netns && !a.hosts.empty())
    throw std::invalid_argument("--netns makes the hosts' launchers itself: not with --host");
  if (a.netns && hosts.size() > 1) {
    throw std::invalid_argument("--netns makes one other host, and " + spec.id + " names " +
                                std::to_string(hosts.size()) + "; give each a --host launcher");
  }
  if (!a.netns && (a.link_rate != "1gbit" || !a.netem.empty()))
    throw std::invalid_argument(
        "--link-rate and --netem shape the link --netns makes: add --netns");
  std::map<std::string, std::vector<std::string>> out;
  for (const auto& entry : a.hosts) {
    const auto equals = entry.find('=');
    const std::string name = entry.substr(0, equals);
    if (equals == std::string::npos || !harness::valid_host_name(name))
      throw std::invalid_argument("--host " + entry + ": expected NAME=COMMAND");
    if (std::ranges::find(hosts, name) == hosts.end()) {
      throw std::invalid_argument("--host " + name + ": " + spec.id +
                                  " places no node on that host (graph.yaml host:)");
    }
    std::istringstream words(entry.substr(equals + 1));
    for (std::string w; words >> w;) out[name].push_back(w);
    if (out[name].empty()) throw std::invalid_argument("--host " + entry + ": no command");
  }
  return out;
}

// What is sent, when, and what the nodes run on.
void set_input_options(harness::RunOptions& o, const RunArgs& a) {
  if (a.dataset) {
    // A bag replaces the generated dataset, so its workload parameters would change nothing.
    if (!a.workload.empty() || a.sweep)
      throw std::invalid_argument(std::string(a.sweep ? "--sweep" : "--workload") +
                                  " sets the generated dataset's parameters: not with --dataset");
    o.load.bag = bag_selection(a);
  }
  if (a.rate_scale != 1.0 && a.rate != "bag")
    throw std::invalid_argument("--rate-scale only applies with --rate bag");
  if (a.rate == "bag") {
    o.load.bag_timeline = true;
    o.load.rate_scale = a.rate_scale;
  } else if (a.rate) {
    o.load.rate_hz = decimal<double>(*a.rate);
    if (!o.load.rate_hz)
      throw std::invalid_argument("--rate " + *a.rate + ": expected a rate in Hz or 'bag'");
  }
  o.load.arrival = harness::ArrivalPattern::parse(a.arrival);
  if (a.arrival_seed && o.load.arrival.kind != harness::ArrivalPattern::Kind::kPoisson)
    throw std::invalid_argument("--arrival-seed only applies with --arrival poisson");
  if (a.arrival_seed) o.load.arrival.seed = *a.arrival_seed;
  o.load.scenario = harness::parse_scenario(a.scenario);
  o.transport.monitor_wait =
      a.monitor_wait == "spin" ? graph::WaitMode::kSpin : graph::WaitMode::kSleep;
  o.nodes.update_rate_hz = a.update_rate;
  // Said before anything else of the run: a backend this build lacks is named by no kernel.
  if (a.backend) harness::check_backend_available(*a.backend);
  o.nodes.backend = a.backend;
  o.nodes.device_resident = a.device_resident;
  o.load.count = a.count;
  o.load.duration_s = a.duration;
  o.load.warmup = a.warmup;
  o.load.drain_s = a.drain;
}

// The transport, processes, hosts and domain of the graph. The --netns link is made before any
// participant, so that all of this process's sockets are on the runner's side.
void set_graph_options(harness::RunOptions& o, const harness::BenchmarkSpec& spec, const RunArgs& a,
                       const Context& context, std::optional<harness::NetworkLink>& link) {
  const std::string processes = a.processes.value_or(spec.processes);
  // An external graph's nodes are reached through DDS, as per-node children are.
  o.transport.rmw =
      a.rmw.value_or(processes == "per-node" || spec.external() ? "fastdds" : "intra");
  o.processes.log_dir = a.output;
  o.processes.host_launchers = host_launchers(spec, a);
  o.transport.keystore = a.security;
  o.transport.ros_distro = rmw::ros_distro_from_name(a.ros_distro);
  if (a.netns && spec.network.vpn != harness::NetworkLayout::Vpn::kNone &&
      o.transport.rmw == "cyclonedds") {
    throw std::invalid_argument(
        "--netns with a VPN (graph.yaml network:): cyclonedds would send around the tunnel, on the "
        "veth path under it (Cyclone DDS 0.10 takes the multicast-capable interface); use fastdds");
  }
  if (a.netns) {
    link.emplace(harness::LinkShaping{a.link_rate == "none" ? "" : a.link_rate, a.netem},
                 spec.network);
    link->enter_runner_side();
    for (const auto& host : spec.hosts()) o.processes.host_launchers[host] = link->launcher();
    o.processes.network_link = &*link;
  }
  if (!a.domain) {
    o.transport.domain_id = rmw::domain_id_from_environment();
  } else if (*a.domain == "auto") {
    o.transport.domain_id = rmw::find_quiet_domain(o.transport.rmw);
    if (!a.quiet)
      std::fprintf(stderr, "robotperf: --domain auto: domain %d\n", o.transport.domain_id);
  } else {
    o.transport.domain_id = rmw::parse_domain_id(*a.domain).value();  // checked when parsed
  }
  o.processes.layout =
      processes == "per-node" ? harness::ProcessLayout::kPerNode : harness::ProcessLayout::kSingle;
  // Every child loads the plug-ins this process was given (the package's own `plugins:` it
  // loads with the package, ROBOTPERF_PLUGIN_PATH it inherits).
  o.processes.node_command = {self_executable().string()};
  for (const auto& p : context.plugins)
    o.processes.node_command.insert(o.processes.node_command.end(), {"--plugin", p});
  o.processes.node_command.push_back("node");
}

// Power, scheduling, limits, progress, and where the results and a grey run's trace go.
void set_measurement_options(harness::RunOptions& o, const harness::BenchmarkSpec& spec,
                             const RunArgs& a) {
  o.power = a.power.options();
  o.processes.scheduling = a.scheduling.options();
  o.strict = a.strict;
  o.processes.callback_timeout_s = a.callback_timeout_s;
  o.processes.connect_timeout_s = a.connect_timeout_s;
  o.interrupted = &g_interrupted;
  if (!a.quiet && isatty(STDERR_FILENO)) {
    o.progress = [id = spec.id](std::size_t sent, std::size_t total, std::size_t received) {
      std::fprintf(stderr, "\r[%s] sent %zu/%zu  received %zu ", id.c_str(), sent, total, received);
      if (sent == total) std::fputc('\n', stderr);
    };
  }
  // Fail on an unwritable output folder, or a sub-buffer size LTTng refuses, before spending time
  // on the run.
  require_writable_folder(a.output, "--output");
  if (a.mode == "grey" && a.trace_subbuf != 0) tracing::check_subbuffer_bytes(a.trace_subbuf);
  if (a.mode == "grey") {
    // Each run's trace folder is made when it starts (run_drivers.cpp).
    o.tracing.mode = harness::RunMode::kGrey;
    o.tracing.subbuf_bytes = a.trace_subbuf;
  }
}

}  // namespace

void apply_workload(harness::BenchmarkSpec& spec, const RunArgs& args) {
  for (const std::string& assignment : args.workload) {
    const auto equals = assignment.find('=');
    if (equals == std::string::npos || equals == 0)
      throw std::invalid_argument("--workload " + assignment + ": expected KEY=VALUE");
    spec.workload[assignment.substr(0, equals)] = assignment.substr(equals + 1);
  }
}

harness::RunOptions run_options(const harness::BenchmarkSpec& spec, const RunArgs& args,
                                const Context& context, std::optional<harness::NetworkLink>& link) {
  harness::RunOptions options;
  set_input_options(options, args);
  set_graph_options(options, spec, args, context, link);
  set_measurement_options(options, spec, args);
  return options;
}

}  // namespace robotperf::cli
