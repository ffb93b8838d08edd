// Stereo visual odometry (b1) on the synthetic sequence: known motions, the whole lap's drift,
// a perturbed camera model, bad frames and bad inputs.
#include "robotperf/localization/stereo_odometry.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "robotperf/localization/synthetic_odometry.hpp"
#include "robotperf/localization/trajectory_metrics.hpp"

namespace robotperf::localization {
namespace {

double angle_deg(const Eigen::Matrix3d& r) {
  return Eigen::AngleAxisd(r).angle() * 180.0 / std::numbers::pi;
}

StereoOdometry odometry_for(const StereoCamera& c, double focal_scale = 1.0,
                            const StereoOdometryOptions& options = {}) {
  return StereoOdometry(c.fx * focal_scale, c.fy * focal_scale, c.cx, c.cy, c.baseline_m, options);
}

Eigen::Isometry3d motion(double x, double y, double z, double yaw_deg, double pitch_deg) {
  Eigen::Isometry3d m = Eigen::Isometry3d::Identity();
  m.linear() = (Eigen::AngleAxisd(yaw_deg * std::numbers::pi / 180.0, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(pitch_deg * std::numbers::pi / 180.0, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  m.translation() = Eigen::Vector3d(x, y, z);
  return m;
}

// The odometry of a pair rendered at `start` and one rendered at start * relative (the motion
// in the first camera's frame).
void expect_recovers(const Eigen::Isometry3d& start, const Eigen::Isometry3d& relative) {
  const StereoCamera camera = odometry_camera();
  StereoOdometry odometry = odometry_for(camera);
  const StereoPair first = render_odometry_stereo_pair(start);
  const StereoPair second = render_odometry_stereo_pair(start * relative);
  const StereoOdometryResult initial = odometry.process(first.left, first.right);
  EXPECT_TRUE(initial.pose.isApprox(Eigen::Isometry3d::Identity()));
  EXPECT_TRUE(initial.new_keyframe);
  const StereoOdometryResult result = odometry.process(second.left, second.right);
  ASSERT_FALSE(result.tracking_lost);
  EXPECT_GT(result.inliers, 100);
  EXPECT_LT((result.pose.translation() - relative.translation()).norm(), 0.01);
  EXPECT_LT(angle_deg(result.pose.linear().transpose() * relative.linear()), 0.2);
}

TEST(StereoOdometryTwoFrames, RecoversAForwardTurningMotion) {
  expect_recovers(odometry_trajectory_pose(0.0), motion(0.03, 0.01, 0.12, 3.0, 0.5));
}

TEST(StereoOdometryTwoFrames, RecoversASidewaysPitchingMotion) {
  expect_recovers(odometry_trajectory_pose(8.0), motion(-0.08, -0.02, 0.02, -1.0, 2.0));
}

TEST(StereoOdometryTwoFrames, RecoversALargeMotionWithoutAPrediction) {
  // 0.3 m and 8 degrees: features move 70 px and more, beyond the first search radius.
  expect_recovers(odometry_trajectory_pose(3.0), motion(0.0, 0.0, 0.3, 8.0, 0.0));
}

TEST(StereoOdometryTwoFrames, StandsStillOnTheSamePair) {
  const StereoCamera camera = odometry_camera();
  StereoOdometry odometry = odometry_for(camera);
  const StereoPair pair = render_odometry_stereo_pair(odometry_trajectory_pose(4.0));
  odometry.process(pair.left, pair.right);
  for (int i = 0; i < 3; ++i) {
    const StereoOdometryResult result = odometry.process(pair.left, pair.right);
    EXPECT_FALSE(result.tracking_lost);
    EXPECT_FALSE(result.new_keyframe);
    EXPECT_LT(result.pose.translation().norm(), 1e-3);
    EXPECT_LT(angle_deg(result.pose.linear()), 0.01);
  }
}

// The whole default lap, generated once for the tests that run on it.
class StereoOdometryLap : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { sequence_ = new OdometrySequence(generate_odometry_sequence()); }
  static void TearDownTestSuite() {
    delete sequence_;
    sequence_ = nullptr;
  }

  struct Run {
    std::vector<Eigen::Isometry3d> estimate, truth;
    std::vector<StereoOdometryResult> results;
  };

  static Run run(StereoOdometry& odometry, std::size_t frames) {
    Run r;
    for (std::size_t i = 0; i < frames; ++i) {
      const OdometryFrame& frame = sequence_->frames[i];
      r.results.push_back(odometry.process(frame.left, frame.right));
      r.estimate.push_back(r.results.back().pose);
      r.truth.push_back(frame.left_in_first);
    }
    return r;
  }

  static OdometrySequence* sequence_;
};
OdometrySequence* StereoOdometryLap::sequence_ = nullptr;

TEST_F(StereoOdometryLap, DriftsLessThanTwoPercent) {
  StereoOdometry odometry = odometry_for(sequence_->camera);
  const Run r = run(odometry, sequence_->frames.size());
  const RelativePoseError rpe = relative_pose_error(r.estimate, r.truth);
  const AbsoluteTrajectoryError ate = absolute_trajectory_error(r.estimate, r.truth);
  EXPECT_LE(rpe.translation_percent, 2.0);
  EXPECT_LE(rpe.rotation_deg_per_m, 0.3);
  EXPECT_LT(ate.rmse_m, 0.05);
  int keyframes = 0;
  for (const StereoOdometryResult& result : r.results) {
    EXPECT_FALSE(result.tracking_lost);
    EXPECT_LE(result.features, odometry.options().max_features);
    EXPECT_LE(result.stereo_matches, result.features);
    EXPECT_LE(result.inliers, result.tracked);
    keyframes += result.new_keyframe ? 1 : 0;
  }
  // Keyframes come and go with the view, but not every frame.
  EXPECT_GT(keyframes, 5);
  EXPECT_LT(keyframes, 150);
}

TEST_F(StereoOdometryLap, WrongFocalLengthDriftsClearlyMore) {
  StereoOdometry odometry = odometry_for(sequence_->camera, 1.1);
  const Run r = run(odometry, sequence_->frames.size());
  const RelativePoseError rpe = relative_pose_error(r.estimate, r.truth);
  const AbsoluteTrajectoryError ate = absolute_trajectory_error(r.estimate, r.truth);
  EXPECT_GT(rpe.translation_percent, 5.0);
  EXPECT_GT(ate.rmse_m, 0.1);
}

TEST_F(StereoOdometryLap, CoastsThroughABlankFrameAndRecovers) {
  StereoOdometry odometry = odometry_for(sequence_->camera);
  const cv::Mat blank = cv::Mat::zeros(480, 640, CV_8UC1);
  std::vector<Eigen::Isometry3d> estimate, truth;
  for (std::size_t i = 0; i < 60; ++i) {
    const OdometryFrame& frame = sequence_->frames[i];
    const bool blanked = i == 20;
    const StereoOdometryResult result =
        blanked ? odometry.process(blank, blank) : odometry.process(frame.left, frame.right);
    if (blanked) {
      EXPECT_TRUE(result.tracking_lost);
      EXPECT_EQ(result.features, 0);
      EXPECT_FALSE(result.new_keyframe);
      // Constant velocity: the step repeats the previous one.
      const Eigen::Isometry3d step = estimate[19].inverse() * result.pose;
      const Eigen::Isometry3d previous_step = estimate[18].inverse() * estimate[19];
      EXPECT_TRUE(step.isApprox(previous_step, 1e-9));
    } else {
      EXPECT_FALSE(result.tracking_lost) << "frame " << i;
    }
    estimate.push_back(result.pose);
    truth.push_back(frame.left_in_first);
  }
  EXPECT_LT((estimate.back().translation() - truth.back().translation()).norm(), 0.05);
}

TEST_F(StereoOdometryLap, LosesTrackingOnAnUnrelatedViewWithoutThrowing) {
  StereoOdometry odometry = odometry_for(sequence_->camera);
  run(odometry, 5);
  // A view from the other side of the room: no keyframe point is where it is predicted.
  const StereoPair elsewhere = render_odometry_stereo_pair(odometry_trajectory_pose(7.5));
  const StereoOdometryResult lost = odometry.process(elsewhere.left, elsewhere.right);
  EXPECT_TRUE(lost.tracking_lost);
  EXPECT_TRUE(lost.new_keyframe);  // restarts from it
  EXPECT_TRUE(lost.pose.matrix().allFinite());
}

TEST_F(StereoOdometryLap, ResetStartsAgainAtIdentity) {
  StereoOdometry odometry = odometry_for(sequence_->camera);
  run(odometry, 10);
  odometry.reset();
  const OdometryFrame& frame = sequence_->frames[50];
  const StereoOdometryResult result = odometry.process(frame.left, frame.right);
  EXPECT_TRUE(result.pose.isApprox(Eigen::Isometry3d::Identity()));
  EXPECT_TRUE(result.new_keyframe);
}

TEST(StereoOdometryInput, RejectsBadIntrinsicsAndOptions) {
  EXPECT_THROW(StereoOdometry(0.0, 500, 320, 240, 0.12), std::invalid_argument);
  EXPECT_THROW(StereoOdometry(500, -1.0, 320, 240, 0.12), std::invalid_argument);
  EXPECT_THROW(StereoOdometry(500, 500, std::nan(""), 240, 0.12), std::invalid_argument);
  EXPECT_THROW(StereoOdometry(500, 500, 320, std::numeric_limits<double>::infinity(), 0.12),
               std::invalid_argument);
  EXPECT_THROW(StereoOdometry(500, 500, 320, 240, 0.0), std::invalid_argument);
  // A calibration's right principal point left out is NaN, and refused.
  EXPECT_THROW(StereoOdometry({.fx = 500, .fy = 500, .cx = 320, .cy = 240, .baseline_m = 0.12}),
               std::invalid_argument);
  EXPECT_NO_THROW(StereoOdometry(
      {.fx = 500, .fy = 500, .cx = 320, .cy = 240, .right_cx = 312, .baseline_m = 0.12}));
  auto expect_invalid = [](auto change) {
    StereoOdometryOptions options;
    change(options);
    EXPECT_THROW(StereoOdometry(500, 500, 320, 240, 0.12, options), std::invalid_argument);
  };
  expect_invalid([](StereoOdometryOptions& o) { o.max_features = 0; });
  expect_invalid([](StereoOdometryOptions& o) { o.grid_rows = 0; });
  expect_invalid([](StereoOdometryOptions& o) { o.fast_threshold = 300; });
  expect_invalid([](StereoOdometryOptions& o) { o.max_disparity_px = o.min_disparity_px; });
  expect_invalid([](StereoOdometryOptions& o) { o.ratio = 1.5; });
  expect_invalid([](StereoOdometryOptions& o) { o.search_radius_px = 0.0; });
  expect_invalid([](StereoOdometryOptions& o) { o.min_inliers = 3; });
  expect_invalid([](StereoOdometryOptions& o) { o.keyframe_inlier_fraction = 2.0; });
  try {
    StereoOdometry(500, 500, 320, 240, -0.1);
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("baseline"), std::string::npos) << e.what();
  }
}

TEST(StereoOdometryInput, RejectsImagesOfTheWrongTypeOrSize) {
  StereoOdometry odometry(500, 500, 320, 240, 0.12);
  const cv::Mat grey = cv::Mat::zeros(480, 640, CV_8UC1);
  EXPECT_THROW(odometry.process(cv::Mat::zeros(480, 640, CV_8UC3), grey), std::invalid_argument);
  EXPECT_THROW(odometry.process(grey, cv::Mat::zeros(480, 640, CV_16UC1)), std::invalid_argument);
  EXPECT_THROW(odometry.process(cv::Mat(), grey), std::invalid_argument);
  EXPECT_THROW(odometry.process(grey, cv::Mat::zeros(480, 600, CV_8UC1)), std::invalid_argument);
  EXPECT_THROW(odometry.process(cv::Mat::zeros(32, 32, CV_8UC1), cv::Mat::zeros(32, 32, CV_8UC1)),
               std::invalid_argument);
  // The first frame fixes the size.
  EXPECT_NO_THROW(odometry.process(grey, grey));
  const cv::Mat smaller = cv::Mat::zeros(240, 320, CV_8UC1);
  EXPECT_THROW(odometry.process(smaller, smaller), std::invalid_argument);
  EXPECT_NO_THROW(odometry.process(grey, grey));
}

}  // namespace
}  // namespace robotperf::localization
