// The tf2 buffer against tf2's semantics: chains through a common parent, interpolation,
// extrapolation errors, the latest common time, static against dynamic frames, the cache, refused
// transforms; and /tf and /tf_static between a broadcaster and a listener.
#include "robotperf/plugin/tf2_buffer.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <condition_variable>
#include <mutex>
#include <numbers>

#include "robotperf/graph/executor.hpp"
#include "robotperf/rmw/transport.hpp"

namespace robotperf::plugin {
namespace {

constexpr int64_t kSecond = 1'000'000'000;

msgs::TransformStamped stamped(const std::string& parent, const std::string& child,
                               int64_t stamp_ns, double x, double y, double z, double yaw = 0) {
  msgs::TransformStamped t;
  t.header.frame_id = parent;
  t.header.stamp = msgs::Time::from_ns(stamp_ns);
  t.child_frame_id = child;
  t.transform.translation = {x, y, z};
  t.transform.rotation = {0, 0, std::sin(yaw / 2), std::cos(yaw / 2)};
  return t;
}

double yaw_of(const msgs::Quaternion& q) {
  return std::atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z));
}

TEST(Tf2Buffer, ChainsThroughTheCommonParent) {
  TransformBuffer b("test");
  // world -> turtle1 at (1, 0) facing +y; world -> turtle2 at (3, 0) facing +x.
  b.set_transform(stamped("world", "turtle1", kSecond, 1, 0, 0, std::numbers::pi / 2), "t", false);
  b.set_transform(stamped("world", "turtle2", kSecond, 3, 0, 0), "t", false);
  // turtle2's origin seen from turtle1: 2 m ahead along world +x, which is turtle1's -y.
  const auto t = b.lookup_transform("turtle1", "turtle2", kSecond);
  EXPECT_EQ(t.header.frame_id, "turtle1");
  EXPECT_EQ(t.child_frame_id, "turtle2");
  EXPECT_EQ(t.header.stamp.to_ns(), kSecond);
  EXPECT_NEAR(t.transform.translation.x, 0, 1e-12);
  EXPECT_NEAR(t.transform.translation.y, -2, 1e-12);
  EXPECT_NEAR(yaw_of(t.transform.rotation), -std::numbers::pi / 2, 1e-12);
  // The other way round is the inverse.
  const auto back = b.lookup_transform("turtle2", "turtle1", kSecond);
  EXPECT_NEAR(back.transform.translation.x, -2, 1e-12);
  EXPECT_NEAR(back.transform.translation.y, 0, 1e-12);
  EXPECT_NEAR(yaw_of(back.transform.rotation), std::numbers::pi / 2, 1e-12);
}

TEST(Tf2Buffer, WalksDeepChainsUpToTheCommonAncestorOnly) {
  TransformBuffer b("test");
  b.set_transform(stamped("map", "odom", kSecond, 5, 0, 0), "t", false);
  b.set_transform(stamped("odom", "base", 2 * kSecond, 1, 0, 0), "t", false);
  b.set_transform(stamped("odom", "base", 3 * kSecond, 2, 0, 0), "t", false);
  b.set_transform(stamped("base", "laser", 0, 0, 0, 0.5), "t", true);
  // map -> odom has no data at 2.5 s, but odom is the common ancestor: not needed.
  const auto t = b.lookup_transform("odom", "laser", 2 * kSecond + kSecond / 2);
  EXPECT_NEAR(t.transform.translation.x, 1.5, 1e-12);
  EXPECT_NEAR(t.transform.translation.z, 0.5, 1e-12);
  // Through map it is needed: map's single sample is at 1 s.
  try {
    b.lookup_transform("map", "laser", 2 * kSecond + kSecond / 2);
    FAIL() << "no extrapolation error";
  } catch (const TransformError& e) {
    EXPECT_EQ(e.kind(), TransformError::Kind::kExtrapolation);
    EXPECT_NE(std::string(e.what()).find("Lookup would require extrapolation at time 2.500000, "
                                         "but only time 1.000000 is in the buffer"),
              std::string::npos)
        << e.what();
  }
}

TEST(Tf2Buffer, InterpolatesTranslationLinearlyAndRotationBySlerp) {
  TransformBuffer b("test");
  b.set_transform(stamped("a", "b", 10 * kSecond, 0, 0, 0, 0), "t", false);
  b.set_transform(stamped("a", "b", 11 * kSecond, 4, -2, 1, 1.0), "t", false);
  const auto t = b.lookup_transform("a", "b", 10 * kSecond + kSecond / 4);
  EXPECT_NEAR(t.transform.translation.x, 1, 1e-12);
  EXPECT_NEAR(t.transform.translation.y, -0.5, 1e-12);
  EXPECT_NEAR(t.transform.translation.z, 0.25, 1e-12);
  // SLERP about one axis turns at constant speed: a quarter of the way is a quarter of the angle.
  EXPECT_NEAR(yaw_of(t.transform.rotation), 0.25, 1e-12);
  // A sample's own time gives the sample.
  EXPECT_NEAR(b.lookup_transform("a", "b", 11 * kSecond).transform.translation.x, 4, 0);
}

TEST(Tf2Buffer, SlerpTakesTheShorterArc) {
  RigidTransform a, c;
  a.rotation = {0, 0, std::sin(0.1), std::cos(0.1)};  // yaw 0.2
  // Yaw -0.2 written as the negated quaternion: the same rotation, the other hemisphere.
  c.rotation = {0, 0, std::sin(0.1), -std::cos(0.1)};
  const RigidTransform mid = interpolate(a, c, 0.5);
  msgs::Quaternion q{mid.rotation[0], mid.rotation[1], mid.rotation[2], mid.rotation[3]};
  EXPECT_NEAR(yaw_of(q), 0, 1e-12);
}

TEST(Tf2Buffer, ExtrapolationIntoTheFutureAndThePastAreErrorsWithTf2sText) {
  TransformBuffer b("test");
  b.set_transform(stamped("world", "turtle1", 2 * kSecond, 0, 0, 0), "t", false);
  b.set_transform(stamped("world", "turtle1", 3 * kSecond, 1, 0, 0), "t", false);
  auto error = [&](int64_t time) {
    try {
      b.lookup_transform("world", "turtle1", time);
    } catch (const TransformError& e) {
      EXPECT_EQ(e.kind(), TransformError::Kind::kExtrapolation);
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(error(4 * kSecond),
            "Lookup would require extrapolation into the future.  Requested time 4.000000 but the "
            "latest data is at time 3.000000, when looking up transform from frame [turtle1] to "
            "frame [world]");
  EXPECT_EQ(error(kSecond),
            "Lookup would require extrapolation into the past.  Requested time 1.000000 but the "
            "earliest data is at time 2.000000, when looking up transform from frame [turtle1] to "
            "frame [world]");
  std::string why;
  EXPECT_FALSE(b.can_transform("world", "turtle1", 4 * kSecond, &why));
  EXPECT_NE(why.find("into the future"), std::string::npos);
  EXPECT_TRUE(b.can_transform("world", "turtle1", 3 * kSecond));
}

TEST(Tf2Buffer, TimeZeroIsTheLatestCommonTimeOfThePath) {
  TransformBuffer b("test");
  for (int i = 1; i <= 5; ++i)
    b.set_transform(stamped("world", "turtle1", i * kSecond, i, 0, 0), "t", false);
  for (int i = 1; i <= 3; ++i)
    b.set_transform(stamped("world", "turtle2", i * kSecond, 0, i, 0), "t", false);
  const auto t = b.lookup_transform("turtle2", "turtle1", TransformBuffer::kLatest);
  EXPECT_EQ(t.header.stamp.to_ns(), 3 * kSecond);  // turtle2's newest, not turtle1's
  EXPECT_NEAR(t.transform.translation.x, 3, 1e-12);
  EXPECT_NEAR(t.transform.translation.y, -3, 1e-12);
  // One frame alone: its newest sample.
  EXPECT_EQ(b.lookup_transform("world", "turtle1", 0).header.stamp.to_ns(), 5 * kSecond);
}

TEST(Tf2Buffer, StaticTransformsHoldAtEveryTimeAndDynamicOnesOnlyWhereSampled) {
  TransformBuffer b("test");
  b.set_transform(stamped("base", "camera", 5 * kSecond, 0.1, 0, 0.3), "t", true);
  b.set_transform(stamped("base", "wheel", 5 * kSecond, 0, 0.2, 0), "t", false);
  for (int64_t time : {int64_t{1}, 5 * kSecond, 1000 * kSecond, TransformBuffer::kLatest}) {
    const auto t = b.lookup_transform("base", "camera", time);
    EXPECT_NEAR(t.transform.translation.z, 0.3, 1e-12);
    EXPECT_EQ(t.header.stamp.to_ns(), time);
  }
  EXPECT_TRUE(b.can_transform("camera", "wheel", 5 * kSecond));
  EXPECT_FALSE(b.can_transform("camera", "wheel", 6 * kSecond));
  // A static frame set again holds the new transform, whatever its stamp.
  b.set_transform(stamped("base", "camera", kSecond, 0.1, 0, 0.4), "t", true);
  EXPECT_NEAR(b.lookup_transform("base", "camera", 0).transform.translation.z, 0.4, 1e-12);
}

TEST(Tf2Buffer, UnknownAndUnconnectedFramesAreErrors) {
  TransformBuffer b("test");
  b.set_transform(stamped("world", "turtle1", kSecond, 0, 0, 0), "t", false);
  b.set_transform(stamped("other", "turtle3", kSecond, 0, 0, 0), "t", false);
  try {
    b.lookup_transform("turtle9", "turtle1", kSecond);
    FAIL();
  } catch (const TransformError& e) {
    EXPECT_EQ(e.kind(), TransformError::Kind::kLookup);
    EXPECT_STREQ(e.what(),
                 "\"turtle9\" passed to lookupTransform argument target_frame does not "
                 "exist. ");
  }
  try {
    b.lookup_transform("turtle3", "turtle1", kSecond);
    FAIL();
  } catch (const TransformError& e) {
    EXPECT_EQ(e.kind(), TransformError::Kind::kConnectivity);
    EXPECT_NE(std::string(e.what()).find("not part of the same tree"), std::string::npos);
  }
  EXPECT_THROW(b.lookup_transform("", "turtle1", kSecond), TransformError);
  // A frame to itself is the identity, and a leading slash names the same frame.
  const auto self = b.lookup_transform("/turtle1", "turtle1", kSecond);
  EXPECT_EQ(self.transform.rotation.w, 1);
  EXPECT_EQ(b.frames(), (std::vector<std::string>{"other", "turtle1", "turtle3", "world"}));
}

TEST(Tf2Buffer, RefusesWhatTf2Refuses) {
  TransformBuffer b("test");
  auto kind_of = [&](const msgs::TransformStamped& t) {
    try {
      b.set_transform(t, "sender", false);
    } catch (const TransformError& e) {
      return e.kind();
    }
    return TransformError::Kind::kLookup;
  };
  EXPECT_EQ(kind_of(stamped("a", "a", 1, 0, 0, 0)), TransformError::Kind::kInvalidArgument);
  EXPECT_EQ(kind_of(stamped("", "a", 1, 0, 0, 0)), TransformError::Kind::kInvalidArgument);
  EXPECT_EQ(kind_of(stamped("a", "", 1, 0, 0, 0)), TransformError::Kind::kInvalidArgument);
  EXPECT_EQ(kind_of(stamped("a", "b", 1, std::nan(""), 0, 0)),
            TransformError::Kind::kInvalidArgument);
  auto denormalised = stamped("a", "b", 1, 0, 0, 0);
  denormalised.transform.rotation.w = 1.5;
  EXPECT_EQ(kind_of(denormalised), TransformError::Kind::kInvalidArgument);
  EXPECT_TRUE(b.frames().empty());
  // A quaternion slightly off is normalised.
  auto nearly = stamped("a", "b", 1, 0, 0, 0);
  nearly.transform.rotation.w = 1.005;
  EXPECT_TRUE(b.set_transform(nearly, "sender", false));
  EXPECT_DOUBLE_EQ(b.lookup_transform("a", "b", 1).transform.rotation.w, 1);
}

TEST(Tf2Buffer, KeepsTheCacheTimeAndIgnoresOldAndRepeatedData) {
  TransformBuffer b("test", std::chrono::seconds(2));
  EXPECT_EQ(b.cache_time(), std::chrono::seconds(2));
  EXPECT_EQ(TransformBuffer("default").cache_time(), std::chrono::seconds(10));
  for (int i = 0; i <= 5; ++i)
    EXPECT_TRUE(b.set_transform(stamped("a", "b", i * kSecond, i, 0, 0), "t", false));
  // Samples older than the newest minus 2 s are gone; data that old is not taken.
  EXPECT_FALSE(b.can_transform("a", "b", 2 * kSecond + kSecond / 2));
  EXPECT_TRUE(b.can_transform("a", "b", 3 * kSecond));
  EXPECT_FALSE(b.set_transform(stamped("a", "b", kSecond, 9, 0, 0), "t", false));
  EXPECT_FALSE(b.set_transform(stamped("a", "b", 4 * kSecond, 9, 0, 0), "t", false));
  EXPECT_NEAR(b.lookup_transform("a", "b", 4 * kSecond).transform.translation.x, 4, 0);
  // Out of order but within the cache: inserted in place.
  EXPECT_TRUE(b.set_transform(stamped("a", "b", 4 * kSecond + kSecond / 2, 7, 0, 0), "t", false));
  EXPECT_NEAR(b.lookup_transform("a", "b", 4 * kSecond + kSecond / 4).transform.translation.x, 5.5,
              1e-12);
  EXPECT_THROW(TransformBuffer("bad", std::chrono::seconds(0)), std::invalid_argument);
}

TEST(Tf2Buffer, AFrameWhoseParentChangesFollowsItsParentAtTheTime) {
  TransformBuffer b("test");
  b.set_transform(stamped("world", "table", 0, 10, 0, 0), "t", true);
  b.set_transform(stamped("world", "cup", kSecond, 1, 0, 0), "t", false);
  b.set_transform(stamped("table", "cup", 2 * kSecond, 0, 1, 0), "t", false);
  EXPECT_NEAR(b.lookup_transform("world", "cup", kSecond).transform.translation.x, 1, 1e-12);
  const auto later = b.lookup_transform("world", "cup", 2 * kSecond);
  EXPECT_NEAR(later.transform.translation.x, 10, 1e-12);
  EXPECT_NEAR(later.transform.translation.y, 1, 1e-12);
  // Between them the older parent holds, not interpolated across parents.
  EXPECT_NEAR(b.lookup_transform("world", "cup", kSecond + kSecond / 2).transform.translation.x, 1,
              1e-12);
}

TEST(Tf2Buffer, ALoopInTheTreeIsAnErrorNotAHang) {
  TransformBuffer b("test");
  b.set_transform(stamped("a", "b", kSecond, 0, 0, 0), "t", false);
  b.set_transform(stamped("b", "c", kSecond, 0, 0, 0), "t", false);
  b.set_transform(stamped("c", "a", kSecond, 0, 0, 0), "t", false);
  b.set_transform(stamped("x", "y", kSecond, 0, 0, 0), "t", false);
  EXPECT_THROW(b.lookup_transform("y", "a", kSecond), TransformError);
}

// What the listener has set, awaited.
class Arrivals {
 public:
  void add() {
    const std::lock_guard lock(mutex_);
    ++count_;
    changed_.notify_all();
  }
  bool wait_for(int n) {
    std::unique_lock lock(mutex_);
    return changed_.wait_for(lock, std::chrono::seconds(10), [&] { return count_ >= n; });
  }

 private:
  std::mutex mutex_;
  std::condition_variable changed_;
  int count_ = 0;
};

TEST(Tf2Listener, TakesTfAndALateJoinersTfStaticAsTf2RosDoes) {
  graph::Context ctx(rmw::make_transport("intra"));
  auto broadcaster_node = std::make_shared<graph::Node>(ctx, "broadcaster");
  TransformBroadcaster tf(*broadcaster_node);
  StaticTransformBroadcaster tf_static(*broadcaster_node);
  // Two static sends before the listener exists: its one transient-local message holds both.
  tf_static.send({stamped("base", "camera", 0, 0.1, 0, 0)});
  tf_static.send({stamped("base", "lidar", 0, 0, 0, 0.5)});

  auto listener_node = std::make_shared<graph::Node>(ctx, "listener");
  TransformBuffer buffer("listener");
  Arrivals arrivals;
  TransformListener listener(*listener_node, buffer,
                             [&](const msgs::TFMessage&) { arrivals.add(); });
  graph::Executor executor(1);
  executor.add_node(listener_node);
  executor.start();
  ASSERT_TRUE(arrivals.wait_for(1));
  tf.send(
      {stamped("odom", "base", kSecond, 1, 0, 0), stamped("odom", "base", 2 * kSecond, 3, 0, 0)});
  auto bad = stamped("odom", "odom", kSecond, 0, 0, 0);
  tf.send({bad});
  ASSERT_TRUE(arrivals.wait_for(3));
  executor.stop();
  EXPECT_EQ(listener.refused(), 1u);
  const auto t = buffer.lookup_transform("odom", "lidar", kSecond + kSecond / 2);
  EXPECT_NEAR(t.transform.translation.x, 2, 1e-12);
  EXPECT_NEAR(t.transform.translation.z, 0.5, 1e-12);
  EXPECT_TRUE(buffer.can_transform("camera", "lidar", 12345));
  EXPECT_EQ(tf_static_broadcaster_qos().durability, rmw::Durability::kTransientLocal);
  EXPECT_EQ(tf_qos().depth, 100u);
}

}  // namespace
}  // namespace robotperf::plugin
