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

void PeerTable::add_topic(const ParticipantId& id, std::string dds_topic) {
  if (dds_topic.starts_with("rt/")) dds_topic.erase(0, 2);
  std::lock_guard lock(mutex_);
  peer_locked(id).topics.insert(std::move(dds_topic));
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
