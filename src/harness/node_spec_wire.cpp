#include "robotperf/harness/node_spec_wire.hpp"

#include <cstddef>
#include <nlohmann/json.hpp>
#include <stdexcept>

namespace robotperf::harness {
namespace {

constexpr char kHexDigits[] = "0123456789abcdef";

int hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return -1;
}

nlohmann::json qos_to_json(const rmw::QoS& qos) {
  return {{"history", static_cast<int>(qos.history)},
          {"depth", qos.depth},
          {"reliability", static_cast<int>(qos.reliability)},
          {"durability", static_cast<int>(qos.durability)}};
}

rmw::QoS qos_from_json(const nlohmann::json& j) {
  rmw::QoS qos;
  qos.history = static_cast<rmw::History>(j.at("history").get<int>());
  qos.depth = j.at("depth").get<std::size_t>();
  qos.reliability = static_cast<rmw::Reliability>(j.at("reliability").get<int>());
  qos.durability = static_cast<rmw::Durability>(j.at("durability").get<int>());
  return qos;
}

nlohmann::json node_to_json(const NodeSpec& node) {
  return {{"name", node.name},
          {"kernel", node.kernel},
          {"backend", node.backend},
          {"host", node.host},
          {"parameters", node.parameters},
          {"topics", node.topics},
          {"qos", qos_to_json(node.qos)},
          {"device_resident_outputs", node.device_resident_outputs}};
}

NodeSpec node_from_json(const nlohmann::json& j) {
  NodeSpec node;
  node.name = j.at("name").get<std::string>();
  node.kernel = j.at("kernel").get<std::string>();
  node.backend = j.at("backend").get<std::string>();
  node.host = j.at("host").get<std::string>();
  node.parameters = j.at("parameters").get<std::map<std::string, std::string>>();
  node.topics = j.at("topics").get<std::map<std::string, std::string>>();
  node.qos = qos_from_json(j.at("qos"));
  node.device_resident_outputs = j.at("device_resident_outputs").get<std::set<std::string>>();
  return node;
}

}  // namespace

std::string encode_nodes(const std::vector<NodeSpec>& nodes) {
  nlohmann::json j = nlohmann::json::array();
  for (const auto& node : nodes) j.push_back(node_to_json(node));
  std::string encoded;
  for (const unsigned char c : j.dump()) {
    encoded += kHexDigits[c >> 4];
    encoded += kHexDigits[c & 0xf];
  }
  return encoded;
}

void use_encoded_nodes(BenchmarkSpec& spec, const std::string& encoded) {
  if (encoded.size() % 2 != 0)
    throw std::invalid_argument("--nodes: an odd number of hexadecimal digits");
  std::string text;
  for (std::size_t i = 0; i < encoded.size(); i += 2) {
    const int high = hex_value(encoded[i]), low = hex_value(encoded[i + 1]);
    if (high < 0 || low < 0) throw std::invalid_argument("--nodes: not hexadecimal digits");
    text += static_cast<char>(high * 16 + low);
  }
  std::vector<NodeSpec> nodes;
  try {
    for (const auto& j : nlohmann::json::parse(text)) nodes.push_back(node_from_json(j));
  } catch (const nlohmann::json::exception& e) {
    throw std::invalid_argument(std::string("--nodes: not the nodes of a run: ") + e.what());
  }
  // The runner's nodes are the package's, resolved: a package that differs is not the runner's.
  if (nodes.size() != spec.nodes.size())
    throw std::invalid_argument("--nodes: the runner's graph has other nodes than " +
                                spec.dir.string());
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    if (nodes[i].name != spec.nodes[i].name)
      throw std::invalid_argument("--nodes: the runner's graph has other nodes than " +
                                  spec.dir.string());
  }
  spec.nodes = std::move(nodes);
}

}  // namespace robotperf::harness
