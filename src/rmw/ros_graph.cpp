#include "ros_graph.hpp"

#include <algorithm>
#include <utility>

#include "robotperf/msgs/cdr.hpp"
#include "robotperf/msgs/type_hash.hpp"

namespace robotperf::rmw {
namespace {

std::size_t gid_size(RosDistro distro) {
  return distro == RosDistro::kHumble ? 24 : 16;
}

void write_gid(msgs::CdrWriter& w, const Gid& gid, std::size_t size) {
  for (std::size_t i = 0; i < size; ++i) w(i < gid.size() ? gid[i] : uint8_t{0});
}

Gid read_gid(msgs::CdrReader& r, std::size_t size) {
  Gid gid{};
  for (std::size_t i = 0; i < size; ++i) {
    uint8_t b = 0;
    r(b);
    if (i < gid.size()) gid[i] = b;
  }
  return gid;
}

std::vector<Gid> read_gids(msgs::CdrReader& r, std::size_t size) {
  uint32_t n = 0;
  r(n);
  if (n > r.remaining() / size) throw msgs::CdrError("GID sequence exceeds the sample");
  std::vector<Gid> gids;
  for (uint32_t i = 0; i < n; ++i) gids.push_back(read_gid(r, size));
  return gids;
}

// The sample read with GIDs of `size` bytes, when that layout accounts for all of it (but the
// trailing padding of at most 3 bytes some writers add).
std::optional<ParticipantEntities> decode_as(std::span<const uint8_t> cdr, std::size_t size) {
  try {
    msgs::CdrReader r(cdr);
    ParticipantEntities out;
    out.participant = read_gid(r, size);
    uint32_t n = 0;
    r(n);
    if (n > r.remaining()) return std::nullopt;
    for (uint32_t i = 0; i < n; ++i) {
      PeerNode node;
      r(node.namespace_);
      r(node.name);
      node.readers = read_gids(r, size);
      node.writers = read_gids(r, size);
      out.nodes.push_back(std::move(node));
    }
    if (r.remaining() > 3) return std::nullopt;
    return out;
  } catch (const msgs::CdrError&) {
    return std::nullopt;
  }
}

}  // namespace

QoS ros_discovery_writer_qos() {
  return QoS{History::kKeepLast, 1, Reliability::kReliable, Durability::kTransientLocal};
}

QoS ros_discovery_reader_qos() {
  return QoS{History::kKeepAll, 0, Reliability::kReliable, Durability::kTransientLocal};
}

std::string endpoint_user_data(const msgs::TypeSupport& type, RosDistro distro) {
  if (distro == RosDistro::kHumble) return {};
  const auto hash = msgs::builtin_type_hash(type.ros_type);
  return hash ? "typehash=" + *hash + ";" : std::string();
}

std::vector<uint8_t> encode_participant_entities(const Gid& participant,
                                                 const std::vector<PeerNode>& nodes,
                                                 RosDistro distro) {
  const std::size_t size = gid_size(distro);
  std::vector<uint8_t> out;
  msgs::CdrWriter w(out);
  write_gid(w, participant, size);
  w(static_cast<uint32_t>(nodes.size()));
  for (const PeerNode& node : nodes) {
    w(node.namespace_);
    w(node.name);
    for (const auto* gids : {&node.readers, &node.writers}) {
      w(static_cast<uint32_t>(gids->size()));
      for (const Gid& gid : *gids) write_gid(w, gid, size);
    }
  }
  return out;
}

std::optional<ParticipantEntities> decode_participant_entities(std::span<const uint8_t> cdr) {
  if (auto iron = decode_as(cdr, 16)) return iron;
  return decode_as(cdr, 24);
}

void LocalNodes::set_publisher(
    std::function<void(std::shared_ptr<const msgs::SerializedMessage>)> publish) {
  std::lock_guard lock(mutex_);
  publish_ = std::move(publish);
  publish_locked();
}

void LocalNodes::add(const NodeName& node, const Gid& endpoint, bool writer) {
  std::lock_guard lock(mutex_);
  auto it = std::ranges::find_if(nodes_, [&](const PeerNode& n) {
    return n.name == node.name && n.namespace_ == node.namespace_;
  });
  if (it == nodes_.end()) {
    nodes_.push_back(PeerNode{node.namespace_, node.name, {}, {}});
    it = std::prev(nodes_.end());
  }
  (writer ? it->writers : it->readers).push_back(endpoint);
  publish_locked();
}

void LocalNodes::remove(const Gid& endpoint) {
  std::lock_guard lock(mutex_);
  for (PeerNode& node : nodes_) {
    std::erase(node.readers, endpoint);
    std::erase(node.writers, endpoint);
  }
  // A node whose endpoints are all gone is gone too (robotperf's nodes have endpoints).
  std::erase_if(nodes_, [](const PeerNode& n) { return n.readers.empty() && n.writers.empty(); });
  publish_locked();
}

void LocalNodes::publish_locked() {
  if (!publish_) return;
  auto sample = std::make_shared<msgs::SerializedMessage>();
  sample->cdr = encode_participant_entities(participant_, nodes_, distro_);
  // An announcement that fails leaves ROS 2 tools a state behind; the endpoint itself works.
  try {
    publish_(std::move(sample));
  } catch (const TransportError&) {
  }
}

NodeEndpoint::NodeEndpoint(LocalNodes& nodes, const NodeName& node, const Gid& gid, bool writer)
    : gid_(gid) {
  if (node.name.empty()) return;
  nodes.add(node, gid, writer);
  nodes_ = &nodes;
}

NodeEndpoint::~NodeEndpoint() {
  if (nodes_ != nullptr) nodes_->remove(gid_);
}

}  // namespace robotperf::rmw
