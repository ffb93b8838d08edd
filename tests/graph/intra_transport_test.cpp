#include <gtest/gtest.h>

#include <condition_variable>
#include <mutex>

#include "robotperf/graph/executor.hpp"
#include "robotperf/msgs/sensor_msgs.hpp"

namespace robotperf::graph {
namespace {

using msgs::CameraInfo;
using msgs::Image;

TEST(IntraTransport, DeliversTheSameObjectWithoutCopying) {
  Context ctx(rmw::make_transport("intra"));
  auto node = std::make_shared<Node>(ctx, "n");
  std::vector<std::shared_ptr<const Image>> got;
  auto pub = node->create_publisher<Image>("/image");
  auto sub = node->create_subscription<Image>(
      "/image", QoS{}, [&](std::shared_ptr<const Image> m) { got.push_back(m); });
  EXPECT_EQ(pub->matched_subscriptions(), 1u);
  EXPECT_EQ(sub->matched_publishers(), 1u);

  auto msg = std::make_shared<Image>();
  msg->data.assign(1000, 7);
  const Image* original = msg.get();
  pub->publish(std::shared_ptr<const Image>(msg));
  while (sub->execute()) {
  }
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].get(), original);  // zero-copy: the very same object
}

TEST(IntraTransport, KeepLastDropsTheOldest) {
  Context ctx(rmw::make_transport("intra"));
  auto node = std::make_shared<Node>(ctx, "n");
  std::vector<int32_t> seen;
  QoS qos = QoS::sensor_data();  // depth 5
  auto pub = node->create_publisher<Image>("/image", qos);
  auto sub = node->create_subscription<Image>(
      "/image", qos, [&](std::shared_ptr<const Image> m) { seen.push_back(m->header.stamp.sec); });
  for (int i = 0; i < 8; ++i) {
    Image m;
    m.header.stamp.sec = i;
    pub->publish(std::move(m));
  }
  while (sub->execute()) {
  }
  EXPECT_EQ(seen, (std::vector<int32_t>{3, 4, 5, 6, 7}));
}

TEST(IntraTransport, RejectsATypeClashAndBadNames) {
  Context ctx(rmw::make_transport("intra"));
  auto node = std::make_shared<Node>(ctx, "n");
  auto pub = node->create_publisher<Image>("/topic");
  EXPECT_THROW(node->create_publisher<CameraInfo>("/topic"), rmw::TransportError);
  EXPECT_THROW(node->create_publisher<Image>("relative"), std::invalid_argument);
  EXPECT_THROW(node->create_publisher<Image>("/a//b"), std::invalid_argument);
  EXPECT_THROW(rmw::make_transport("zenoh"), std::invalid_argument);
}

TEST(IntraTransport, EndpointsReportMatches) {
  Context ctx(rmw::make_transport("intra"));
  auto a = std::make_shared<Node>(ctx, "a");
  auto pub = a->create_publisher<Image>("/x");
  auto eps = a->endpoints();
  ASSERT_EQ(eps.size(), 1u);
  EXPECT_TRUE(eps[0].is_publisher);
  EXPECT_EQ(eps[0].matched, 0u);
  auto sub = a->create_subscription<Image>("/x", QoS{}, [](std::shared_ptr<const Image>) {});
  EXPECT_EQ(pub->matched_subscriptions(), 1u);
  EXPECT_EQ(a->endpoints().size(), 2u);
}

TEST(QoSProfiles, MatchRos2) {
  EXPECT_EQ(QoS::from_profile_name("default").depth, 10u);
  EXPECT_EQ(QoS::from_profile_name("default").reliability, rmw::Reliability::kReliable);
  EXPECT_EQ(QoS::from_profile_name("sensor_data").depth, 5u);
  EXPECT_EQ(QoS::from_profile_name("sensor_data").reliability, rmw::Reliability::kBestEffort);
  EXPECT_THROW(QoS::from_profile_name("fast"), std::invalid_argument);
}

TEST(TopicNames, MapToDds) {
  EXPECT_EQ(rmw::dds_topic_name("/camera/image_raw"), "rt/camera/image_raw");
  EXPECT_THROW(rmw::dds_topic_name("/camera/"), std::invalid_argument);
  EXPECT_THROW(rmw::dds_topic_name("/9lives"), std::invalid_argument);
}

}  // namespace
}  // namespace robotperf::graph
