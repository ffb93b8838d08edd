// The bytes on the wire, read and written by a plain Fast DDS participant with raw-bytes
// endpoints (no robotperf code in the path): every DDS transport sends exactly the TypeSupport's
// CDR under the ROS 2 type name, and drops malformed payloads without failing. For cyclonedds
// this is also a cross-vendor check.
#include <gtest/gtest.h>

#include <cstdint>
#include <fastdds/dds/core/status/PublicationMatchedStatus.hpp>
#include <fastdds/dds/core/status/SubscriptionMatchedStatus.hpp>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/publisher/qos/DataWriterQos.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <string>
#include <vector>

#include "fastdds_raw_bytes_type.hpp"
#include "robotperf/msgs/cdr.hpp"
#include "robotperf/msgs/sensor_msgs.hpp"
#include "transport_test_util.hpp"

namespace robotperf::rmw {
namespace {

namespace dds = eprosima::fastdds::dds;
using eprosima::fastrtps::types::ReturnCode_t;
using msgs::CameraInfo;
using msgs::Image;
using namespace testing;

class WireFormat : public ::testing::TestWithParam<std::string> {};

// A plain Fast DDS participant with raw-bytes endpoints under a given type name.
class RawParticipant {
 public:
  RawParticipant(int domain_id, const std::string& dds_type_name) {
    auto* factory = dds::DomainParticipantFactory::get_instance();
    participant_ = factory->create_participant(domain_id, factory->get_default_participant_qos());
    type_ = dds::TypeSupport(new FastddsRawBytesType(dds_type_name));
    type_.register_type(participant_);
    publisher_ = participant_->create_publisher(participant_->get_default_publisher_qos());
    subscriber_ = participant_->create_subscriber(participant_->get_default_subscriber_qos());
  }
  ~RawParticipant() {
    participant_->delete_contained_entities();
    dds::DomainParticipantFactory::get_instance()->delete_participant(participant_);
  }

  dds::DataWriter* writer(const std::string& ros_topic) {
    return publisher_->create_datawriter(topic(ros_topic),
                                         reliable(publisher_->get_default_datawriter_qos()));
  }
  dds::DataReader* reader(const std::string& ros_topic) {
    return subscriber_->create_datareader(topic(ros_topic),
                                          reliable(subscriber_->get_default_datareader_qos()));
  }

 private:
  template <class Qos>
  static Qos reliable(Qos qos) {
    qos.reliability().kind = dds::RELIABLE_RELIABILITY_QOS;
    qos.history().kind = dds::KEEP_LAST_HISTORY_QOS;
    qos.history().depth = 10;
    qos.endpoint().history_memory_policy =
        eprosima::fastrtps::rtps::PREALLOCATED_WITH_REALLOC_MEMORY_MODE;
    return qos;
  }
  dds::Topic* topic(const std::string& ros_topic) {
    return participant_->create_topic(dds_topic_name(ros_topic), type_.get_type_name(),
                                      participant_->get_default_topic_qos());
  }

  dds::DomainParticipant* participant_;
  dds::TypeSupport type_;
  dds::Publisher* publisher_;
  dds::Subscriber* subscriber_;
};

TEST_P(WireFormat, PayloadOnTheWireIsTheTypeSupportCdr) {
  const int domain = reserved_domain();
  const std::string topic = test_topic("wire");
  auto transport = make_transport(GetParam(), {domain});
  auto pub = transport->create_publisher(topic, msgs::type_support<CameraInfo>(), QoS{});
  RawParticipant raw(domain, "sensor_msgs::msg::dds_::CameraInfo_");
  dds::DataReader* reader = raw.reader(topic);
  ASSERT_NE(reader, nullptr);
  ASSERT_TRUE(wait_until([&] {
    dds::SubscriptionMatchedStatus status;
    reader->get_subscription_matched_status(status);
    return pub->matched_subscriptions() == 1 && status.current_count == 1;
  }));

  const CameraInfo camera_info = make_camera_info();
  pub->publish(share(camera_info));
  ASSERT_TRUE(reader->wait_for_unread_message(eprosima::fastrtps::Duration_t(kTimeout.count(), 0)));
  FastddsRawBytesType::Sample bytes;
  dds::SampleInfo info;
  ASSERT_EQ(reader->take_next_sample(&bytes, &info), ReturnCode_t::RETCODE_OK);
  ASSERT_GE(bytes.size(), 4u);
  EXPECT_EQ(bytes[0], 0x00);
  EXPECT_EQ(bytes[1], 0x01);
  // A writer may pad the payload to whole 4-byte words (Cyclone DDS does), counting the padding in
  // the low two bits of the encapsulation options (XTypes 1.3, 7.6.3.1.2).
  const std::size_t padding = bytes[3] & 3u;
  ASSERT_GE(bytes.size(), 4u + padding);
  for (std::size_t i = bytes.size() - padding; i < bytes.size(); ++i) EXPECT_EQ(bytes[i], 0);
  bytes.resize(bytes.size() - padding);
  bytes[3] &= ~3u;
  const std::vector<uint8_t> expected = msgs::to_cdr(camera_info);
  EXPECT_EQ(bytes, expected);
  if (GetParam() == "cyclonedds") {
    EXPECT_EQ((expected.size() + padding) % 4, 0u) << "Cyclone DDS sends whole words";
  }
}

TEST_P(WireFormat, MalformedPayloadIsDroppedNotFatal) {
  const int domain = reserved_domain();
  const std::string topic = test_topic("malformed");
  auto transport = make_transport(GetParam(), {domain});
  Inbox inbox;
  auto sub =
      transport->create_subscription(topic, msgs::type_support<Image>(), QoS{}, inbox.on_ready());
  RawParticipant raw(domain, "sensor_msgs::msg::dds_::Image_");
  dds::DataWriter* writer = raw.writer(topic);
  ASSERT_NE(writer, nullptr);
  ASSERT_TRUE(wait_until([&] {
    dds::PublicationMatchedStatus status;
    writer->get_publication_matched_status(status);
    return sub->matched_publishers() == 1 && status.current_count == 1;
  }));

  // A truncated body, a big-endian header, and an absurd sequence length.
  FastddsRawBytesType::Sample truncated{0x00, 0x01, 0x00, 0x00, 0x01, 0x02};
  FastddsRawBytesType::Sample big_endian(64, 0);
  std::vector<uint8_t> huge_sequence = msgs::to_cdr(make_image(4, 4, 0));
  huge_sequence.resize(huge_sequence.size() - 16);  // the last 4 bytes become the length
  for (std::size_t i = huge_sequence.size() - 4; i < huge_sequence.size(); ++i) {
    huge_sequence[i] = 0xff;
  }
  FastddsRawBytesType::Sample valid = msgs::to_cdr(make_image(16, 4, 3));
  for (auto* sample : {&truncated, &big_endian, &huge_sequence, &valid}) {
    ASSERT_TRUE(writer->write(sample));
  }

  MessagePtr got = inbox.take(*sub);
  ASSERT_NE(got, nullptr);
  EXPECT_EQ(as<Image>(got), make_image(16, 4, 3)) << "only the valid message comes through";
}

INSTANTIATE_TEST_SUITE_P(Dds, WireFormat, ::testing::Values("fastdds", "cyclonedds"),
                         [](const auto& info) { return info.param; });

}  // namespace
}  // namespace robotperf::rmw
