// Private to the harness: whether a graph is connected, for the runner's connect stage and for a
// per-node child, and what is known of an endpoint that has no peer.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "robotperf/graph/node.hpp"
#include "robotperf/harness/benchmark_spec.hpp"
#include "robotperf/rmw/transport.hpp"

namespace robotperf::harness {

struct Wiring {
  std::set<std::string> published;   // topics someone in the whole graph publishes
  std::set<std::string> subscribed;  // topics someone in the whole graph subscribes
};

Wiring wiring_of(const BenchmarkSpec& spec);

// What the other participants of the domain have on `ours.topic`: each opposite endpoint with
// its type, its QoS and why it does not match ours.
std::string others_on_topic(const std::vector<rmw::PeerParticipant>& peers,
                            const graph::EndpointStatus& ours, const rmw::QoS& our_qos,
                            int domain_id);

// Polls matched counts: discovery offers no single event for "graph complete".
// Returns false as soon as `abandon` returns true; throws GraphNotConnected at the deadline, with
// a line for each endpoint without its peer (and what `about_topic` knows of others on it).
bool wait_connected(
    const std::vector<std::shared_ptr<graph::Node>>& nodes, const Wiring& w, int64_t deadline_ns,
    const std::function<bool()>& abandon = [] { return false; },
    const std::function<std::string(const graph::EndpointStatus&)>& about_topic = {});

}  // namespace robotperf::harness
