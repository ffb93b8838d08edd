// The synthetic stereo odometry sequence: camera model, trajectory, stereo geometry, noise and
// determinism.
#include "robotperf/localization/synthetic_odometry.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <opencv2/core.hpp>
#include <stdexcept>
#include <vector>

namespace robotperf::localization {
namespace {

SyntheticOdometryConfig short_config(uint32_t frames) {
  SyntheticOdometryConfig config;
  config.frames = frames;
  return config;
}

// FNV-1a over every pixel and every pose bit of a sequence.
uint64_t sequence_hash(const OdometrySequence& sequence) {
  uint64_t hash = 0xcbf29ce484222325ULL;
  auto add = [&hash](const void* data, std::size_t size) {
    const auto* bytes = static_cast<const uint8_t*>(data);
    for (std::size_t i = 0; i < size; ++i) {
      hash ^= bytes[i];
      hash *= 0x100000001b3ULL;
    }
  };
  for (const OdometryFrame& frame : sequence.frames) {
    for (const cv::Mat* image : {&frame.left, &frame.right}) {
      for (int v = 0; v < image->rows; ++v)
        add(image->ptr(v), static_cast<std::size_t>(image->cols));
    }
    add(frame.left_in_world.matrix().data(), 16 * sizeof(double));
  }
  return hash;
}

double angle_deg(const Eigen::Matrix3d& r) {
  return Eigen::AngleAxisd(r).angle() * 180.0 / std::numbers::pi;
}

TEST(SyntheticOdometry, CameraIsThePerceptionPinholeConvention) {
  const StereoCamera camera = odometry_camera();
  EXPECT_EQ(camera.width, 640);
  EXPECT_EQ(camera.height, 480);
  EXPECT_NEAR(camera.fx, 320.0 / std::tan(0.55), 1e-9);
  EXPECT_DOUBLE_EQ(camera.fy, camera.fx);
  EXPECT_DOUBLE_EQ(camera.cx, 320.0);
  EXPECT_DOUBLE_EQ(camera.cy, 240.0);
  EXPECT_DOUBLE_EQ(camera.baseline_m, 0.12);
}

TEST(SyntheticOdometry, FramesFollowTheTrajectoryAt20Hz) {
  const OdometrySequence sequence = generate_odometry_sequence(short_config(4));
  ASSERT_EQ(sequence.frames.size(), 4u);
  for (std::size_t k = 0; k < sequence.frames.size(); ++k) {
    const OdometryFrame& frame = sequence.frames[k];
    EXPECT_DOUBLE_EQ(frame.stamp_s, k / 20.0);
    EXPECT_EQ(frame.left.type(), CV_8UC1);
    EXPECT_EQ(frame.right.size(), cv::Size(640, 480));
    EXPECT_TRUE(frame.left_in_world.isApprox(odometry_trajectory_pose(k / 20.0), 0.0));
    EXPECT_TRUE(frame.left_in_first.isApprox(
        sequence.frames[0].left_in_world.inverse() * frame.left_in_world, 1e-12));
  }
  EXPECT_TRUE(sequence.frames[0].left_in_first.isApprox(Eigen::Isometry3d::Identity(), 1e-12));
  EXPECT_GT(sequence.frames[0].left_in_world.translation().norm(), 0.5);
}

TEST(SyntheticOdometry, TrajectoryIsASmoothLapOfAbout16Metres) {
  double length = 0.0;
  double max_step = 0.0;
  double max_turn_deg = 0.0;
  Eigen::Isometry3d previous = odometry_trajectory_pose(0.0);
  for (int k = 1; k <= 300; ++k) {
    const Eigen::Isometry3d pose = odometry_trajectory_pose(k / 20.0);
    const double step = (pose.translation() - previous.translation()).norm();
    length += step;
    max_step = std::max(max_step, step);
    max_turn_deg = std::max(max_turn_deg, angle_deg(previous.linear().transpose() * pose.linear()));
    // The camera's axes stay orthonormal, y (down) near the world's.
    EXPECT_TRUE((pose.linear().transpose() * pose.linear()).isIdentity(1e-12));
    EXPECT_GT(pose.linear()(1, 1), 0.99);
    previous = pose;
  }
  EXPECT_NEAR(length, 16.5, 0.2);
  EXPECT_LT(max_step, 0.085);    // 1.6 m/s at most
  EXPECT_LT(max_turn_deg, 3.5);  // per frame: 65 deg/s at most
  EXPECT_GT(max_turn_deg, 2.5);
  // Periodic: the lap closes after 15 s.
  EXPECT_TRUE(odometry_trajectory_pose(15.0).isApprox(odometry_trajectory_pose(0.0), 1e-9));
}

TEST(SyntheticOdometry, ImagesAreTexturedEverywhere) {
  const StereoPair pair = render_odometry_stereo_pair(odometry_trajectory_pose(3.3));
  for (const cv::Mat* image : {&pair.left, &pair.right}) {
    cv::Scalar mean, stddev;
    cv::meanStdDev(*image, mean, stddev);
    EXPECT_GT(stddev[0], 25.0);
    double lowest = 0;
    cv::minMaxLoc(*image, &lowest);
    EXPECT_GT(lowest, 0.0);  // no ray leaves the room
  }
}

TEST(SyntheticOdometry, RightCameraIsTheLeftMovedAlongItsX) {
  const Eigen::Isometry3d left = odometry_trajectory_pose(6.1);
  Eigen::Isometry3d moved = left;
  moved.translation() += 0.12 * left.linear().col(0);
  const StereoPair pair = render_odometry_stereo_pair(left);
  const StereoPair from_right = render_odometry_stereo_pair(moved);
  cv::Mat differ;
  cv::compare(pair.right, from_right.left, differ, cv::CMP_NE);
  EXPECT_LE(cv::countNonZero(differ), 30);  // rounding of the centre at most, at edges
  // And not the left image: the views differ by the parallax.
  EXPECT_GT(cv::norm(pair.left, pair.right, cv::NORM_L1) / pair.left.total(), 5.0);
}

TEST(SyntheticOdometry, NoiseIsZeroMeanWithTheRequestedSpread) {
  SyntheticOdometryConfig noisy = short_config(1);
  noisy.noise_stddev = 3.0;
  const Eigen::Isometry3d pose = odometry_trajectory_pose(1.0);
  const StereoPair clean = render_odometry_stereo_pair(pose);
  const StereoPair with_noise = render_odometry_stereo_pair(pose, noisy);
  cv::Mat difference;
  cv::subtract(with_noise.left, clean.left, difference, cv::noArray(), CV_32F);
  cv::Scalar mean, stddev;
  cv::meanStdDev(difference, mean, stddev);
  EXPECT_NEAR(mean[0], 0.0, 0.05);
  EXPECT_NEAR(stddev[0], 3.0, 0.15);
  // Independent per camera and per frame.
  cv::Mat right_difference;
  cv::subtract(with_noise.right, clean.right, right_difference, cv::noArray(), CV_32F);
  EXPECT_GT(cv::norm(difference, right_difference, cv::NORM_L1) / difference.total(), 2.0);
  const StereoPair next = render_odometry_stereo_pair(pose, noisy, 1);
  EXPECT_GT(cv::norm(with_noise.left, next.left, cv::NORM_L1) / difference.total(), 2.0);
}

TEST(SyntheticOdometry, IsDeterministicAndThreadCountIndependent) {
  const OdometrySequence first = generate_odometry_sequence(short_config(3));
  const OdometrySequence again = generate_odometry_sequence(short_config(3));
  const int threads = cv::getNumThreads();
  cv::setNumThreads(1);
  const OdometrySequence single_threaded = generate_odometry_sequence(short_config(3));
  cv::setNumThreads(threads);
  EXPECT_EQ(sequence_hash(again), sequence_hash(first));
  EXPECT_EQ(sequence_hash(single_threaded), sequence_hash(first));
  // A frame rendered alone is the sequence's frame.
  const StereoPair alone = render_odometry_stereo_pair(first.frames[2].left_in_world, {}, 2);
  EXPECT_EQ(cv::norm(alone.left, first.frames[2].left, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(alone.right, first.frames[2].right, cv::NORM_INF), 0.0);
  // Pinned: a change here changes the benchmark's dataset.
  EXPECT_EQ(sequence_hash(first), 0x794d51bb13a8b09bULL);
}

TEST(SyntheticOdometry, RejectsInvalidConfigs) {
  auto expect_invalid = [](auto change) {
    SyntheticOdometryConfig config = short_config(1);
    change(config);
    EXPECT_THROW(generate_odometry_sequence(config), std::invalid_argument);
    EXPECT_THROW(render_odometry_stereo_pair(Eigen::Isometry3d::Identity(), config),
                 std::invalid_argument);
  };
  expect_invalid([](SyntheticOdometryConfig& c) { c.width = 8; });
  expect_invalid([](SyntheticOdometryConfig& c) { c.height = 10000; });
  expect_invalid([](SyntheticOdometryConfig& c) { c.frames = 0; });
  expect_invalid([](SyntheticOdometryConfig& c) { c.rate_hz = 0.0; });
  expect_invalid([](SyntheticOdometryConfig& c) { c.baseline_m = -0.1; });
  expect_invalid([](SyntheticOdometryConfig& c) { c.hfov_rad = std::numbers::pi; });
  expect_invalid([](SyntheticOdometryConfig& c) { c.noise_stddev = -1.0; });
  expect_invalid([](SyntheticOdometryConfig& c) { c.noise_stddev = std::nan(""); });
}

}  // namespace
}  // namespace robotperf::localization
