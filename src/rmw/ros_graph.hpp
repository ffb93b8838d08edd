// Private to the rmw library: ROS 2's graph announcements on DDS, as rmw_dds_common makes them
// (docs/design.md §2). Each participant publishes on the DDS-only topic ros_discovery_info one
// rmw_dds_common/msg/ParticipantEntitiesInfo sample: its GID and, per ROS 2 node, the GIDs of the
// node's readers and writers. ROS 2 tools name nodes from it; DDS discovery alone has no nodes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "robotperf/msgs/serialized_message.hpp"
#include "robotperf/rmw/transport.hpp"

namespace robotperf::rmw {

inline constexpr const char* kRosDiscoveryTopic = "ros_discovery_info";
inline constexpr const char* kParticipantEntitiesInfoType =
    "rmw_dds_common/msg/ParticipantEntitiesInfo";

// The writer's QoS rmw_dds_common gives it (reliable, transient local, keep last 1), so that a
// participant joining later reads each one's latest state. The reader keeps all it receives until
// it is read, as rmw_fastrtps's does: the topic is keyless, so a KEEP_LAST history would be shared
// by all writers, and a burst of one's announcements would push out another's latest.
QoS ros_discovery_writer_qos();
QoS ros_discovery_reader_qos();

// The endpoint USER_DATA rmw writes from Iron on: "typehash=RIHS01_<hex>;" for a type robotperf
// has the definition of; empty for Humble and for types it does not know.
std::string endpoint_user_data(const msgs::TypeSupport& type, RosDistro distro);

// A ParticipantEntitiesInfo sample as CDR (encapsulation header included), with the GIDs in the
// distribution's layout: 16 bytes from Iron on, Humble's 24 (the GUID, then zeros).
std::vector<uint8_t> encode_participant_entities(const Gid& participant,
                                                 const std::vector<PeerNode>& nodes,
                                                 RosDistro distro);
// Reads one whatever its layout (the sample must be exactly one of them); nullopt when malformed.
struct ParticipantEntities {
  Gid participant{};
  std::vector<PeerNode> nodes;
};
std::optional<ParticipantEntities> decode_participant_entities(std::span<const uint8_t> cdr);

// The nodes of this participant and their endpoints; every change publishes the new sample
// through `publish` (set once the writer exists; changes before then are published then).
class LocalNodes {
 public:
  LocalNodes(const Gid& participant, RosDistro distro)
      : participant_(participant), distro_(distro) {}
  RosDistro distro() const { return distro_; }
  void set_publisher(std::function<void(std::shared_ptr<const msgs::SerializedMessage>)> publish);
  void add(const NodeName& node, const Gid& endpoint, bool writer);
  void remove(const Gid& endpoint);

 private:
  void publish_locked();

  const Gid participant_;
  const RosDistro distro_;
  std::mutex mutex_;
  std::function<void(std::shared_ptr<const msgs::SerializedMessage>)> publish_;
  std::vector<PeerNode> nodes_;  // in the order they appeared, as rmw lists them
};

// An endpoint's entry under its node for as long as it lives (nothing for an endpoint of no node).
class NodeEndpoint {
 public:
  NodeEndpoint(LocalNodes& nodes, const NodeName& node, const Gid& gid, bool writer);
  NodeEndpoint(const NodeEndpoint&) = delete;
  NodeEndpoint& operator=(const NodeEndpoint&) = delete;
  ~NodeEndpoint();

 private:
  LocalNodes* nodes_ = nullptr;
  Gid gid_{};
};

}  // namespace robotperf::rmw
