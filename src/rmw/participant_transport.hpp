// Private to the rmw library: what the DDS transports share. A DDS transport is a participant
// shared by its endpoints; ParticipantTransport is the Transport around one, whatever the vendor:
// `Participant` has peers() and id(); `Publisher` and `Subscription` are constructed from the
// participant and the endpoint's arguments, and keep the participant alive, so that handles may
// outlive their Transport.
#pragma once

#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "robotperf/rmw/transport.hpp"

namespace robotperf::rmw {

// dds_topic_name(ros_topic), or a TransportError naming the vendor when the name is invalid.
inline std::string checked_dds_topic_name(const std::string& vendor, const std::string& ros_topic) {
  try {
    return dds_topic_name(ros_topic);
  } catch (const std::invalid_argument& e) {
    throw TransportError(vendor + ": " + e.what());
  }
}

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

template <class Participant, class Publisher, class Subscription>
class ParticipantTransport final : public Transport {
 public:
  ParticipantTransport(std::string name, const TransportOptions& options)
      : name_(std::move(name)), participant_(std::make_shared<Participant>(options)) {}

  std::string name() const override { return name_; }

  std::unique_ptr<PublisherHandle> create_publisher(const std::string& topic,
                                                    const msgs::TypeSupport& type,
                                                    const QoS& qos) override {
    return std::make_unique<Publisher>(participant_, topic, type, qos);
  }

  std::unique_ptr<SubscriptionHandle> create_subscription(const std::string& topic,
                                                          const msgs::TypeSupport& type,
                                                          const QoS& qos,
                                                          std::function<void()> on_ready) override {
    return std::make_unique<Subscription>(participant_, topic, type, qos, std::move(on_ready));
  }
  std::vector<PeerParticipant> peers() const override { return participant_->peers(); }
  ParticipantId participant() const override { return participant_->id(); }

 private:
  std::string name_;
  std::shared_ptr<Participant> participant_;
};

}  // namespace robotperf::rmw
