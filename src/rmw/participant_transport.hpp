// Private to the rmw library: what the DDS transports share. A DDS transport is a participant
// shared by its endpoints; ParticipantTransport is the Transport around one, whatever the vendor:
// `Participant` has peers() and id(); `Publisher` and `Subscription` are constructed from the
// participant and the endpoint's arguments, and keep the participant alive, so that handles may
// outlive their Transport.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "robotperf/msgs/serialized_message.hpp"
#include "robotperf/rmw/transport.hpp"
#include "ros_graph.hpp"

namespace robotperf::rmw {

// An endpoint's topic: the name messages give it and its DDS name.
struct EndpointTopic {
  std::string name;
  std::string dds_name;

  // A ROS topic ("/camera/image_raw" on DDS as "rt/camera/image_raw"); a TransportError naming
  // the vendor when the name is invalid.
  static EndpointTopic ros(const std::string& vendor, const std::string& ros_topic) {
    try {
      return {ros_topic, dds_topic_name(ros_topic)};
    } catch (const std::invalid_argument& e) {
      throw TransportError(vendor + ": " + e.what());
    }
  }
  // A topic ROS 2 keeps to DDS (ros_discovery_info), named the same on both.
  static EndpointTopic dds_only(const std::string& name) { return {name, name}; }
};

// The participant's USER_DATA: ROS 2's "enclave=<enclave>;" (the security enclave, "/" without
// security), as every rmw writes it, then the caller's pairs.
inline std::string participant_user_data(const TransportOptions& options) {
  return "enclave=" + (options.security ? options.security->enclave : std::string("/")) + ";" +
         options.user_data;
}

// Throws TransportError when `options` asks for DDS Security on a domain that no keystore's
// governance can name, before the DDS implementation fails with a less telling message.
inline void check_secured_domain(const std::string& vendor, const TransportOptions& options) {
  if (options.security && (options.domain_id < 0 || options.domain_id > kLastSecuredDomain)) {
    throw TransportError(vendor + ": DDS Security covers domains 0 to " +
                         std::to_string(kLastSecuredDomain) + ", not " +
                         std::to_string(options.domain_id) + "; choose another domain");
  }
}

// Counts the arrivals a reader signals, for a thread that waits for them; shared with the reader's
// listener, which may signal until the reader is gone.
class Arrivals {
 public:
  void notify() {
    {
      std::lock_guard lock(mutex_);
      ++count_;
    }
    changed_.notify_all();
  }
  void stop() {
    {
      std::lock_guard lock(mutex_);
      stopped_ = true;
    }
    changed_.notify_all();
  }
  // Waits until there were arrivals since `seen` (updated), or stop(); false once stopped.
  bool wait(uint64_t& seen) {
    std::unique_lock lock(mutex_);
    changed_.wait(lock, [&] { return stopped_ || count_ != seen; });
    seen = count_;
    return !stopped_;
  }

 private:
  std::mutex mutex_;
  std::condition_variable changed_;
  uint64_t count_ = 0;
  bool stopped_ = false;
};

// `Participant` also has nodes() (its LocalNodes) and peer_table() (the PeerTable its discovery
// fills); endpoints are constructed from (participant, EndpointTopic, type, qos, [on_ready,]
// NodeName). The transport announces its nodes on ros_discovery_info and reads the others'.
template <class Participant, class Publisher, class Subscription>
class ParticipantTransport final : public Transport {
 public:
  ParticipantTransport(std::string name, const TransportOptions& options)
      : name_(std::move(name)),
        participant_(std::make_shared<Participant>(options)),
        discovery_writer_(
            std::make_unique<Publisher>(participant_, EndpointTopic::dds_only(kRosDiscoveryTopic),
                                        discovery_type(), ros_discovery_writer_qos(), NodeName{})),
        discovery_reader_(std::make_unique<Subscription>(
            participant_, EndpointTopic::dds_only(kRosDiscoveryTopic), discovery_type(),
            ros_discovery_reader_qos(), [arrivals = arrivals_] { arrivals->notify(); },
            NodeName{})) {
    participant_->nodes().set_publisher(
        [writer = discovery_writer_.get()](std::shared_ptr<const msgs::SerializedMessage> sample) {
          writer->publish(std::move(sample));
        });
    announcements_ = std::thread([this] { apply_announcements(); });
  }
  ~ParticipantTransport() override {
    arrivals_->stop();
    announcements_.join();
    // Endpoints may outlive the transport; their removal is then no longer announced.
    participant_->nodes().set_publisher(nullptr);
  }

  std::string name() const override { return name_; }

  using Transport::create_publisher;
  using Transport::create_subscription;
  std::unique_ptr<PublisherHandle> create_publisher(const std::string& topic,
                                                    const msgs::TypeSupport& type, const QoS& qos,
                                                    const NodeName& node) override {
    return std::make_unique<Publisher>(participant_, EndpointTopic::ros(name_, topic), type, qos,
                                       node);
  }

  std::unique_ptr<SubscriptionHandle> create_subscription(const std::string& topic,
                                                          const msgs::TypeSupport& type,
                                                          const QoS& qos,
                                                          std::function<void()> on_ready,
                                                          const NodeName& node) override {
    return std::make_unique<Subscription>(participant_, EndpointTopic::ros(name_, topic), type, qos,
                                          std::move(on_ready), node);
  }
  std::vector<PeerParticipant> peers() const override {
    // Callers on several threads (a Monitor's executor and the main thread) read the discovery
    // data one at a time: a vendor may take it from its built-in topics as asked (Cyclone DDS),
    // which is not thread-safe on every vendor, and two samples of one endpoint must be applied
    // in the order they were taken.
    std::lock_guard lock(peers_mutex_);
    return participant_->peers();
  }
  ParticipantId participant() const override { return participant_->id(); }

 private:
  static const msgs::TypeSupport& discovery_type() {
    return msgs::serialized_type_support(kParticipantEntitiesInfoType);
  }

  // The others' nodes, applied to the peer table as their announcements arrive (each
  // participant's latest kept), on a thread of its own as rmw_dds_common has one: the topic is
  // keyless, so the reader's history holds every participant's announcements together, and it is
  // emptied as it fills, whether or not anyone asks for the peers.
  void apply_announcements() {
    uint64_t seen = 0;
    do {
      MessageInfo info;
      try {
        while (MessagePtr sample = discovery_reader_->take(&info)) {
          const auto& cdr = static_cast<const msgs::SerializedMessage*>(sample.get())->cdr;
          if (auto entities = decode_participant_entities(cdr)) {
            participant_->peer_table().set_nodes(info.sender, std::move(entities->nodes));
          }
        }
      } catch (const TransportError&) {
        // A failed take leaves ROS 2 nodes a state behind until the next arrival; the endpoints
        // themselves work.
      }
    } while (arrivals_->wait(seen));
  }

  std::string name_;
  std::shared_ptr<Participant> participant_;
  const std::shared_ptr<Arrivals> arrivals_ = std::make_shared<Arrivals>();
  std::unique_ptr<Publisher> discovery_writer_;
  std::unique_ptr<Subscription> discovery_reader_;
  std::thread announcements_;  // runs apply_announcements()
  mutable std::mutex peers_mutex_;
};

}  // namespace robotperf::rmw
