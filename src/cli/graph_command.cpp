#include "graph_command.hpp"

#include <algorithm>
#include <chrono>
#include <cstring>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <stdexcept>
#include <thread>
#include <tuple>
#include <vector>

#include "robotperf/msgs/type_support.hpp"
#include "robotperf/rmw/transport.hpp"

namespace robotperf::cli {
namespace {

using nlohmann::json;

// ROS names are fully qualified; what is not (ros_discovery_info, services' rq/ and rr/ topics)
// stays in the DDS namespace.
bool is_ros_topic(const std::string& topic) {
  return topic.starts_with('/');
}

json endpoint_json(const rmw::PeerEndpoint& e) {
  return {{"topic", e.topic},
          {"type", msgs::ros_type_name(e.dds_type)},
          {"kind", e.writer ? "publisher" : "subscription"},
          {"reliability", rmw::to_string(e.qos.reliability)},
          {"durability", rmw::to_string(e.qos.durability)},
          {"type_hash", e.type_hash},
          {"gid", rmw::to_text(e.gid)}};
}

// A service's DDS topic: "rq/<service>Request" or "rr/<service>Reply" -> (service, is request).
std::optional<std::pair<std::string, bool>> service_of(const std::string& topic) {
  for (const auto& [prefix, suffix, request] :
       {std::tuple{"rq", "Request", true}, std::tuple{"rr", "Reply", false}}) {
    const std::string head = std::string(prefix) + "/";
    if (topic.starts_with(head) && topic.ends_with(suffix) &&
        topic.size() > head.size() + std::strlen(suffix)) {
      return std::pair{
          "/" + topic.substr(head.size(), topic.size() - head.size() - std::strlen(suffix)),
          request};
    }
  }
  return std::nullopt;
}

// A node's endpoints with its services folded, as rmw makes them: a server reads rq/<s>Request
// and writes rr/<s>Reply, a client the other way round. Returns (endpoints, services); an rq/ or
// rr/ endpoint without its pair stays an endpoint.
std::pair<json, json> fold_services(const std::vector<const rmw::PeerEndpoint*>& own) {
  // (service, server?) -> (request endpoint, reply endpoint)
  std::map<std::pair<std::string, bool>,
           std::pair<const rmw::PeerEndpoint*, const rmw::PeerEndpoint*>>
      pairs;
  for (const auto* e : own) {
    auto s = service_of(e->topic);
    if (!s) continue;
    const bool server = s->second ? !e->writer : e->writer;
    auto& [request, reply] = pairs[{s->first, server}];
    (s->second ? request : reply) = e;
  }
  std::set<const rmw::PeerEndpoint*> folded;
  json services = json::array();
  for (const auto& [key, ends] : pairs) {
    if (ends.first == nullptr || ends.second == nullptr) continue;
    folded.insert(ends.first);
    folded.insert(ends.second);
    std::string type = msgs::ros_type_name(ends.first->dds_type);
    if (type.ends_with("_Request")) type.resize(type.size() - std::strlen("_Request"));
    services.push_back(
        {{"service", key.first}, {"type", type}, {"kind", key.second ? "server" : "client"}});
  }
  json endpoints = json::array();
  for (const auto* e : own) {
    if (!folded.contains(e)) endpoints.push_back(endpoint_json(*e));
  }
  return {endpoints, services};
}

// What every participant of the domain shows: its nodes with their endpoints, and the endpoints
// no node claims (plain DDS applications, or ROS 2 participants whose announcement is not read).
json graph_json(const std::vector<rmw::PeerParticipant>& peers) {
  json participants = json::array();
  std::map<std::string, std::pair<std::set<std::string>, std::array<int, 2>>> topics, services;
  for (const auto& peer : peers) {
    if (peer.endpoints.empty() && peer.nodes.empty()) continue;  // left, or only discovering
    std::set<rmw::Gid> claimed;
    json nodes = json::array();
    for (const auto& node : peer.nodes) {
      std::vector<const rmw::PeerEndpoint*> own;
      for (const auto* gids : {&node.writers, &node.readers}) {
        for (const auto& gid : *gids) {
          claimed.insert(gid);
          auto e = std::ranges::find(peer.endpoints, gid, &rmw::PeerEndpoint::gid);
          if (e != peer.endpoints.end()) own.push_back(&*e);
        }
      }
      auto [endpoints, node_services] = fold_services(own);
      for (const auto& service : node_services) {
        auto& [types, counts] = services[service["service"].get<std::string>()];
        types.insert(service["type"].get<std::string>());
        ++counts[service["kind"] == "server" ? 0 : 1];
      }
      nodes.push_back(
          {{"name", node.path()}, {"endpoints", endpoints}, {"services", node_services}});
    }
    json unclaimed = json::array();
    for (const auto& e : peer.endpoints) {
      if (is_ros_topic(e.topic)) {
        auto& [types, counts] = topics[e.topic];
        types.insert(msgs::ros_type_name(e.dds_type));
        ++counts[e.writer ? 0 : 1];
      }
      if (!claimed.contains(e.gid) && e.topic != "ros_discovery_info") {
        unclaimed.push_back(endpoint_json(e));
      }
    }
    participants.push_back({{"id", rmw::to_hex(peer.id)},
                            {"name", peer.name},
                            {"enclave", rmw::user_data_value(peer.user_data, "enclave")},
                            {"addresses", peer.addresses},
                            {"nodes", nodes},
                            {"endpoints_of_no_node", unclaimed}});
  }
  auto listed = [](const auto& named, const char* first, const char* second) {
    json out = json::array();
    for (const auto& [name, entry] : named) {
      out.push_back({{"name", name},
                     {"types", entry.first},
                     {first, entry.second[0]},
                     {second, entry.second[1]}});
    }
    return out;
  };
  return {{"participants", participants},
          {"topics", listed(topics, "publishers", "subscriptions")},
          {"services", listed(services, "servers", "clients")}};
}

std::string plural(int n, const std::string& word) {
  return std::to_string(n) + " " + word + (n == 1 ? "" : "s");
}

void print_endpoint(std::ostream& out, const json& e, const std::string& indent) {
  out << indent << (e["kind"] == "publisher" ? "publishes   " : "subscribes  ")
      << e["topic"].get<std::string>() << "  [" << e["type"].get<std::string>() << "]  "
      << e["reliability"].get<std::string>() << ", " << e["durability"].get<std::string>();
  if (!e["type_hash"].get<std::string>().empty()) out << "  " << e["type_hash"].get<std::string>();
  out << "\n";
}

}  // namespace

int ros_graph(const GraphOptions& options, std::ostream& out) {
  if (options.rmw == "intra") {
    throw std::invalid_argument("graph reads a DDS domain: use --rmw fastdds or cyclonedds");
  }
  rmw::TransportOptions t;
  t.domain_id = options.domain.value_or(rmw::domain_id_from_environment());
  auto transport = rmw::make_transport(options.rmw, t);
  // Discovery has no end: what is listed is what announced itself within the window.
  std::this_thread::sleep_for(std::chrono::duration<double>(options.listen_s));
  print_graph(transport->peers(), options, t.domain_id, out);
  return 0;
}

void print_graph(const std::vector<rmw::PeerParticipant>& peers, const GraphOptions& options,
                 int domain_id, std::ostream& out) {
  const json graph = graph_json(peers);
  if (options.json) {
    json doc = graph;
    doc["domain_id"] = domain_id;
    doc["rmw"] = options.rmw;
    doc["listened_s"] = options.listen_s;
    // Names come from any program on the domain: bytes that are not UTF-8 are replaced.
    out << doc.dump(2, ' ', false, json::error_handler_t::replace) << "\n";
    return;
  }
  int node_count = 0;
  for (const auto& p : graph["participants"]) node_count += static_cast<int>(p["nodes"].size());
  out << "ROS 2 graph on domain " << domain_id << " (" << options.rmw << ", listened "
      << options.listen_s
      << " s): " << plural(static_cast<int>(graph["participants"].size()), "participant") << ", "
      << plural(node_count, "node") << ", "
      << plural(static_cast<int>(graph["topics"].size()), "topic") << ", "
      << plural(static_cast<int>(graph["services"].size()), "service") << "\n";
  out << "\nnodes\n";
  for (const auto& p : graph["participants"]) {
    for (const auto& node : p["nodes"]) {
      out << "  " << node["name"].get<std::string>() << "   (participant "
          << p["id"].get<std::string>() << ", enclave " << p["enclave"].get<std::string>() << ")\n";
      for (const auto& e : node["endpoints"]) print_endpoint(out, e, "    ");
      for (const auto& service : node["services"]) {
        out << "    " << (service["kind"] == "server" ? "serves      " : "calls       ")
            << service["service"].get<std::string>() << "  [" << service["type"].get<std::string>()
            << "]\n";
      }
    }
  }
  // Topics and services alike: a name, its types, and who is on each side.
  auto list = [&](const json& entries, const char* sides[2], const char* words[2]) {
    for (const auto& e : entries) {
      std::string types;
      for (const auto& type : e["types"])
        types += (types.empty() ? "" : ", ") + type.get<std::string>();
      out << "  " << e["name"].get<std::string>() << "  [" << types << "]  "
          << plural(e[sides[0]].get<int>(), words[0]) << ", "
          << plural(e[sides[1]].get<int>(), words[1]) << "\n";
    }
  };
  const char* topic_sides[2] = {"publishers", "subscriptions"};
  const char* topic_words[2] = {"publisher", "subscription"};
  out << "\ntopics\n";
  list(graph["topics"], topic_sides, topic_words);
  const char* service_sides[2] = {"servers", "clients"};
  const char* service_words[2] = {"server", "client"};
  if (!graph["services"].empty()) out << "\nservices\n";
  list(graph["services"], service_sides, service_words);
  bool header = false;
  for (const auto& p : graph["participants"]) {
    if (p["endpoints_of_no_node"].empty()) continue;
    if (!header) out << "\nDDS endpoints of no ROS 2 node\n";
    header = true;
    out << "  participant " << p["id"].get<std::string>() << " \"" << p["name"].get<std::string>()
        << "\"\n";
    for (const auto& e : p["endpoints_of_no_node"]) print_endpoint(out, e, "    ");
  }
}

}  // namespace robotperf::cli
