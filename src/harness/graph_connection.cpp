#include "graph_connection.hpp"

#include <algorithm>
#include <chrono>
#include <set>
#include <thread>

#include "robotperf/harness/run.hpp"
#include "robotperf/harness/suggestions.hpp"
#include "robotperf/msgs/known_types.hpp"

namespace robotperf::harness {

Wiring wiring_of(const BenchmarkSpec& spec) {
  Wiring w;
  for (const auto& in : spec.inputs) w.published.insert(in.topic);
  w.subscribed.insert(spec.output.topic);
  for (const auto& out : spec.more_outputs) w.subscribed.insert(out.topic);
  if (spec.external()) {
    // An external graph's endpoints are not declared: it reads every input and writes the outputs.
    for (const auto& in : spec.inputs) w.subscribed.insert(in.topic);
    w.published.insert(spec.output.topic);
    for (const auto& out : spec.more_outputs) w.published.insert(out.topic);
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

namespace {

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

}  // namespace

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
    // The graph may be running with its topics named otherwise: say which it has, of the kind
    // that would match ours, and the nearest name when one looks like a typo of ours.
    std::set<std::string> theirs;
    for (const auto& peer : peers) {
      for (const auto& e : peer.endpoints) {
        if (e.writer != ours.is_publisher && e.topic.starts_with('/'))
          theirs.insert(e.topic + " [" + msgs::ros_type_name(e.dds_type) + "]");
      }
    }
    std::string line =
        "no other participant on domain " + std::to_string(domain_id) + " has an endpoint on it";
    if (theirs.empty()) return line + " (is the graph running, with this domain and RMW?)";
    std::vector<std::string> names;
    for (const auto& t : theirs) names.push_back(t.substr(0, t.find(" [")));
    line += std::string("; the others ") + (ours.is_publisher ? "subscribe " : "publish ");
    constexpr std::size_t kShown = 8;
    std::size_t shown = 0;
    for (const auto& t : theirs) {
      if (shown == kShown) break;
      line += (shown++ == 0 ? "" : ", ") + t;
    }
    if (theirs.size() > kShown) line += " and " + std::to_string(theirs.size() - kShown) + " more";
    return line + did_you_mean(ours.topic, names);
  }
  return seen + " (ours: " + rmw::to_string(our_qos) + ")";
}

bool wait_connected(const std::vector<std::shared_ptr<graph::Node>>& nodes, const Wiring& w,
                    int64_t deadline_ns, const std::function<bool()>& abandon,
                    const std::function<std::string(const graph::EndpointStatus&)>& about_topic) {
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

}  // namespace robotperf::harness
