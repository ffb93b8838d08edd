// The "fastdds" transport: round trips in one process and across two, large
// messages, QoS, type clashes, discovery counts, and the bytes on the wire.
#include "fastdds_transport.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
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
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "fastdds_raw_bytes_type.hpp"
#include "inbox.hpp"
#include "robotperf/msgs/cdr.hpp"
#include "robotperf/msgs/sensor_msgs.hpp"

extern char** environ;

namespace robotperf::rmw {
namespace {

namespace dds = eprosima::fastdds::dds;
using eprosima::fastrtps::types::ReturnCode_t;
using msgs::CameraInfo;
using msgs::Image;
using testing::Inbox;
using testing::kTimeout;
using testing::wait_until;

// Tests run in parallel as separate processes: each uses its own domain and
// topic names that carry the process id, so no two tests can see each other.
int test_domain(int offset) {
  return static_cast<int>(getpid() % 100) + offset;
}

std::string test_topic(const std::string& name) {
  return "/robotperf_test/" + name + "_" + std::to_string(getpid());
}

Image make_image(uint32_t width, uint32_t height, uint8_t seed) {
  Image img;
  img.header.stamp = msgs::Time{1700000000, 123456789};
  img.header.frame_id = "camera_optical_frame";
  img.width = width;
  img.height = height;
  img.encoding = "mono8";
  img.step = width;
  img.data.resize(std::size_t{width} * height);
  for (std::size_t i = 0; i < img.data.size(); ++i) {
    img.data[i] = static_cast<uint8_t>(i * 31 + seed + i / 251);
  }
  return img;
}

CameraInfo make_camera_info() {
  CameraInfo info;
  info.header.stamp = msgs::Time{42, 999999999};
  info.header.frame_id = "left";
  info.width = 1280;
  info.height = 720;
  info.distortion_model = "plumb_bob";
  info.d = {-0.28, 0.07, 0.0002, -0.0001, 0.0};
  info.k = {700.5, 0, 640.25, 0, 701.0, 360.75, 0, 0, 1};
  info.r = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  info.p = {700.5, 0, 640.25, -42.1, 0, 701.0, 360.75, 0, 0, 0, 1, 0};
  info.binning_x = 2;
  info.binning_y = 3;
  info.roi = {10, 20, 300, 400, true};
  return info;
}

template <class T>
MessagePtr share(T msg) {
  return std::make_shared<const T>(std::move(msg));
}

template <class T>
const T& as(const MessagePtr& msg) {
  return *static_cast<const T*>(msg.get());
}

// One publisher and one subscription of T on one topic, discovered.
template <class T>
struct Pair {
  Pair(Transport& transport, const std::string& topic, const QoS& qos) {
    pub = transport.create_publisher(topic, msgs::type_support<T>(), qos);
    sub = transport.create_subscription(topic, msgs::type_support<T>(), qos, inbox.on_ready());
  }
  bool matched() {
    return wait_until(
        [&] { return pub->matched_subscriptions() == 1 && sub->matched_publishers() == 1; });
  }
  Inbox inbox;  // outlives `sub`, which notifies it
  std::unique_ptr<PublisherHandle> pub;
  std::unique_ptr<SubscriptionHandle> sub;
};

TEST(FastddsTransport, IsNamedFastdds) {
  EXPECT_EQ(make_fastdds_transport({test_domain(0)})->name(), "fastdds");
}

TEST(FastddsTransport, ImageAndCameraInfoRoundTripInOneProcess) {
  auto transport = make_fastdds_transport({test_domain(1)});
  Pair<Image> images(*transport, test_topic("image"), QoS::ros_default());
  Pair<CameraInfo> infos(*transport, test_topic("camera_info"), QoS::ros_default());
  ASSERT_TRUE(images.matched());
  ASSERT_TRUE(infos.matched());

  const Image image = make_image(64, 48, 7);
  const CameraInfo camera_info = make_camera_info();
  images.pub->publish(share(image));
  infos.pub->publish(share(camera_info));

  MessageInfo image_info;
  MessagePtr got_image = images.inbox.take(*images.sub, &image_info);
  ASSERT_NE(got_image, nullptr);
  EXPECT_EQ(as<Image>(got_image), image);
  MessagePtr got_info = infos.inbox.take(*infos.sub);
  ASSERT_NE(got_info, nullptr);
  EXPECT_EQ(as<CameraInfo>(got_info), camera_info);

  // DDS stamps samples with the system clock, so compare with it, not steady_now_ns().
  const int64_t wall_now_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                                  std::chrono::system_clock::now().time_since_epoch())
                                  .count();
  EXPECT_GT(image_info.source_timestamp_ns, wall_now_ns - 60'000'000'000);
  EXPECT_LE(image_info.source_timestamp_ns, image_info.reception_timestamp_ns);
  EXPECT_LE(image_info.reception_timestamp_ns, wall_now_ns);
  EXPECT_FALSE(image_info.from_intra_process);

  EXPECT_EQ(images.sub->take(nullptr), nullptr) << "exactly one message was published";
}

TEST(FastddsTransport, FourMebibyteImageInOneProcess) {
  auto transport = make_fastdds_transport({test_domain(2)});
  Pair<Image> images(*transport, test_topic("big_image"), QoS::ros_default());
  ASSERT_TRUE(images.matched());
  for (uint8_t seed = 0; seed < 3; ++seed) {
    const Image image = make_image(2048, 2048, seed);
    ASSERT_EQ(image.data.size(), 4u << 20);
    images.pub->publish(share(image));
    MessagePtr got = images.inbox.take(*images.sub);
    ASSERT_NE(got, nullptr) << "message " << int{seed};
    EXPECT_TRUE(as<Image>(got) == image) << "message " << int{seed} << " differs";
  }
}

TEST(FastddsTransport, AcceptsEveryQosCombination) {
  auto transport = make_fastdds_transport({test_domain(3)});
  const QoS profiles[] = {
      QoS::ros_default(),
      QoS::sensor_data(),
      QoS{History::kKeepLast, 1, Reliability::kReliable, Durability::kTransientLocal},
      QoS{History::kKeepAll, 0, Reliability::kReliable, Durability::kVolatile},
      QoS{History::kKeepAll, 0, Reliability::kBestEffort, Durability::kVolatile},
      QoS{History::kKeepLast, 0, Reliability::kBestEffort, Durability::kVolatile},
  };
  int index = 0;
  for (const QoS& qos : profiles) {
    SCOPED_TRACE("QoS #" + std::to_string(index));
    Pair<Image> images(*transport, test_topic("qos" + std::to_string(index++)), qos);
    ASSERT_TRUE(images.matched());
    const Image image = make_image(320, 240, static_cast<uint8_t>(index));
    images.pub->publish(share(image));
    MessagePtr got = images.inbox.take(*images.sub);
    ASSERT_NE(got, nullptr);
    EXPECT_EQ(as<Image>(got), image);
  }
}

TEST(FastddsTransport, TransientLocalDeliversToLateSubscriber) {
  auto transport = make_fastdds_transport({test_domain(4)});
  const QoS latched{History::kKeepLast, 1, Reliability::kReliable, Durability::kTransientLocal};
  const std::string topic = test_topic("latched");
  auto pub = transport->create_publisher(topic, msgs::type_support<CameraInfo>(), latched);
  CameraInfo old_info = make_camera_info();
  old_info.width = 1;
  pub->publish(share(old_info));
  const CameraInfo last_info = make_camera_info();
  pub->publish(share(last_info));

  Inbox inbox;
  auto sub = transport->create_subscription(topic, msgs::type_support<CameraInfo>(), latched,
                                            inbox.on_ready());
  MessagePtr got = inbox.take(*sub);
  ASSERT_NE(got, nullptr);
  EXPECT_EQ(as<CameraInfo>(got), last_info) << "depth 1 keeps only the last message";
}

TEST(FastddsTransport, SecondTypeOnATopicIsATransportError) {
  auto transport = make_fastdds_transport({test_domain(5)});
  const std::string topic = test_topic("clash");
  auto pub = transport->create_publisher(topic, msgs::type_support<Image>(), QoS{});
  // The same type again, on this and on another topic, is fine.
  auto pub2 = transport->create_publisher(topic, msgs::type_support<Image>(), QoS{});
  Inbox inbox;
  auto sub = transport->create_subscription(test_topic("other"), msgs::type_support<Image>(), QoS{},
                                            inbox.on_ready());
  try {
    transport->create_subscription(topic, msgs::type_support<CameraInfo>(), QoS{},
                                   inbox.on_ready());
    FAIL() << "expected a TransportError";
  } catch (const TransportError& e) {
    EXPECT_NE(std::string(e.what()).find("sensor_msgs::msg::dds_::Image_"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(
      transport->create_publisher(topic, msgs::type_support<CameraInfo>(), QoS::sensor_data()),
      TransportError);
}

TEST(FastddsTransport, InvalidTopicNameIsATransportError) {
  auto transport = make_fastdds_transport({test_domain(6)});
  EXPECT_THROW(transport->create_publisher("no_slash", msgs::type_support<Image>(), QoS{}),
               TransportError);
  EXPECT_THROW(
      transport->create_subscription("/bad//name", msgs::type_support<Image>(), QoS{}, [] {}),
      TransportError);
}

TEST(FastddsTransport, CountsMatchedEndpoints) {
  auto transport = make_fastdds_transport({test_domain(7)});
  auto other_transport = make_fastdds_transport({test_domain(7)});
  const std::string topic = test_topic("matched");
  const auto& type = msgs::type_support<Image>();
  auto pub = transport->create_publisher(topic, type, QoS{});
  EXPECT_EQ(pub->matched_subscriptions(), 0u);

  Inbox inbox;
  auto local_sub = transport->create_subscription(topic, type, QoS{}, inbox.on_ready());
  auto remote_sub = other_transport->create_subscription(topic, type, QoS{}, inbox.on_ready());
  EXPECT_TRUE(wait_until([&] { return pub->matched_subscriptions() == 2; }))
      << pub->matched_subscriptions();
  EXPECT_TRUE(wait_until([&] { return remote_sub->matched_publishers() == 1; }));

  auto remote_pub = other_transport->create_publisher(topic, type, QoS{});
  EXPECT_TRUE(wait_until([&] { return local_sub->matched_publishers() == 2; }));

  remote_sub.reset();
  EXPECT_TRUE(wait_until([&] { return pub->matched_subscriptions() == 1; }))
      << pub->matched_subscriptions();
  remote_pub.reset();
  EXPECT_TRUE(wait_until([&] { return local_sub->matched_publishers() == 1; }));
}

// What robotperf tells runs apart by: the other participants, with their USER_DATA and topics,
// and the participant each sample came from.
TEST(FastddsTransport, DiscoversPeersAndTheSenderOfEachSample) {
  TransportOptions mine{test_domain(12), "robotperf_run=aaaa;"};
  TransportOptions theirs{test_domain(12), "robotperf_run=bbbb;"};
  auto transport = make_fastdds_transport(mine);
  auto other = make_fastdds_transport(theirs);
  const std::string topic = test_topic("peers");
  const auto& type = msgs::type_support<Image>();
  Inbox inbox;
  auto sub = transport->create_subscription(topic, type, QoS{}, inbox.on_ready());
  auto pub = other->create_publisher(topic, type, QoS{});
  ASSERT_TRUE(wait_until([&] { return pub->matched_subscriptions() == 1; }));
  std::vector<PeerParticipant> peers;
  ASSERT_TRUE(wait_until([&] {
    peers = transport->peers();
    return peers.size() == 1 && peers[0].topics.contains(topic);
  })) << peers.size();
  EXPECT_EQ(peers[0].user_data, "robotperf_run=bbbb;");
  EXPECT_EQ(peers[0].name, "robotperf");
  EXPECT_EQ(to_hex(peers[0].id).size(), 24u);
  EXPECT_FALSE(peers[0].addresses.empty());  // an IP address, or this host's shared memory

  pub->publish(std::make_shared<Image>(make_image(4, 2, 1)));
  MessageInfo info;
  ASSERT_NE(inbox.take(*sub, &info), nullptr);
  EXPECT_EQ(info.sender, peers[0].id);
}

// A newcomer sees a participant that was already there within the time --domain auto listens
// (usually at once: the existing one answers the newcomer's first announcements; at the latest
// at its next periodic announcement, every 3 s by default).
TEST(FastddsTransport, ANewcomerDiscoversAnExistingParticipantWhileDomainAutoListens) {
  auto existing = make_fastdds_transport({test_domain(13), "robotperf_run=cccc;"});
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));  // its first announcements are over
  const auto start = std::chrono::steady_clock::now();
  auto newcomer = make_fastdds_transport({test_domain(13)});
  ASSERT_TRUE(wait_until([&] { return !newcomer->peers().empty(); }));
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::milliseconds(3500));
}

TEST(FastddsTransport, HandlesMayOutliveTheirTransport) {
  auto transport = make_fastdds_transport({test_domain(8)});
  Pair<Image> images(*transport, test_topic("outlive"), QoS{});
  transport.reset();
  ASSERT_TRUE(images.matched());
  const Image image = make_image(8, 8, 1);
  images.pub->publish(share(image));
  MessagePtr got = images.inbox.take(*images.sub);
  ASSERT_NE(got, nullptr);
  EXPECT_EQ(as<Image>(got), image);
}

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

TEST(FastddsTransport, PayloadOnTheWireIsTheTypeSupportCdr) {
  const int domain = test_domain(9);
  const std::string topic = test_topic("wire");
  auto transport = make_fastdds_transport({domain});
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
  const std::vector<uint8_t> expected = msgs::to_cdr(camera_info);
  EXPECT_EQ(bytes, expected);
  ASSERT_GE(bytes.size(), 4u);
  EXPECT_EQ(bytes[0], 0x00);
  EXPECT_EQ(bytes[1], 0x01);
}

TEST(FastddsTransport, MalformedPayloadIsDroppedNotFatal) {
  const int domain = test_domain(10);
  const std::string topic = test_topic("malformed");
  auto transport = make_fastdds_transport({domain});
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

// The echo peer in its own process, fed through a pipe on its stdin.
class EchoPeer {
 public:
  EchoPeer(int domain_id, const std::string& in_topic, const std::string& out_topic) {
    int fds[2];
    if (pipe2(fds, O_CLOEXEC) != 0) throw std::runtime_error("pipe2 failed");
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, fds[0], STDIN_FILENO);
    const std::string domain = std::to_string(domain_id);
    std::vector<std::string> args = {ROBOTPERF_FASTDDS_ECHO_PEER, domain, in_topic, out_topic};
    std::vector<char*> argv;
    for (auto& arg : args) argv.push_back(arg.data());
    argv.push_back(nullptr);
    const int rc = posix_spawn(&pid_, argv[0], &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    close(fds[0]);
    stdin_ = fds[1];
    if (rc != 0) {
      close(stdin_);
      throw std::runtime_error("cannot start " + args[0]);
    }
  }
  ~EchoPeer() {
    if (pid_ > 0) {
      kill(pid_, SIGKILL);
      finish();
    }
  }

  // Closes the peer's stdin and returns its exit status (-1 if it had to be killed).
  int finish() {
    if (stdin_ >= 0) close(stdin_);
    stdin_ = -1;
    int status = 0;
    const bool exited = wait_until([&] { return waitpid(pid_, &status, WNOHANG) == pid_; });
    if (!exited) {
      kill(pid_, SIGKILL);
      waitpid(pid_, &status, 0);
    }
    pid_ = -1;
    return exited && WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }

 private:
  pid_t pid_ = -1;
  int stdin_ = -1;
};

TEST(FastddsTransport, RoundTripAcrossProcesses) {
  const int domain = test_domain(11);
  const std::string ping = test_topic("ping");
  const std::string pong = test_topic("pong");
  auto transport = make_fastdds_transport({domain});
  auto pub = transport->create_publisher(ping, msgs::type_support<Image>(), QoS{});
  Inbox inbox;
  auto sub =
      transport->create_subscription(pong, msgs::type_support<Image>(), QoS{}, inbox.on_ready());
  EchoPeer peer(domain, ping, pong);
  ASSERT_TRUE(wait_until([&] {
    return pub->matched_subscriptions() == 1 && sub->matched_publishers() == 1;
  })) << "the peer process was not discovered";

  // Small, one fragment, and 4 MiB (many fragments), twice each.
  const std::pair<uint32_t, uint32_t> shapes[] = {{16, 2}, {2048, 2048}, {640, 3}, {2048, 2048}};
  uint8_t seed = 0;
  for (const auto& [width, height] : shapes) {
    const Image image = make_image(width, height, ++seed);
    pub->publish(share(image));
    MessageInfo info;
    MessagePtr echo = inbox.take(*sub, &info);
    ASSERT_NE(echo, nullptr) << width << "x" << height << " did not come back";
    EXPECT_TRUE(as<Image>(echo) == image) << width << "x" << height << " came back changed";
    EXPECT_FALSE(info.from_intra_process);
  }
  EXPECT_EQ(peer.finish(), 0);
}

}  // namespace
}  // namespace robotperf::rmw
