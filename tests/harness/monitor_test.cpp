// The Monitor around the graph: what it keeps for the functional evaluation.
#include <gtest/gtest.h>

#include "black_box.hpp"
#include "robotperf/graph/executor.hpp"
#include "robotperf/msgs/sensor_msgs.hpp"

namespace robotperf::harness {
namespace {

// A node that reuses its output once released (stereo_depth_nodes.cpp) must get it back even when
// the Monitor keeps that output: over intra, the Monitor keeps a copy.
TEST(Monitor, KeepsACopyOfAnOutputSharedWithTheGraphOverIntra) {
  graph::Context context(rmw::make_transport("intra", {}));
  const BoundaryTopic output{"/out", "sensor_msgs/msg/Image", "", rmw::QoS{}};
  const MessageIds ids{1'000'000'000, 100'000'000, 3};
  Monitor monitor(context, output, ids, 0);
  monitor.keep_outputs({1});
  graph::Executor executor(1);
  executor.add_node(monitor.node());
  graph::Node graph_node(context, "graph");
  auto publisher = graph_node.create_publisher<msgs::Image>("/out");
  executor.start();

  auto published = std::make_shared<msgs::Image>();
  published->header.stamp = msgs::Time::from_ns(ids.stamp_ns(1));
  published->encoding = "mono8";
  published->width = published->height = published->step = 4;
  published->data.assign(16, 7);
  publisher->publish(std::shared_ptr<const msgs::Image>(published));
  ASSERT_TRUE(monitor.wait_for(1, rmw::steady_now_ns() + 10'000'000'000));
  executor.stop();

  const Monitor::Tally tally = monitor.tally();
  ASSERT_EQ(tally.kept.size(), 1u);
  EXPECT_EQ(tally.kept[0].first, 1u);
  const auto* kept = static_cast<const msgs::Image*>(tally.kept[0].second.get());
  EXPECT_NE(kept, published.get());
  EXPECT_EQ(kept->header.stamp.to_ns(), ids.stamp_ns(1));
  EXPECT_EQ(kept->data, published->data);
  EXPECT_EQ(published.use_count(), 1) << "the Monitor still holds the graph's message";
}

}  // namespace
}  // namespace robotperf::harness
