// Absolute trajectory error and KITTI-style drift on constructed trajectories.
#include "robotperf/localization/trajectory_metrics.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <vector>

namespace robotperf::localization {
namespace {

using Poses = std::vector<Eigen::Isometry3d>;

Eigen::Isometry3d pose(const Eigen::Vector3d& position, double yaw_rad = 0.0,
                       double pitch_rad = 0.0) {
  Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
  p.linear() = (Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(pitch_rad, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  p.translation() = position;
  return p;
}

// `count` poses 0.1 m apart along z, facing along it.
Poses straight_line(int count) {
  Poses poses;
  for (int i = 0; i < count; ++i) poses.push_back(pose({0.0, 0.0, 0.1 * i}));
  return poses;
}

// A winding path with varying orientation, for the invariance tests.
Poses winding(int count) {
  Poses poses;
  for (int i = 0; i < count; ++i) {
    const double t = 0.05 * i;
    poses.push_back(pose({2.0 * std::sin(t), 0.1 * std::sin(3.0 * t), 1.5 * t}, 0.8 * std::cos(t),
                         0.05 * std::sin(2.0 * t)));
  }
  return poses;
}

TEST(AbsoluteTrajectoryError, IsZeroForTheTruth) {
  const Poses truth = winding(100);
  const AbsoluteTrajectoryError ate = absolute_trajectory_error(truth, truth);
  EXPECT_NEAR(ate.rmse_m, 0.0, 1e-12);
  EXPECT_NEAR(ate.max_m, 0.0, 1e-12);
  EXPECT_TRUE(ate.alignment.isApprox(Eigen::Isometry3d::Identity(), 1e-9));
}

TEST(AbsoluteTrajectoryError, AlignsAwayARigidOffset) {
  const Poses truth = winding(100);
  const Eigen::Isometry3d offset = pose({1.0, -2.0, 3.0}, 0.7, -0.2);
  Poses estimate;
  for (const Eigen::Isometry3d& p : truth) estimate.push_back(offset * p);
  const AbsoluteTrajectoryError ate = absolute_trajectory_error(estimate, truth);
  EXPECT_NEAR(ate.rmse_m, 0.0, 1e-9);
  EXPECT_TRUE((ate.alignment * offset).isApprox(Eigen::Isometry3d::Identity(), 1e-9));
}

TEST(AbsoluteTrajectoryError, MeasuresWhatNoRigidMotionExplains) {
  // A square's corners against a rectangle's: the best alignment leaves 0.1 m at each corner.
  const Poses truth{pose({1, 0, 1}), pose({-1, 0, 1}), pose({-1, 0, -1}), pose({1, 0, -1})};
  const Poses estimate{pose({1.1, 0, 1}), pose({-1.1, 0, 1}), pose({-1.1, 0, -1}),
                       pose({1.1, 0, -1})};
  const AbsoluteTrajectoryError ate = absolute_trajectory_error(estimate, truth);
  EXPECT_NEAR(ate.rmse_m, 0.1, 1e-9);
  EXPECT_NEAR(ate.mean_m, 0.1, 1e-9);
  EXPECT_NEAR(ate.max_m, 0.1, 1e-9);
  // One displaced pose: no more than the unaligned error, and not zero.
  Poses displaced = truth;
  displaced[2].translation().y() += 0.2;
  const double rmse = absolute_trajectory_error(displaced, truth).rmse_m;
  EXPECT_GT(rmse, 0.01);
  EXPECT_LE(rmse, 0.2 / 2.0 + 1e-12);
}

TEST(AbsoluteTrajectoryError, DoesNotScale) {
  const Poses truth = winding(100);
  Poses estimate;
  for (const Eigen::Isometry3d& p : truth) estimate.push_back(pose(1.1 * p.translation()));
  EXPECT_GT(absolute_trajectory_error(estimate, truth).rmse_m, 0.1);
}

TEST(RelativePoseError, IsZeroForTheTruthAndUnderARigidOffset) {
  const Poses truth = winding(200);
  const Eigen::Isometry3d offset = pose({1.0, -2.0, 3.0}, 0.7, -0.2);
  Poses moved;
  for (const Eigen::Isometry3d& p : truth) moved.push_back(offset * p);
  for (const Poses& estimate : {truth, moved}) {
    const RelativePoseError rpe = relative_pose_error(estimate, truth);
    EXPECT_GT(rpe.segments, 0u);
    EXPECT_NEAR(rpe.translation_percent, 0.0, 1e-9);
    EXPECT_NEAR(rpe.rotation_deg_per_m, 0.0, 1e-9);
  }
}

TEST(RelativePoseError, ReportsAScaleDriftAsItsPercentage) {
  const Poses truth = straight_line(101);  // 10 m
  Poses estimate;
  for (const Eigen::Isometry3d& p : truth) estimate.push_back(pose(1.02 * p.translation()));
  const RelativePoseError rpe = relative_pose_error(estimate, truth);
  EXPECT_NEAR(rpe.translation_percent, 2.0, 1e-9);
  EXPECT_NEAR(rpe.rotation_deg_per_m, 0.0, 1e-12);
  ASSERT_EQ(rpe.by_length.size(), 4u);
  // Segments of L m start at every frame with L m still to go.
  const std::size_t expected_segments[] = {91, 81, 61, 21};
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_DOUBLE_EQ(rpe.by_length[i].length_m, kDefaultSegmentLengthsM[i]);
    EXPECT_EQ(rpe.by_length[i].segments, expected_segments[i]);
    EXPECT_NEAR(rpe.by_length[i].translation_percent, 2.0, 1e-9);
  }
  EXPECT_EQ(rpe.segments, 91u + 81u + 61u + 21u);
  // KITTI's spacing of first frames.
  EXPECT_EQ(relative_pose_error(estimate, truth, {1.0}, 10).segments, 10u);
}

TEST(RelativePoseError, ReportsAHeadingDriftInDegreesPerMetre) {
  const Poses truth = straight_line(101);
  Poses estimate;
  const double drift_rad_per_m = 0.5 * std::numbers::pi / 180.0;
  for (const Eigen::Isometry3d& p : truth) {
    estimate.push_back(pose(p.translation(), drift_rad_per_m * p.translation().z()));
  }
  const RelativePoseError rpe = relative_pose_error(estimate, truth, {1.0, 5.0});
  EXPECT_NEAR(rpe.rotation_deg_per_m, 0.5, 1e-9);
  EXPECT_NEAR(rpe.by_length[1].rotation_deg_per_m, 0.5, 1e-9);
  EXPECT_GT(rpe.translation_percent, 0.0);
}

TEST(RelativePoseError, HasNoSegmentsOnATooShortTrajectory) {
  const Poses truth = straight_line(11);  // 1 m
  const RelativePoseError rpe = relative_pose_error(truth, truth, {2.0});
  EXPECT_EQ(rpe.segments, 0u);
  EXPECT_TRUE(std::isnan(rpe.translation_percent));
  EXPECT_TRUE(std::isnan(rpe.by_length[0].rotation_deg_per_m));
}

TEST(TrajectoryMetrics, RejectBadInput) {
  const Poses three = straight_line(3);
  const Poses two = straight_line(2);
  const Poses one = straight_line(1);
  EXPECT_THROW(absolute_trajectory_error(three, two), std::invalid_argument);
  EXPECT_THROW(absolute_trajectory_error(one, one), std::invalid_argument);
  EXPECT_THROW(absolute_trajectory_error({}, {}), std::invalid_argument);
  EXPECT_THROW(relative_pose_error(three, two), std::invalid_argument);
  EXPECT_THROW(relative_pose_error(one, one), std::invalid_argument);
  EXPECT_THROW(relative_pose_error(two, two, {}), std::invalid_argument);
  EXPECT_THROW(relative_pose_error(two, two, {1.0, -1.0}), std::invalid_argument);
  EXPECT_THROW(relative_pose_error(two, two, {std::numeric_limits<double>::infinity()}),
               std::invalid_argument);
  EXPECT_THROW(relative_pose_error(two, two, {1.0}, 0), std::invalid_argument);
  EXPECT_NO_THROW(relative_pose_error(two, two, {0.1}));
}

}  // namespace
}  // namespace robotperf::localization
