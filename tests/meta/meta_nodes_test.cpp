// The turtle tf2 demo's nodes: the broadcaster's transforms, the listener's commands against the
// command of the true relative pose (plane trigonometry, no tf2), and the evaluator.
#include <cmath>
#include <numbers>

#include "../node_test_support.hpp"
#include "category.hpp"
#include "robotperf/msgs/tf2_msgs.hpp"

namespace robotperf::meta {
namespace {

using testing::CategoryUnderTest;
using testing::NodeUnderTest;

const CategoryUnderTest& meta() {
  static const CategoryUnderTest category{register_kernels, register_evaluators};
  return category;
}

struct Turtle {
  double x, y, theta;
};

msgs::TransformStamped world_to(const std::string& child, const Turtle& t, int64_t stamp_ns) {
  msgs::TransformStamped s;
  s.header.frame_id = "world";
  s.header.stamp = msgs::Time::from_ns(stamp_ns);
  s.child_frame_id = child;
  s.transform.translation = {t.x, t.y, 0};
  s.transform.rotation = {0, 0, std::sin(t.theta / 2), std::cos(t.theta / 2)};
  return s;
}

msgs::TFMessage tf(std::vector<msgs::TransformStamped> transforms) {
  msgs::TFMessage m;
  m.transforms = std::move(transforms);
  return m;
}

TEST(TurtleTf2Listener, CommandsFollowTheTrueRelativePoseOncePerTimeBothTurtlesHave) {
  NodeUnderTest node(meta(), "meta/turtle_tf2_listener");
  auto in = node.input<msgs::TFMessage>("tf");
  auto& commands = node.output<msgs::TwistStamped>("cmd_vel");
  node.start();
  const Turtle leader{7, 3, 0.4}, follower{2, 5, -2.9};
  for (int64_t k = 1; k <= 3; ++k) {
    // The leader's transform first in odd frames, the follower's in even ones.
    const auto a = world_to("turtle1", leader, k * 100), b = world_to("turtle2", follower, k * 100);
    if (k % 2) {
      in->publish(tf({a}));
      in->publish(tf({b}));
    } else {
      in->publish(tf({b}));
      in->publish(tf({a}));
    }
  }
  in->publish(tf({world_to("turtle1", leader, 400)}));  // frame 4: the follower never comes
  in->publish(tf({world_to("turtle1", leader, 500), world_to("turtle2", follower, 500)}));
  ASSERT_TRUE(commands.wait([](const auto& m) { return m.size() >= 4; }));
  node.stop();
  const auto got = commands.messages();
  ASSERT_EQ(got.size(), 4u);
  const double dx = leader.x - follower.x, dy = leader.y - follower.y;
  const msgs::Twist truth =
      follow_command(std::cos(follower.theta) * dx + std::sin(follower.theta) * dy,
                     -std::sin(follower.theta) * dx + std::cos(follower.theta) * dy);
  const std::vector<int64_t> stamps{100, 200, 300, 500};
  for (std::size_t i = 0; i < got.size(); ++i) {
    EXPECT_EQ(got[i].header.stamp.to_ns(), stamps[i]);
    EXPECT_EQ(got[i].header.frame_id, "turtle2");
    EXPECT_NEAR(got[i].twist.linear.x, truth.linear.x, 1e-12);
    EXPECT_NEAR(got[i].twist.angular.z, truth.angular.z, 1e-12);
  }
  EXPECT_EQ(node.counters().at("commands"), 4u);
}

TEST(TurtleTf2Listener, RefusesTwoNamesForOneFrame) {
  EXPECT_THROW(NodeUnderTest(meta(), "meta/turtle_tf2_listener",
                             {{"follower_frame", "turtle1"}, {"leader_frame", "turtle1"}}),
               std::invalid_argument);
}

TEST(Tf2Broadcaster, SendsThePoseAsTheTurtlesTransformAndSkipsBadPoses) {
  NodeUnderTest node(meta(), "meta/tf2_broadcaster", {{"child_frame", "turtle7"}});
  auto in = node.input<msgs::PoseStamped>("pose");
  auto& out = node.output<msgs::TFMessage>("tf");
  node.start();
  msgs::PoseStamped bad;  // no frame
  in->publish(bad);
  msgs::PoseStamped p;
  p.header.frame_id = "world";
  p.header.stamp = msgs::Time::from_ns(42);
  p.pose.position = {1, 2, 0};
  p.pose.orientation = {0, 0, 0, 1};
  in->publish(p);
  ASSERT_TRUE(out.wait([](const auto& m) { return !m.empty(); }));
  node.stop();
  const auto t = out.messages().at(0).transforms.at(0);
  EXPECT_EQ(t.header.frame_id, "world");
  EXPECT_EQ(t.child_frame_id, "turtle7");
  EXPECT_EQ(t.header.stamp.to_ns(), 42);
  EXPECT_EQ(t.transform.translation.y, 2);
  EXPECT_EQ(node.counters().at("poses_skipped"), 1u);
}

TEST(TurtleFollowEvaluator, MeasuresTheLargestDifferencesAndTakesPlusAndMinusPiAlike) {
  plugin::DatasetStream truth = plugin::make_stream<msgs::TwistStamped>("commands", "/t");
  msgs::TwistStamped a;
  a.header.frame_id = "turtle2";
  a.twist.linear.x = 1;
  a.twist.angular.z = std::numbers::pi;
  plugin::append(truth, a);
  plugin::append(truth, a);
  auto evaluator = meta().evaluator("turtle_follow", {{"command", &truth}});
  msgs::TwistStamped out = a;
  out.twist.angular.z = -std::numbers::pi;
  evaluator->add(&out, 0);
  out.twist.linear.x = 1.25;
  out.header.frame_id = "turtle1";
  evaluator->add(&out, 1);
  const auto m = evaluator->metrics();
  EXPECT_NEAR(m.at("angular_error_max_radps"), 0, 1e-12);
  EXPECT_DOUBLE_EQ(m.at("linear_error_max_mps"), 0.25);
  EXPECT_EQ(evaluator->problems().size(), 1u);
}

}  // namespace
}  // namespace robotperf::meta
