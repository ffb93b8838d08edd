// Private to the rmw library: the other participants a DDS transport has discovered, kept alike
// for every vendor. Discovery reports from the vendor's threads; peers() reads from any.
#pragma once

#include <functional>
#include <map>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "robotperf/rmw/transport.hpp"

namespace robotperf::rmw {

class PeerTable {
 public:
  // A participant announced itself (or changed its QoS); `describe` fills in what the vendor's
  // discovery data tells of it (name, USER_DATA, addresses). A participant known only by its key
  // (one that left before it was read) is announced without it.
  void announce(const ParticipantId& id,
                const std::function<void(PeerParticipant&)>& describe = nullptr);
  // One of its endpoints, named by its DDS topic in `endpoint.topic`: "rt/<name>" is listed as
  // the ROS name, other (DDS-only) topics as DDS names them. Its topic stays listed in the peer's
  // `topics` after remove_endpoint.
  void add_endpoint(const ParticipantId& id, PeerEndpoint endpoint);
  void remove_endpoint(const ParticipantId& id, const Gid& gid);
  // Its ROS 2 nodes, from a ros_discovery_info sample it wrote.
  void set_nodes(const ParticipantId& id, std::vector<PeerNode> nodes);
  // Those announced so far, including those that have left since, but `self` (vendors report a
  // participant's own endpoints too).
  std::vector<PeerParticipant> peers(const ParticipantId& self) const;

 private:
  PeerParticipant& peer_locked(const ParticipantId& id);

  mutable std::mutex mutex_;
  // Endpoints may be reported before their participant: only announced participants are peers.
  std::map<ParticipantId, PeerParticipant> peers_;
  std::set<ParticipantId> announced_;
};

}  // namespace robotperf::rmw
