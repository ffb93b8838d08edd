// The transport interface: what the node runtime needs from a middleware.
//
// Publishers hand over immutable, shared messages; a transport may pass the
// pointer on unchanged (intra) or serialize it (DDS). Subscriptions follow the
// rmw model: the transport calls `on_ready` from any thread when data arrives,
// and the executor later `take`s it on its own thread.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "robotperf/msgs/type_support.hpp"
#include "robotperf/rmw/security.hpp"

namespace robotperf::rmw {

using MessagePtr = std::shared_ptr<const void>;

enum class Reliability { kReliable, kBestEffort };
enum class Durability { kVolatile, kTransientLocal };
enum class History { kKeepLast, kKeepAll };

struct QoS {
  History history = History::kKeepLast;
  std::size_t depth = 10;
  Reliability reliability = Reliability::kReliable;
  Durability durability = Durability::kVolatile;

  // ROS 2 `rmw_qos_profile_default`: KEEP_LAST 10, RELIABLE, VOLATILE.
  static QoS ros_default() { return QoS{}; }
  // ROS 2 `rmw_qos_profile_sensor_data`: KEEP_LAST 5, BEST_EFFORT, VOLATILE.
  static QoS sensor_data() {
    return QoS{History::kKeepLast, 5, Reliability::kBestEffort, Durability::kVolatile};
  }
  // Parses "default" or "sensor_data"; throws std::invalid_argument otherwise.
  static QoS from_profile_name(const std::string& name);

  friend bool operator==(const QoS&, const QoS&) = default;
};

// Why a publisher offering `offered` does not match a subscription requesting `requested`, by DDS's
// requested-versus-offered rules, which every transport follows ("a reliable subscription needs a
// reliable publisher"); empty when they match. History and depth never keep a pair apart.
std::string qos_incompatibility(const QoS& offered, const QoS& requested);

// "reliable" / "best_effort", "transient_local" / "volatile": as ROS 2 names them.
std::string to_string(Reliability reliability);
std::string to_string(Durability durability);
// "reliable, volatile, keep_last 10"
std::string to_string(const QoS& qos);

// The ROS 2 release whose graph conventions the DDS transports follow (docs/design.md §2): Humble
// announces 24-byte GIDs on ros_discovery_info and no type hashes; Iron and later 16-byte GIDs
// and each endpoint's type hash ("typehash=RIHS01_...;" in its USER_DATA).
enum class RosDistro { kHumble, kIron, kJazzy };
// "humble", "iron" or "jazzy"; throws std::invalid_argument naming the choices.
RosDistro ros_distro_from_name(const std::string& name);
std::string to_string(RosDistro distro);

// The ROS 2 node an endpoint belongs to, announced on ros_discovery_info as rmw does, so that
// `ros2 node list` and `ros2 node info` show it. An empty name: an endpoint of no node.
struct NodeName {
  std::string name;
  std::string namespace_ = "/";
};

// A node name as a graph names it, split as rcl does: "relay" is node relay in "/", "ns/relay"
// and "/ns/relay" node relay in "/ns". Each part: letters, digits and '_', not starting with a
// digit; the name at most 255 characters. Throws std::invalid_argument (one line, saying what is
// wrong) for any other.
NodeName parse_node_name(std::string_view full_name);

// A DDS participant's GUID prefix.
using ParticipantId = std::array<uint8_t, 12>;
// An endpoint's (or participant's) GUID, which rmw uses as its GID.
using Gid = std::array<uint8_t, 16>;

// An endpoint another participant announced.
struct PeerEndpoint {
  Gid gid{};
  bool writer = false;
  std::string topic;     // the ROS name ("rt/" dropped), or the DDS name of a DDS-only topic
  std::string dds_type;  // "sensor_msgs::msg::dds_::Image_"
  // What discovery carries of its QoS: history and depth are not announced, so `qos.history`
  // and `qos.depth` are left at their defaults.
  QoS qos;
  std::string type_hash;  // "RIHS01_..." from its USER_DATA; empty when it announces none
};

// A ROS 2 node of another participant, as that participant announces it on ros_discovery_info.
struct PeerNode {
  std::string namespace_;
  std::string name;
  std::vector<Gid> readers;
  std::vector<Gid> writers;

  // "/ns/name", as `ros2 node list` prints it.
  std::string path() const { return (namespace_ == "/" ? "" : namespace_) + "/" + name; }
};

// Another participant a transport discovered on its domain.
struct PeerParticipant {
  ParticipantId id{};
  std::string name;
  std::string user_data;  // its USER_DATA QoS, as text
  // Where it runs: its unicast IP addresses, or "this host (shared memory)".
  std::vector<std::string> addresses;
  std::set<std::string> topics;  // the ROS names of its endpoints seen so far
  std::vector<PeerEndpoint> endpoints;
  // Its ROS 2 nodes, from its latest ros_discovery_info sample (none for a participant that
  // publishes none, as plain DDS applications).
  std::vector<PeerNode> nodes;
};

// The value of `key` in USER_DATA text of "key=value;" pairs ("enclave=/;typehash=...;");
// empty when absent.
std::string user_data_value(std::string_view user_data, std::string_view key);

// "0f1e...": the 24 hex digits of a participant id.
std::string to_hex(const ParticipantId& id);
// "01.0f.ba...": a GID as `ros2 topic info -v` prints it.
std::string to_text(const Gid& gid);

struct MessageInfo {
  // DDS's source timestamp on every transport: the publication time on the sender, wall clock
  // (CLOCK_REALTIME) ns. It pairs a take with its publish; latencies use the monotonic clock.
  int64_t source_timestamp_ns = 0;
  int64_t reception_timestamp_ns = 0;  // arrival at the transport on the receiver (wall clock)
  bool from_intra_process = false;
  // The DDS participant that wrote it (its GUID prefix); all zero where the transport has no
  // participants (intra).
  ParticipantId sender{};
};

// Errors a transport reports to the user (bad topic, type clash, DDS failure).
class TransportError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class PublisherHandle {
 public:
  virtual ~PublisherHandle() = default;
  virtual void publish(MessagePtr msg) = 0;
  // Subscriptions currently matched (discovered and compatible).
  virtual std::size_t matched_subscriptions() const = 0;
};

class SubscriptionHandle {
 public:
  virtual ~SubscriptionHandle() = default;
  // The oldest pending message, or nullptr when none is pending.
  virtual MessagePtr take(MessageInfo* info) = 0;
  virtual std::size_t matched_publishers() const = 0;
};

class Transport {
 public:
  virtual ~Transport() = default;
  virtual std::string name() const = 0;
  // `topic` is the ROS name, e.g. "/camera/image_raw"; the endpoint belongs to `node`.
  virtual std::unique_ptr<PublisherHandle> create_publisher(const std::string& topic,
                                                            const msgs::TypeSupport& type,
                                                            const QoS& qos,
                                                            const NodeName& node) = 0;
  // `on_ready` may be called from any thread, possibly once for several messages.
  virtual std::unique_ptr<SubscriptionHandle> create_subscription(const std::string& topic,
                                                                  const msgs::TypeSupport& type,
                                                                  const QoS& qos,
                                                                  std::function<void()> on_ready,
                                                                  const NodeName& node) = 0;
  // Endpoints of no ROS 2 node.
  std::unique_ptr<PublisherHandle> create_publisher(const std::string& topic,
                                                    const msgs::TypeSupport& type, const QoS& qos) {
    return create_publisher(topic, type, qos, NodeName{});
  }
  std::unique_ptr<SubscriptionHandle> create_subscription(const std::string& topic,
                                                          const msgs::TypeSupport& type,
                                                          const QoS& qos,
                                                          std::function<void()> on_ready) {
    return create_subscription(topic, type, qos, std::move(on_ready), NodeName{});
  }
  // The other participants discovered on the domain since the transport started, including
  // those that have left since (none for transports without discovery).
  virtual std::vector<PeerParticipant> peers() const { return {}; }
  // This transport's own participant (all zero for transports without participants).
  virtual ParticipantId participant() const { return {}; }
};

struct TransportOptions {
  TransportOptions() = default;
  explicit(false) TransportOptions(int domain, std::string participant_user_data = {})
      : domain_id(domain), user_data(std::move(participant_user_data)) {}

  int domain_id = 0;  // DDS domain; ROS_DOMAIN_ID when set
  // The participant's USER_DATA, which every other participant on the domain sees: "key=value;"
  // pairs as ROS 2 uses it. robotperf marks the participants of one run with it. The DDS
  // transports put ROS 2's "enclave=...;" before it.
  std::string user_data;
  // DDS Security for the DDS transports' participant (authentication, access control,
  // encryption), from one enclave of a keystore; empty: unsecured. Ignored by intra.
  std::optional<SecurityFiles> security;
  // Whose conventions the DDS transports' graph announcements follow. Ignored by intra.
  RosDistro ros_distro = RosDistro::kJazzy;
};

// "intra", "fastdds" or "cyclonedds"; throws std::invalid_argument naming the valid choices.
std::unique_ptr<Transport> make_transport(const std::string& name,
                                          const TransportOptions& options = {});

// The largest DDS domain id whose RTPS ports still fit in 16 bits.
inline constexpr int kMaxDomainId = 232;

// A domain id as written: decimal digits only (no sign, space or 0x), 0 to kMaxDomainId; nullopt
// otherwise. The one reading of ROS_DOMAIN_ID and of every --domain.
std::optional<int> parse_domain_id(std::string_view text);

// Reads ROS_DOMAIN_ID (0 when unset); throws std::invalid_argument when malformed.
int domain_id_from_environment();

// ROS_STATIC_PEERS as ROS 2 reads it: the IPv4 addresses, separated by ';', that the DDS
// transports' participants also announce themselves to by unicast, besides multicast discovery:
// for networks that carry no multicast (a VPN tunnel, a router between subnets). Empty when unset;
// throws std::invalid_argument naming an entry that is not an IPv4 address.
std::vector<std::string> static_peers_from_environment();

// A DDS domain on which `transport` discovers no other participant within `listen_s`: domains
// 1 to 230 tried in a random order (0, ROS 2's default, is left to robots; 231 and 232 to no one,
// as DDS Security cannot name them), each reserved first
// among the robotperf processes of this machine (a lock on a file in /tmp), so that those looking
// at the same time never pick the same one; the reservation lasts until this process ends.
// Transports without discovery (intra) get 0. Throws TransportError when none of the tries is
// quiet.
int find_quiet_domain(const std::string& transport, double listen_s = 3.5);

// The domain this process reserved for its tests or benchmarks, as find_quiet_domain reserves
// one: the first call reserves one of 1 to 230 (starting from a place given by the process id),
// later calls return the same, so that no two tests or benchmarks running at once share one.
// Throws TransportError when all are held.
int reserved_domain();

// Monotonic time (CLOCK_MONOTONIC) in nanoseconds: the one clock of docs/design.md §3.2.
int64_t steady_now_ns();
// Wall-clock time (CLOCK_REALTIME) in nanoseconds since the epoch: DDS's source timestamps, which
// ros2:rmw_publish and ros2:rmw_take record on every transport.
int64_t wall_now_ns();

// "/camera/image_raw" -> "rt/camera/image_raw"; validates the ROS name.
std::string dds_topic_name(const std::string& ros_topic);

}  // namespace robotperf::rmw
