// Every DDS transport (fastdds, cyclonedds) against the same expectations: round trips in one
// process and across two, large messages, QoS, type clashes, discovery, and handle lifetimes; and
// intra where it follows them.
#include "robotperf/rmw/transport.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "robotperf/msgs/cdr.hpp"
#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/msgs/serialized_message.hpp"
#include "transport_test_util.hpp"

namespace robotperf::rmw {
namespace {

using msgs::CameraInfo;
using msgs::Image;
using namespace testing;

class DdsTransport : public ::testing::TestWithParam<std::string> {
 protected:
  std::unique_ptr<Transport> make(std::string user_data = {}) {
    return make_transport(GetParam(), test_options(std::move(user_data)));
  }

  // The widths of the CameraInfos a subscription gets from a TRANSIENT_LOCAL publisher of `depth`
  // that published widths 1 to `published` before the subscription existed, up to `depth` of them.
  std::vector<uint32_t> late_subscriber_receives(std::size_t depth, uint32_t published) {
    auto transport = make();
    const QoS latched{History::kKeepLast, depth, Reliability::kReliable,
                      Durability::kTransientLocal};
    const std::string topic = test_topic("latched_" + std::to_string(depth));
    auto pub = transport->create_publisher(topic, msgs::type_support<CameraInfo>(), latched);
    CameraInfo info = make_camera_info();
    for (uint32_t width = 1; width <= published; ++width) {
      info.width = width;
      pub->publish(share(info));
    }
    Inbox inbox;
    auto sub = transport->create_subscription(topic, msgs::type_support<CameraInfo>(), latched,
                                              inbox.on_ready());
    std::vector<uint32_t> widths;
    while (widths.size() < depth) {
      MessagePtr got = inbox.take(*sub);
      if (got == nullptr) break;
      widths.push_back(as<CameraInfo>(got).width);
    }
    return widths;
  }
};

TEST_P(DdsTransport, IsNamedAsChosen) {
  EXPECT_EQ(make()->name(), GetParam());
}

TEST_P(DdsTransport, ImageAndCameraInfoRoundTripInOneProcess) {
  auto transport = make();
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

TEST_P(DdsTransport, FourMebibyteImageInOneProcess) {
  auto transport = make();
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

TEST_P(DdsTransport, AcceptsEveryQosCombination) {
  auto transport = make();
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

TEST_P(DdsTransport, TransientLocalDeliversToLateSubscriber) {
  EXPECT_EQ(late_subscriber_receives(1, 2), std::vector<uint32_t>{2})
      << "depth 1 keeps only the last message";
}

// Cyclone DDS keeps for late joiners what the DURABILITY_SERVICE history says (1 by default),
// not the writer's depth.
TEST_P(DdsTransport, TransientLocalDeliversItsDepthToLateSubscriber) {
  EXPECT_EQ(late_subscriber_receives(5, 7), (std::vector<uint32_t>{3, 4, 5, 6, 7}));
}

TEST_P(DdsTransport, SecondTypeOnATopicIsATransportError) {
  auto transport = make();
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

// What a run with a bag does: Playback's participant sends the recorded CDR bytes
// (SerializedMessage) while the graph's participants, in the same process, send and take the same
// type as typed messages. Each endpoint must keep its own type support even where the vendor
// shares type definitions across the process (Cyclone DDS's sertypes), in either creation order.
TEST_P(DdsTransport, SerializedAndTypedEndpointsOfOneTypeShareAProcess) {
  auto typed_side = make();
  auto serialized_side = make();
  const msgs::TypeSupport& typed = msgs::type_support<Image>();
  const msgs::TypeSupport& serialized = msgs::serialized_type_support(typed.ros_type);
  const std::string to_typed = test_topic("serialized_to_typed");
  const std::string to_serialized = test_topic("typed_to_serialized");
  Inbox typed_inbox, serialized_inbox;
  // Typed first on one topic, serialized first on the other.
  auto typed_sub =
      typed_side->create_subscription(to_typed, typed, QoS::ros_default(), typed_inbox.on_ready());
  auto serialized_pub = serialized_side->create_publisher(to_typed, serialized, QoS::ros_default());
  auto serialized_sub = serialized_side->create_subscription(
      to_serialized, serialized, QoS::ros_default(), serialized_inbox.on_ready());
  auto typed_pub = typed_side->create_publisher(to_serialized, typed, QoS::ros_default());
  ASSERT_TRUE(wait_until([&] {
    return typed_sub->matched_publishers() == 1 && serialized_pub->matched_subscriptions() == 1 &&
           serialized_sub->matched_publishers() == 1 && typed_pub->matched_subscriptions() == 1;
  }));

  const Image image = make_image(320, 240, 3);
  serialized_pub->publish(share(msgs::SerializedMessage{msgs::to_cdr(image)}));
  MessagePtr got_typed = typed_inbox.take(*typed_sub);
  ASSERT_NE(got_typed, nullptr);
  EXPECT_TRUE(as<Image>(got_typed) == image);

  typed_pub->publish(share(image));
  MessagePtr got_serialized = serialized_inbox.take(*serialized_sub);
  ASSERT_NE(got_serialized, nullptr);
  EXPECT_TRUE(as<msgs::SerializedMessage>(got_serialized).cdr == msgs::to_cdr(image));
}

// One participant with serialized and typed endpoints of one type, on different topics and on the
// same one: Fast DDS keeps one data type per type name and participant, whose codec the first
// endpoint chose for all (a typed subscription decoded Images with the serialized codec and
// corrupted the heap); Cyclone DDS's topic of one name was one sertype for both.
TEST_P(DdsTransport, SerializedAndTypedOfOneTypeShareOneParticipant) {
  auto mixed = make();
  auto sender = make();
  const msgs::TypeSupport& typed = msgs::type_support<Image>();
  const msgs::TypeSupport& serialized = msgs::serialized_type_support(typed.ros_type);
  const std::string recorded = test_topic("recorded");
  const std::string camera = test_topic("camera");
  Inbox recorded_inbox, typed_inbox, serialized_inbox;
  // The serialized endpoint first: it is the one the participant registers the type for.
  auto recorded_sub = mixed->create_subscription(recorded, serialized, QoS::ros_default(),
                                                 recorded_inbox.on_ready());
  auto typed_sub =
      mixed->create_subscription(camera, typed, QoS::ros_default(), typed_inbox.on_ready());
  auto serialized_sub = mixed->create_subscription(camera, serialized, QoS::ros_default(),
                                                   serialized_inbox.on_ready());
  auto pub = sender->create_publisher(camera, typed, QoS::ros_default());
  ASSERT_TRUE(wait_until([&] { return pub->matched_subscriptions() == 2; }));

  const Image image = make_image(640, 4, 9);
  pub->publish(share(image));
  MessagePtr got_typed = typed_inbox.take(*typed_sub);
  ASSERT_NE(got_typed, nullptr);
  EXPECT_TRUE(as<Image>(got_typed) == image);
  MessagePtr got_serialized = serialized_inbox.take(*serialized_sub);
  ASSERT_NE(got_serialized, nullptr);
  EXPECT_TRUE(as<msgs::SerializedMessage>(got_serialized).cdr == msgs::to_cdr(image));
  EXPECT_EQ(recorded_sub->take(nullptr), nullptr);
}

TEST_P(DdsTransport, InvalidTopicNameIsATransportError) {
  auto transport = make();
  EXPECT_THROW(transport->create_publisher("no_slash", msgs::type_support<Image>(), QoS{}),
               TransportError);
  EXPECT_THROW(
      transport->create_subscription("/bad//name", msgs::type_support<Image>(), QoS{}, [] {}),
      TransportError);
}

TEST_P(DdsTransport, CountsMatchedEndpoints) {
  auto transport = make();
  auto other_transport = make();
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
TEST_P(DdsTransport, DiscoversPeersAndTheSenderOfEachSample) {
  auto transport = make("robotperf_run=aaaa;");
  auto other = make("robotperf_run=bbbb;");
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
  // ROS 2's enclave first, as every rmw writes it.
  EXPECT_EQ(peers[0].user_data, "enclave=/;robotperf_run=bbbb;");
  EXPECT_EQ(peers[0].name, "robotperf");
  EXPECT_EQ(to_hex(peers[0].id).size(), 24u);
  // Fast DDS tells where a participant runs (an IP address, or this host's shared memory);
  // Cyclone DDS's discovery data does not.
  if (GetParam() == "fastdds") {
    EXPECT_FALSE(peers[0].addresses.empty());
  }

  pub->publish(std::make_shared<Image>(make_image(4, 2, 1)));
  MessageInfo info;
  ASSERT_NE(inbox.take(*sub, &info), nullptr);
  EXPECT_EQ(info.sender, peers[0].id);
}

// Cyclone DDS tells of an endpoint that left before its announcement was read only by the state
// of that announcement, without a sample of its own.
TEST_P(DdsTransport, PeersDoNotListAnEndpointThatLeftBeforeTheyWereRead) {
  auto transport = make();
  auto other = make();
  const std::string topic = test_topic("left");
  const auto& type = msgs::type_support<Image>();
  Inbox inbox;
  auto sub = transport->create_subscription(topic, type, QoS{}, inbox.on_ready());
  auto pub = other->create_publisher(topic, type, QoS{});
  ASSERT_TRUE(wait_until([&] { return sub->matched_publishers() == 1; }));
  pub.reset();
  ASSERT_TRUE(wait_until([&] { return sub->matched_publishers() == 0; }));
  std::vector<PeerParticipant> peers;
  EXPECT_TRUE(wait_until([&] {
    peers = transport->peers();
    return peers.size() == 1 && std::ranges::none_of(peers[0].endpoints, [&](const auto& e) {
             return e.topic == topic;
           });
  })) << "the publisher is still listed";
}

// The Monitor's executor and the main thread both ask for the peers, while newcomers announce
// their nodes from writers not seen before. Most telling under a sanitizer.
TEST_P(DdsTransport, PeersMayBeReadFromTwoThreadsAtOnce) {
  auto transport = make();
  std::atomic<bool> stop = false;
  auto read_peers = [&] {
    while (!stop) transport->peers();
  };
  std::thread first(read_peers), second(read_peers);
  std::vector<std::unique_ptr<Transport>> newcomers;
  std::vector<std::unique_ptr<PublisherHandle>> pubs;
  for (int i = 0; i < 6; ++i) {
    newcomers.push_back(make());
    pubs.push_back(newcomers.back()->create_publisher(test_topic("crowd"),
                                                      msgs::type_support<Image>(), QoS{},
                                                      NodeName{"node" + std::to_string(i)}));
  }
  const bool all_nodes_seen = wait_until([&] {
    const std::vector<PeerParticipant> peers = transport->peers();
    return peers.size() == newcomers.size() &&
           std::ranges::all_of(peers, [](const auto& p) { return p.nodes.size() == 1; });
  });
  stop = true;
  first.join();
  second.join();
  EXPECT_TRUE(all_nodes_seen);
}

// A newcomer sees a participant that was already there within the time --domain auto listens
// (usually at once: the existing one answers the newcomer's first announcements; at the latest
// at its next periodic announcement, every 3 s by default).
TEST_P(DdsTransport, ANewcomerDiscoversAnExistingParticipantWhileDomainAutoListens) {
  auto existing = make("robotperf_run=cccc;");
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));  // its first announcements are over
  const auto start = std::chrono::steady_clock::now();
  auto newcomer = make();
  ASSERT_TRUE(wait_until([&] { return !newcomer->peers().empty(); }));
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::milliseconds(3500));
}

TEST_P(DdsTransport, HandlesMayOutliveTheirTransport) {
  auto transport = make();
  Pair<Image> images(*transport, test_topic("outlive"), QoS{});
  transport.reset();
  ASSERT_TRUE(images.matched());
  const Image image = make_image(8, 8, 1);
  images.pub->publish(share(image));
  MessagePtr got = images.inbox.take(*images.sub);
  ASSERT_NE(got, nullptr);
  EXPECT_EQ(as<Image>(got), image);
}

TEST_P(DdsTransport, RoundTripAcrossProcesses) {
  const int domain = reserved_domain();
  const std::string ping = test_topic("ping");
  const std::string pong = test_topic("pong");
  auto transport = make_transport(GetParam(), {domain});
  auto pub = transport->create_publisher(ping, msgs::type_support<Image>(), QoS{});
  Inbox inbox;
  auto sub =
      transport->create_subscription(pong, msgs::type_support<Image>(), QoS{}, inbox.on_ready());
  EchoPeer peer(GetParam(), domain, ping, pong);
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

// ROS_DOMAIN_ID is a domain id in decimal digits, as --domain takes it: strtol alone read " +7"
// as 7.
TEST(DomainFromEnvironment, IsDecimalDigitsFrom0To232) {
  const char* before = std::getenv("ROS_DOMAIN_ID");
  const std::string kept = before != nullptr ? before : "";
  for (const auto& [value, id] : std::vector<std::pair<std::string, int>>{
           {"", 0}, {"0", 0}, {"7", 7}, {"007", 7}, {"232", 232}}) {
    setenv("ROS_DOMAIN_ID", value.c_str(), 1);
    EXPECT_EQ(domain_id_from_environment(), id) << value;
  }
  for (const std::string bad : {" 7", "+7", "-1", "7 ", "0x7", "233", "99999999999999999999"}) {
    setenv("ROS_DOMAIN_ID", bad.c_str(), 1);
    EXPECT_THROW(domain_id_from_environment(), std::invalid_argument) << bad;
  }
  if (before != nullptr) {
    setenv("ROS_DOMAIN_ID", kept.c_str(), 1);
  } else {
    unsetenv("ROS_DOMAIN_ID");
  }
}

// ROS 2 reads depth 0 as the system default, which both DDS transports take as 1.
TEST(IntraTransport, KeepLastDepthZeroKeepsTheLastMessage) {
  auto transport = make_transport("intra");
  const QoS depth_zero{History::kKeepLast, 0, Reliability::kReliable, Durability::kVolatile};
  Pair<CameraInfo> infos(*transport, test_topic("depth_zero"), depth_zero);
  CameraInfo info = make_camera_info();
  for (uint32_t width : {1u, 2u}) {
    info.width = width;
    infos.pub->publish(share(info));
  }
  MessagePtr got = infos.sub->take(nullptr);
  ASSERT_NE(got, nullptr);
  EXPECT_EQ(as<CameraInfo>(got).width, 2u);
  EXPECT_EQ(infos.sub->take(nullptr), nullptr);
}

// Intra matches a publisher and a subscription as DDS does (and as rclcpp's intra-process refuses
// an incompatible pair): it delivered a best-effort publisher's messages to a reliable
// subscription.
TEST(IntraTransport, HonoursRequestedOfferedQos) {
  auto transport = make_transport("intra");
  const QoS reliable = QoS::ros_default();
  const QoS best_effort = QoS::sensor_data();
  QoS latched = QoS::ros_default();
  latched.durability = Durability::kTransientLocal;
  struct Case {
    QoS offered, requested;
    bool matched;
  };
  const Case cases[] = {{best_effort, reliable, false},
                        {reliable, latched, false},
                        {reliable, best_effort, true},
                        {latched, reliable, true},
                        {best_effort, best_effort, true}};
  int index = 0;
  for (const Case& c : cases) {
    SCOPED_TRACE("offered " + to_string(c.offered) + ", requested " + to_string(c.requested));
    const std::string topic = test_topic("qos_match_" + std::to_string(index++));
    auto pub = transport->create_publisher(topic, msgs::type_support<CameraInfo>(), c.offered);
    auto sub =
        transport->create_subscription(topic, msgs::type_support<CameraInfo>(), c.requested, [] {});
    EXPECT_EQ(pub->matched_subscriptions(), c.matched ? 1u : 0u);
    EXPECT_EQ(sub->matched_publishers(), c.matched ? 1u : 0u);
    EXPECT_EQ(qos_incompatibility(c.offered, c.requested).empty(), c.matched);
    pub->publish(share(make_camera_info()));
    EXPECT_EQ(sub->take(nullptr) != nullptr, c.matched);
  }
  EXPECT_EQ(qos_incompatibility(best_effort, reliable),
            "a reliable subscription needs a reliable publisher");
}

// A transient-local publisher keeps its last `depth` messages for the transient-local subscriptions
// that join later, as DDS does (DdsTransport.TransientLocalDeliversItsDepthToLateSubscriber); a
// volatile one joining later gets only what comes after it.
TEST(IntraTransport, TransientLocalDeliversToLateSubscriber) {
  auto transport = make_transport("intra");
  const QoS latched{History::kKeepLast, 2, Reliability::kReliable, Durability::kTransientLocal};
  const std::string topic = test_topic("latched");
  auto pub = transport->create_publisher(topic, msgs::type_support<CameraInfo>(), latched);
  CameraInfo info = make_camera_info();
  for (uint32_t width : {1u, 2u, 3u}) {
    info.width = width;
    pub->publish(share(info));
  }
  int ready = 0;
  auto late = transport->create_subscription(topic, msgs::type_support<CameraInfo>(), latched,
                                             [&] { ++ready; });
  EXPECT_GT(ready, 0) << "the kept messages are signalled as they are delivered";
  auto volatile_late = transport->create_subscription(topic, msgs::type_support<CameraInfo>(),
                                                      QoS::ros_default(), [] {});
  EXPECT_EQ(volatile_late->take(nullptr), nullptr);
  auto widths = [](SubscriptionHandle& sub) {
    std::vector<uint32_t> out;
    while (MessagePtr got = sub.take(nullptr)) out.push_back(as<CameraInfo>(got).width);
    return out;
  };
  EXPECT_EQ(widths(*late), (std::vector<uint32_t>{2, 3}));
  info.width = 4;
  pub->publish(share(info));
  EXPECT_EQ(widths(*late), std::vector<uint32_t>{4});
  EXPECT_EQ(widths(*volatile_late), std::vector<uint32_t>{4});
}

// A serialized and a typed endpoint of one type on one topic (a bag's Playback and a graph node):
// the subscription gets a message of its own type, converted through CDR, as rclcpp converts
// between generic and typed endpoints; a typed subscription took a SerializedMessage as if it were
// an Image. Bytes that do not decode are dropped, as a DDS reader drops them.
TEST(IntraTransport, ConvertsBetweenSerializedAndTypedEndpoints) {
  auto transport = make_transport("intra");
  const msgs::TypeSupport& typed = msgs::type_support<Image>();
  const msgs::TypeSupport& serialized = msgs::serialized_type_support(typed.ros_type);
  const std::string topic = test_topic("mixed");
  auto serialized_pub = transport->create_publisher(topic, serialized, QoS::ros_default());
  auto typed_pub = transport->create_publisher(topic, typed, QoS::ros_default());
  auto typed_sub = transport->create_subscription(topic, typed, QoS::ros_default(), [] {});
  auto serialized_sub =
      transport->create_subscription(topic, serialized, QoS::ros_default(), [] {});

  const Image image = make_image(64, 2, 5);
  serialized_pub->publish(share(msgs::SerializedMessage{msgs::to_cdr(image)}));
  MessagePtr got_typed = typed_sub->take(nullptr);
  ASSERT_NE(got_typed, nullptr);
  EXPECT_TRUE(as<Image>(got_typed) == image);
  MessagePtr got_serialized = serialized_sub->take(nullptr);
  ASSERT_NE(got_serialized, nullptr);
  EXPECT_TRUE(as<msgs::SerializedMessage>(got_serialized).cdr == msgs::to_cdr(image));

  const MessagePtr sent = share(image);
  typed_pub->publish(sent);
  EXPECT_EQ(typed_sub->take(nullptr), sent) << "between typed endpoints, the very same object";
  got_serialized = serialized_sub->take(nullptr);
  ASSERT_NE(got_serialized, nullptr);
  EXPECT_TRUE(as<msgs::SerializedMessage>(got_serialized).cdr == msgs::to_cdr(image));

  serialized_pub->publish(share(msgs::SerializedMessage{{0x00, 0x01, 0x00, 0x00, 0x07}}));
  EXPECT_EQ(typed_sub->take(nullptr), nullptr);
  EXPECT_NE(serialized_sub->take(nullptr), nullptr);
}

INSTANTIATE_TEST_SUITE_P(Dds, DdsTransport, ::testing::Values("fastdds", "cyclonedds"),
                         [](const auto& info) { return info.param; });

}  // namespace
}  // namespace robotperf::rmw
