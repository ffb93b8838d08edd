#include "peer_table.hpp"

#include <utility>

namespace robotperf::rmw {

void PeerTable::announce(const ParticipantId& id,
                         const std::function<void(PeerParticipant&)>& describe) {
  std::lock_guard lock(mutex_);
  announced_.insert(id);
  PeerParticipant& peer = peer_locked(id);
  if (describe) describe(peer);
}

void PeerTable::add_endpoint(const ParticipantId& id, PeerEndpoint endpoint) {
  if (endpoint.topic.starts_with("rt/")) endpoint.topic.erase(0, 2);
  std::lock_guard lock(mutex_);
  PeerParticipant& peer = peer_locked(id);
  peer.topics.insert(endpoint.topic);
  // A changed QoS is announced again under the same GID.
  std::erase_if(peer.endpoints, [&](const PeerEndpoint& e) { return e.gid == endpoint.gid; });
  peer.endpoints.push_back(std::move(endpoint));
}

void PeerTable::remove_endpoint(const ParticipantId& id, const Gid& gid) {
  std::lock_guard lock(mutex_);
  std::erase_if(peer_locked(id).endpoints, [&](const PeerEndpoint& e) { return e.gid == gid; });
}

void PeerTable::set_nodes(const ParticipantId& id, std::vector<PeerNode> nodes) {
  std::lock_guard lock(mutex_);
  peer_locked(id).nodes = std::move(nodes);
}

std::vector<PeerParticipant> PeerTable::peers(const ParticipantId& self) const {
  std::lock_guard lock(mutex_);
  std::vector<PeerParticipant> out;
  for (const auto& [id, peer] : peers_) {
    if (id != self && announced_.contains(id)) out.push_back(peer);
  }
  return out;
}

PeerParticipant& PeerTable::peer_locked(const ParticipantId& id) {
  PeerParticipant& peer = peers_[id];
  peer.id = id;
  return peer;
}

}  // namespace robotperf::rmw
