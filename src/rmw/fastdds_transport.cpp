// The Fast DDS transport: ROS 2-compatible DDS endpoints (docs/design.md §2).
//
// Each message type is registered under its ROS 2 DDS type name with a keyless
// TopicDataType that writes the plain-CDR bytes of each endpoint's TypeSupport
// (encapsulation header included) straight into the DDS payload, and announces
// no TypeObject, so Fast DDS matches remote endpoints by type name as
// rmw_fastrtps does.
#include "fastdds_transport.hpp"

#include <fastdds/rtps/common/SerializedPayload.h>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastdds/rtps/transport/shared_mem/SharedMemTransportDescriptor.h>
#include <fastrtps/utils/IPLocator.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <exception>
#include <fastdds/dds/core/status/PublicationMatchedStatus.hpp>
#include <fastdds/dds/core/status/SubscriptionMatchedStatus.hpp>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/domain/DomainParticipantListener.hpp>
#include <fastdds/dds/domain/qos/DomainParticipantQos.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/publisher/qos/DataWriterQos.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TopicDataType.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <filesystem>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>

#include "fastdds_participant_qos.hpp"
#include "participant_transport.hpp"
#include "peer_table.hpp"
#include "robotperf/msgs/cdr.hpp"
#include "robotperf/tracing/tracepoints.hpp"

namespace robotperf::rmw {
namespace {

namespace dds = eprosima::fastdds::dds;
using eprosima::fastrtps::rtps::InstanceHandle_t;
using eprosima::fastrtps::rtps::SerializedPayload_t;
using ReturnCode = eprosima::fastrtps::types::ReturnCode_t;

// Payload bytes preallocated per history slot. Message types are unbounded, so
// the pools start here and grow on demand (PREALLOCATED_WITH_REALLOC).
constexpr uint32_t kInitialPayloadSize = 4096;

// Shared memory per participant: room for the fragments of a couple of 1080p
// RGB images (6 MiB each) in flight. tmpfs pages are only used once touched.
constexpr uint32_t kSharedMemorySegmentSize = 16u << 20;

// As the Cyclone DDS transport asks for its sockets.
constexpr uint32_t kUdpReceiveBufferSize = 8u << 20;
constexpr uint32_t kParticipantsPerStaticPeer = 16;
// DDS's (RTPS 2.x) discovery multicast group.
constexpr const char* kDiscoveryMulticastAddress = "239.255.0.1";

// What the transport hands Fast DDS to write, or to take into: a message and the TypeSupport that
// (de)serializes it. Fast DDS keeps one data type per type name and participant, while endpoints of
// one name may hold messages of different layouts (a typed message, or a SerializedMessage's
// bytes): each endpoint brings its own.
struct EndpointSample {
  const msgs::TypeSupport* type;
  void* message;
};

// A message type as Fast DDS sees it: keyless, plain CDR, no TypeObject. Its samples are
// EndpointSamples.
class MessageDataType final : public dds::TopicDataType {
 public:
  // `type`: the TypeSupport of the samples Fast DDS creates itself (createData).
  explicit MessageDataType(const msgs::TypeSupport& type) : type_(type) {
    setName(type.dds_type.c_str());
    m_typeSize = kInitialPayloadSize;
    m_isGetKeyDefined = false;
    auto_fill_type_object(false);
    auto_fill_type_information(false);
  }

  bool serialize(void* data, SerializedPayload_t* payload) override {
    const auto& sample = *static_cast<const EndpointSample*>(data);
    const std::size_t size = sample.type->serialized_size(sample.message);
    // The writer sized the payload with getSerializedSizeProvider; a smaller
    // one means the message exceeds what a 32-bit RTPS length can carry.
    if (size > payload->max_size) return false;
    sample.type->serialize(sample.message, std::span<uint8_t>(payload->data, size));
    payload->length = static_cast<uint32_t>(size);
    payload->encapsulation = CDR_LE;
    return true;
  }

  bool deserialize(SerializedPayload_t* payload, void* data) override {
    const auto& sample = *static_cast<const EndpointSample*>(data);
    // Exceptions must not unwind through Fast DDS: a bad payload drops the sample.
    try {
      sample.type->deserialize(std::span<const uint8_t>(payload->data, payload->length),
                               sample.message);
      return true;
    } catch (const std::exception&) {
      return false;
    }
  }

  std::function<uint32_t()> getSerializedSizeProvider(void* data) override {
    return [data] {
      const auto& sample = *static_cast<const EndpointSample*>(data);
      const std::size_t size = sample.type->serialized_size(sample.message);
      return size > std::numeric_limits<uint32_t>::max() ? 0u : static_cast<uint32_t>(size);
    };
  }

  // Fast DDS only asks for samples when lending them out; the transport takes
  // into its own messages, but the contract still has to hold.
  void* createData() override {
    auto* sample = new OwnedSample;
    sample->owned = type_.create();
    sample->type = &type_;
    sample->message = sample->owned.get();
    return static_cast<EndpointSample*>(sample);
  }
  void deleteData(void* data) override {
    delete static_cast<OwnedSample*>(static_cast<EndpointSample*>(data));
  }

  bool getKey(void*, InstanceHandle_t*, bool) override { return false; }

 private:
  struct OwnedSample : EndpointSample {
    std::shared_ptr<void> owned;
  };
  const msgs::TypeSupport& type_;
};

dds::ReliabilityQosPolicyKind to_dds(Reliability r) {
  return r == Reliability::kReliable ? dds::RELIABLE_RELIABILITY_QOS
                                     : dds::BEST_EFFORT_RELIABILITY_QOS;
}
dds::DurabilityQosPolicyKind to_dds(Durability d) {
  return d == Durability::kTransientLocal ? dds::TRANSIENT_LOCAL_DURABILITY_QOS
                                          : dds::VOLATILE_DURABILITY_QOS;
}

// The QoS both endpoint kinds share, applied to a DataWriterQos or DataReaderQos.
template <class EndpointQos>
void apply_common_qos(const QoS& qos, EndpointQos& out) {
  out.reliability().kind = to_dds(qos.reliability);
  out.durability().kind = to_dds(qos.durability);
  auto& limits = out.resource_limits();
  if (qos.history == History::kKeepLast) {
    // ROS 2 reads depth 0 as "system default", which is 1 in Fast DDS.
    const auto depth = static_cast<int32_t>(qos.depth == 0 ? 1 : qos.depth);
    out.history().kind = dds::KEEP_LAST_HISTORY_QOS;
    out.history().depth = depth;
    limits.max_instances = 1;
    limits.max_samples_per_instance = depth;
    limits.max_samples = depth;
    limits.allocated_samples = depth;
  } else {
    out.history().kind = dds::KEEP_ALL_HISTORY_QOS;
    limits.max_instances = 1;
  }
  // Unbounded types: start small, grow each payload as large messages arrive.
  out.endpoint().history_memory_policy =
      eprosima::fastrtps::rtps::PREALLOCATED_WITH_REALLOC_MEMORY_MODE;
  // Data sharing needs bounded types; everything goes through the RTPS transports.
  out.data_sharing().off();
}

template <class EndpointQos>
void set_user_data(const std::string& text, EndpointQos& qos) {
  qos.user_data().data_vec().assign(text.begin(), text.end());
}

dds::DataWriterQos writer_qos(const dds::Publisher& publisher, const QoS& qos) {
  dds::DataWriterQos out = publisher.get_default_datawriter_qos();
  apply_common_qos(qos, out);
  out.representation().m_value = {dds::XCDR_DATA_REPRESENTATION};
  out.publish_mode().kind = dds::SYNCHRONOUS_PUBLISH_MODE;
  return out;
}

dds::DataReaderQos reader_qos(const dds::Subscriber& subscriber, const QoS& qos) {
  dds::DataReaderQos out = subscriber.get_default_datareader_qos();
  apply_common_qos(qos, out);
  out.type_consistency().representation.m_value = {dds::XCDR_DATA_REPRESENTATION};
  return out;
}

ParticipantId participant_id(const eprosima::fastrtps::rtps::GuidPrefix_t& prefix) {
  ParticipantId id;
  std::memcpy(id.data(), prefix.value, id.size());
  return id;
}

// rmw's GID of an endpoint or participant: its 16-byte GUID.
Gid gid_of(const eprosima::fastrtps::rtps::GUID_t& guid) {
  Gid gid{};
  std::memcpy(gid.data(), guid.guidPrefix.value, guid.guidPrefix.size);
  std::memcpy(gid.data() + guid.guidPrefix.size, guid.entityId.value, guid.entityId.size);
  return gid;
}

// The GID as ros2 tracepoints record it: zero-padded to RMW_GID_STORAGE_SIZE.
std::array<uint8_t, ROBOTPERF_ROS2_GID_STORAGE_SIZE> traced_gid(
    const eprosima::fastrtps::rtps::GUID_t& guid) {
  std::array<uint8_t, ROBOTPERF_ROS2_GID_STORAGE_SIZE> out{};
  const Gid gid = gid_of(guid);
  std::memcpy(out.data(), gid.data(), gid.size());
  return out;
}

// What discovery tells about the other participants of the domain. Fast DDS calls it from its
// own threads.
class PeerListener final : public dds::DomainParticipantListener {
 public:
  void on_participant_discovery(
      dds::DomainParticipant*, eprosima::fastrtps::rtps::ParticipantDiscoveryInfo&& info) override {
    using Info = eprosima::fastrtps::rtps::ParticipantDiscoveryInfo;
    if (info.status != Info::DISCOVERED_PARTICIPANT && info.status != Info::CHANGED_QOS_PARTICIPANT)
      return;
    const auto& data = info.info;
    table_.announce(participant_id(data.m_guid.guidPrefix), [&](PeerParticipant& peer) {
      peer.name = data.m_participantName.to_string();
      const auto& bytes = data.m_userData.data_vec();
      peer.user_data.assign(bytes.begin(), bytes.end());
      // Where it runs: the IP addresses of its user and discovery traffic, or this host when Fast
      // DDS reaches it through shared memory (it then keeps no UDP locator for it).
      peer.addresses.clear();
      for (const auto* locators :
           {&data.default_locators.unicast, &data.metatraffic_locators.unicast}) {
        for (const auto& locator : *locators) {
          std::string address;
          if (locator.kind == LOCATOR_KIND_SHM) {
            address = "this host (shared memory)";
          } else if (locator.kind == LOCATOR_KIND_UDPv4 || locator.kind == LOCATOR_KIND_UDPv6) {
            address = eprosima::fastrtps::rtps::IPLocator::ip_to_string(locator);
          } else {
            continue;
          }
          if (std::ranges::find(peer.addresses, address) == peer.addresses.end())
            peer.addresses.push_back(std::move(address));
        }
      }
    });
  }
  void on_subscriber_discovery(dds::DomainParticipant*,
                               eprosima::fastrtps::rtps::ReaderDiscoveryInfo&& info) override {
    using Info = eprosima::fastrtps::rtps::ReaderDiscoveryInfo;
    record(info.info, info.status == Info::REMOVED_READER, false);
  }
  void on_publisher_discovery(dds::DomainParticipant*,
                              eprosima::fastrtps::rtps::WriterDiscoveryInfo&& info) override {
    using Info = eprosima::fastrtps::rtps::WriterDiscoveryInfo;
    record(info.info, info.status == Info::REMOVED_WRITER, true);
  }

  std::vector<PeerParticipant> peers(const ParticipantId& self) const { return table_.peers(self); }
  PeerTable& table() { return table_; }

 private:
  // A reader's or writer's proxy data.
  template <class ProxyData>
  void record(const ProxyData& data, bool removed, bool writer) {
    const ParticipantId participant = participant_id(data.guid().guidPrefix);
    if (removed) {
      table_.remove_endpoint(participant, gid_of(data.guid()));
      return;
    }
    PeerEndpoint endpoint;
    endpoint.gid = gid_of(data.guid());
    endpoint.writer = writer;
    endpoint.topic = data.topicName().to_string();
    endpoint.dds_type = data.typeName().to_string();
    endpoint.qos.reliability = data.m_qos.m_reliability.kind == dds::RELIABLE_RELIABILITY_QOS
                                   ? Reliability::kReliable
                                   : Reliability::kBestEffort;
    endpoint.qos.durability = data.m_qos.m_durability.kind == dds::VOLATILE_DURABILITY_QOS
                                  ? Durability::kVolatile
                                  : Durability::kTransientLocal;
    const auto& bytes = data.m_qos.m_userData.data_vec();
    endpoint.type_hash = user_data_value(std::string(bytes.begin(), bytes.end()), "typehash");
    table_.add_endpoint(participant, std::move(endpoint));
  }
  PeerTable table_;
};

// DDS Security with Fast DDS's built-in plug-ins (PKI-DH authentication, Access-Permissions
// access control, AES-GCM-GMAC encryption), configured through participant properties as
// rmw_fastrtps configures them.
void add_security(const SecurityFiles& files, dds::DomainParticipantQos& qos) {
  // Fast DDS takes "file://" and an absolute path (a bare "file:" it refuses).
  auto uri = [](const std::filesystem::path& file) { return "file://" + file.string(); };
  const std::string auth = "dds.sec.auth.builtin.PKI-DH.";
  const std::string access = "dds.sec.access.builtin.Access-Permissions.";
  auto& properties = qos.properties().properties();
  properties.emplace_back("dds.sec.auth.plugin", "builtin.PKI-DH");
  properties.emplace_back(auth + "identity_ca", uri(files.identity_ca));
  properties.emplace_back(auth + "identity_certificate", uri(files.certificate));
  properties.emplace_back(auth + "private_key", uri(files.private_key));
  properties.emplace_back("dds.sec.access.plugin", "builtin.Access-Permissions");
  properties.emplace_back(access + "permissions_ca", uri(files.permissions_ca));
  properties.emplace_back(access + "governance", uri(files.governance));
  properties.emplace_back(access + "permissions", uri(files.permissions));
  properties.emplace_back("dds.sec.crypto.plugin", "builtin.AES-GCM-GMAC");
}

// ROS_STATIC_PEERS as rmw_fastrtps adds them: unicast initial peers beside the multicast one that
// Fast DDS uses alone when none are given (port 0: Fast DDS fills in the domain's discovery ports).
void add_static_peers(const std::vector<std::string>& peers, dds::DomainParticipantQos& qos) {
  if (peers.empty()) return;
  auto& initial = qos.wire_protocol().builtin.initialPeersList;
  if (initial.empty()) {
    eprosima::fastrtps::rtps::Locator_t multicast;
    eprosima::fastrtps::rtps::IPLocator::setIPv4(multicast, kDiscoveryMulticastAddress);
    initial.push_back(multicast);
  }
  for (const auto& peer : peers) {
    eprosima::fastrtps::rtps::Locator_t unicast;
    eprosima::fastrtps::rtps::IPLocator::setIPv4(unicast, peer);
    initial.push_back(unicast);
  }
}

// The participant and the entities every endpoint shares. Publisher and
// subscription handles keep it alive, so they may outlive their Transport.
class Participant {
 public:
  explicit Participant(const TransportOptions& options) {
    check_secured_domain("fastdds", options);
    auto* factory = dds::DomainParticipantFactory::get_instance();
    dds::DomainParticipantQos qos = fastdds_participant_qos();
    const std::string user_data = participant_user_data(options);
    qos.user_data().data_vec().assign(user_data.begin(), user_data.end());
    if (options.security) add_security(*options.security, qos);
    // Only the discovery callbacks, which no status mask filters.
    participant_ = factory->create_participant(options.domain_id, qos, &peer_listener_,
                                               dds::StatusMask::none());
    if (participant_ == nullptr) {
      throw TransportError(
          "fastdds: cannot create a DomainParticipant on domain " +
          std::to_string(options.domain_id) +
          (options.security
               ? " with DDS Security (enclave " + options.security->enclave +
                     ": are its keystore files valid, its permissions for this domain?)"
               : ""));
    }
    nodes_.emplace(gid_of(participant_->guid()), options.ros_distro);
    publisher_ = participant_->create_publisher(participant_->get_default_publisher_qos());
    subscriber_ = participant_->create_subscriber(participant_->get_default_subscriber_qos());
    if (publisher_ == nullptr || subscriber_ == nullptr) {
      destroy();
      throw TransportError("fastdds: cannot create the Publisher and Subscriber");
    }
  }
  Participant(const Participant&) = delete;
  Participant& operator=(const Participant&) = delete;
  ~Participant() { destroy(); }

  dds::Publisher& publisher() { return *publisher_; }
  dds::Subscriber& subscriber() { return *subscriber_; }
  ParticipantId id() const { return participant_id(participant_->guid().guidPrefix); }
  std::vector<PeerParticipant> peers() const { return peer_listener_.peers(id()); }
  PeerTable& peer_table() { return peer_listener_.table(); }
  LocalNodes& nodes() { return *nodes_; }

  // The topic, created on first use; a second type is an error.
  dds::Topic& topic(const EndpointTopic& endpoint_topic, const msgs::TypeSupport& type) {
    const std::string& dds_name = endpoint_topic.dds_name;
    std::lock_guard lock(mutex_);
    if (auto it = topics_.find(dds_name); it != topics_.end()) {
      if (it->second->get_type_name() != type.dds_type) {
        throw TransportError("fastdds: topic " + endpoint_topic.name + " already has type " +
                             it->second->get_type_name() + ", not " + type.dds_type);
      }
      return *it->second;
    }
    register_type(type);
    dds::Topic* topic =
        participant_->create_topic(dds_name, type.dds_type, participant_->get_default_topic_qos());
    if (topic == nullptr) throw TransportError("fastdds: cannot create topic " + dds_name);
    topics_.emplace(dds_name, topic);
    return *topic;
  }

 private:
  // Caller holds mutex_. Fast DDS refuses a second TypeSupport under the same
  // name, so each type name is registered once per participant, whichever
  // endpoint comes first: each brings its own TypeSupport (EndpointSample).
  void register_type(const msgs::TypeSupport& type) {
    if (participant_->find_type(type.dds_type).get() != nullptr) return;
    dds::TypeSupport dds_type(new MessageDataType(type));
    if (dds_type.register_type(participant_) != ReturnCode::RETCODE_OK) {
      throw TransportError("fastdds: cannot register type " + type.dds_type);
    }
  }

  void destroy() {
    participant_->delete_contained_entities();
    dds::DomainParticipantFactory::get_instance()->delete_participant(participant_);
  }

  // Declared before the participant that calls it, so that it outlives it.
  PeerListener peer_listener_;
  dds::DomainParticipant* participant_ = nullptr;
  dds::Publisher* publisher_ = nullptr;
  dds::Subscriber* subscriber_ = nullptr;
  std::optional<LocalNodes> nodes_;
  std::mutex mutex_;
  std::map<std::string, dds::Topic*> topics_;
};

class FastddsPublisher final : public PublisherHandle {
 public:
  FastddsPublisher(std::shared_ptr<Participant> participant, const EndpointTopic& topic,
                   const msgs::TypeSupport& type, const QoS& qos, const NodeName& node)
      : participant_(std::move(participant)), topic_(topic.name), type_(type) {
    dds::Publisher& publisher = participant_->publisher();
    dds::DataWriterQos dds_qos = writer_qos(publisher, qos);
    set_user_data(endpoint_user_data(type, participant_->nodes().distro()), dds_qos);
    writer_ = publisher.create_datawriter(&participant_->topic(topic, type), dds_qos);
    if (writer_ == nullptr) throw TransportError("fastdds: cannot create a writer on " + topic_);
    node_.emplace(participant_->nodes(), node, gid_of(writer_->guid()), true);
    if (lttng_ust_tracepoint_enabled(ros2, rmw_publisher_init)) {
      const auto gid = traced_gid(writer_->guid());
      lttng_ust_do_tracepoint(ros2, rmw_publisher_init, this, gid.data());
    }
  }
  ~FastddsPublisher() override {
    node_.reset();
    participant_->publisher().delete_datawriter(writer_);
  }

  void publish(MessagePtr msg) override {
    if (!msg) throw TransportError("fastdds: cannot publish a null message on " + topic_);
    // Fast DDS takes a non-const sample pointer but only reads it to serialize.
    EndpointSample endpoint_sample{&type_, const_cast<void*>(msg.get())};
    void* sample = &endpoint_sample;
    if (lttng_ust_tracepoint_enabled(ros2, rmw_publish)) {
      // Traced, the source timestamp is set here so that rmw_publish and the
      // subscriber's rmw_take carry the same one (Fast DDS would read the
      // same system clock itself inside write()).
      const auto now = std::chrono::system_clock::now().time_since_epoch();
      const int64_t ns = std::chrono::duration_cast<std::chrono::nanoseconds>(now).count();
      lttng_ust_do_tracepoint(ros2, rmw_publish, this, msg.get(), ns);
      const eprosima::fastrtps::Time_t stamp(static_cast<int32_t>(ns / 1'000'000'000),
                                             static_cast<uint32_t>(ns % 1'000'000'000));
      if (writer_->write_w_timestamp(sample, dds::HANDLE_NIL, stamp) != ReturnCode::RETCODE_OK) {
        throw TransportError("fastdds: write on " + topic_ + " failed");
      }
    } else if (!writer_->write(sample)) {
      throw TransportError("fastdds: write on " + topic_ + " failed");
    }
  }

  std::size_t matched_subscriptions() const override {
    dds::PublicationMatchedStatus status;
    writer_->get_publication_matched_status(status);
    return static_cast<std::size_t>(status.current_count);
  }

 private:
  std::shared_ptr<Participant> participant_;
  std::string topic_;
  const msgs::TypeSupport& type_;
  dds::DataWriter* writer_ = nullptr;
  std::optional<NodeEndpoint> node_;
};

class DataAvailableListener final : public dds::DataReaderListener {
 public:
  explicit DataAvailableListener(std::function<void()> on_ready) : on_ready_(std::move(on_ready)) {}
  void on_data_available(dds::DataReader*) override { on_ready_(); }

 private:
  std::function<void()> on_ready_;
};

class FastddsSubscription final : public SubscriptionHandle {
 public:
  FastddsSubscription(std::shared_ptr<Participant> participant, const EndpointTopic& topic,
                      const msgs::TypeSupport& type, const QoS& qos, std::function<void()> on_ready,
                      const NodeName& node)
      : participant_(std::move(participant)),
        topic_(topic.name),
        type_(type),
        listener_(std::move(on_ready)) {
    dds::Subscriber& subscriber = participant_->subscriber();
    dds::DataReaderQos dds_qos = reader_qos(subscriber, qos);
    set_user_data(endpoint_user_data(type, participant_->nodes().distro()), dds_qos);
    reader_ = subscriber.create_datareader(&participant_->topic(topic, type), dds_qos, &listener_,
                                           dds::StatusMask::data_available());
    if (reader_ == nullptr) throw TransportError("fastdds: cannot create a reader on " + topic_);
    node_.emplace(participant_->nodes(), node, gid_of(reader_->guid()), false);
    if (lttng_ust_tracepoint_enabled(ros2, rmw_subscription_init)) {
      const auto gid = traced_gid(reader_->guid());
      lttng_ust_do_tracepoint(ros2, rmw_subscription_init, this, gid.data());
    }
  }
  ~FastddsSubscription() override {
    node_.reset();
    reader_->set_listener(nullptr);
    participant_->subscriber().delete_datareader(reader_);
  }

  MessagePtr take(MessageInfo* info) override {
    std::shared_ptr<void> msg = type_.create();
    EndpointSample sample{&type_, msg.get()};
    dds::SampleInfo sample_info;
    while (true) {
      const auto rc = reader_->take_next_sample(&sample, &sample_info);
      if (rc == ReturnCode::RETCODE_NO_DATA) return nullptr;
      if (rc != ReturnCode::RETCODE_OK) {
        throw TransportError("fastdds: take on " + topic_ + " failed (code " +
                             std::to_string(rc()) + ")");
      }
      // Samples without data only announce writer/instance state changes.
      if (!sample_info.valid_data) continue;
      lttng_ust_tracepoint(ros2, rmw_take, this, msg.get(), sample_info.source_timestamp.to_ns(),
                           1);
      if (info != nullptr) {
        info->source_timestamp_ns = sample_info.source_timestamp.to_ns();
        info->reception_timestamp_ns = sample_info.reception_timestamp.to_ns();
        info->from_intra_process = false;
        info->sender = participant_id(sample_info.sample_identity.writer_guid().guidPrefix);
      }
      return msg;
    }
  }

  std::size_t matched_publishers() const override {
    dds::SubscriptionMatchedStatus status;
    reader_->get_subscription_matched_status(status);
    return static_cast<std::size_t>(status.current_count);
  }

 private:
  std::shared_ptr<Participant> participant_;
  std::string topic_;
  const msgs::TypeSupport& type_;
  DataAvailableListener listener_;
  dds::DataReader* reader_ = nullptr;
  std::optional<NodeEndpoint> node_;
};

}  // namespace

dds::DomainParticipantQos fastdds_participant_qos() {
  auto* factory = dds::DomainParticipantFactory::get_instance();
  // Like rmw_fastrtps, honour a Fast DDS XML profile the user points us at.
  factory->load_profiles();
  dds::DomainParticipantQos qos = factory->get_default_participant_qos();
  qos.name("robotperf");
  if (qos.transport().use_builtin_transports) {
    // The built-in pair (UDPv4 and shared memory), but with a larger segment:
    // samples travel in 64 KiB fragments, and with the default 512 KiB segment
    // the fragments of a multi-megabyte message overrun it, are dropped and
    // wait for reliable repair (tens of milliseconds, and losses under KEEP_LAST).
    auto shm = std::make_shared<eprosima::fastdds::rtps::SharedMemTransportDescriptor>();
    shm->segment_size(kSharedMemorySegmentSize);
    // And UDP sockets that can hold a large sample's burst of fragments (up to net.core.rmem_max):
    // other vendors' writers (Cyclone DDS) send one without pause, and the system's default buffer
    // (208 KiB) drops most of a VGA colour image.
    auto udp = std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>();
    udp->receiveBufferSize = kUdpReceiveBufferSize;
    // ROS_STATIC_PEERS: each peer is tried at the discovery ports of this many participants per
    // address (Fast DDS's default of 4 misses a host's fifth participant).
    udp->maxInitialPeersRange = kParticipantsPerStaticPeer;
    qos.transport().use_builtin_transports = false;
    qos.transport().user_transports = {shm, udp};
  }
  add_static_peers(static_peers_from_environment(), qos);
  return qos;
}

std::unique_ptr<Transport> make_fastdds_transport(const TransportOptions& options) {
  return std::make_unique<ParticipantTransport<Participant, FastddsPublisher, FastddsSubscription>>(
      "fastdds", options);
}

}  // namespace robotperf::rmw
