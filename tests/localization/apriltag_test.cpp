// b3: the AprilTag detector on constructed frames with known answers, the rendered dataset, and
// the evaluator that judges detections against its truth.
#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "robotperf/localization/apriltag_detector.hpp"
#include "robotperf/localization/synthetic_apriltags.hpp"
#include "robotperf/plugin/registry.hpp"

namespace robotperf::localization {
namespace {

// Facing the camera upright: the tag's x is the camera's x, its y and z the camera's -y and -z
// (a half turn about x).
msgs::Pose facing_pose(double x, double y, double z) {
  msgs::Pose p;
  p.position = {x, y, z};
  p.orientation = {1.0, 0.0, 0.0, 0.0};
  return p;
}

struct Detected {
  msgs::AprilTagDetectionArray tags;
  msgs::PoseArray poses;
};

Detected detect(const AprilTagFrame& frame, AprilTagParams params = {}) {
  AprilTagDetector detector(params);
  Detected out;
  detector.detect(frame.image, frame.info, out.tags, out.poses);
  return out;
}

double corner_error(const msgs::AprilTagDetection& a, const msgs::AprilTagDetection& b) {
  double worst = 0.0;
  for (std::size_t c = 0; c < 4; ++c) {
    worst = std::max(worst,
                     std::hypot(a.corners[c].x - b.corners[c].x, a.corners[c].y - b.corners[c].y));
  }
  return worst;
}

TEST(AprilTag, AFrontoParallelTagAtKnownDistanceGivesItsCornersAndPose) {
  const AprilTagFrame frame = render_apriltag_frame({}, {{5, facing_pose(0.1, -0.05, 2.0)}});
  ASSERT_EQ(frame.tags.detections.size(), 1u);
  const Detected found = detect(frame);
  ASSERT_EQ(found.tags.detections.size(), 1u);
  ASSERT_EQ(found.poses.poses.size(), 1u);
  const auto& d = found.tags.detections[0];
  EXPECT_EQ(d.id, 5);
  EXPECT_EQ(d.family, "36h11");
  EXPECT_EQ(d.hamming, 0);
  EXPECT_EQ(found.tags.header, frame.image.header);
  // Sub-pixel corners in ROS's pixel convention, in libapriltag's order.
  EXPECT_LT(corner_error(d, frame.tags.detections[0]), 0.5);
  EXPECT_NEAR(d.centre.x, frame.tags.detections[0].centre.x, 0.3);
  EXPECT_NEAR(d.centre.y, frame.tags.detections[0].centre.y, 0.3);
  // The homography maps the tag's (1, 1) corner onto the reported corner 1... (y down: (1, 1)).
  const auto& h = d.homography;
  const double w = h[6] + h[7] + h[8];
  EXPECT_NEAR((h[0] + h[1] + h[2]) / w, d.corners[1].x, 0.05);
  EXPECT_NEAR((h[3] + h[4] + h[5]) / w, d.corners[1].y, 0.05);
  const msgs::Pose& p = found.poses.poses[0];
  EXPECT_NEAR(p.position.x, 0.1, 0.005);
  EXPECT_NEAR(p.position.y, -0.05, 0.005);
  EXPECT_NEAR(p.position.z, 2.0, 0.01);
  // The orientation as placed within 5 degrees (q and -q are one rotation): facing the camera is
  // the hardest case, every corner at the same depth.
  EXPECT_GT(std::abs(p.orientation.x), std::cos(5.0 * M_PI / 360.0));
}

TEST(AprilTag, AWrongTagSizeScalesTheDistance) {
  const AprilTagFrame frame = render_apriltag_frame({}, {{9, facing_pose(0.0, 0.0, 2.0)}});
  AprilTagParams wrong;
  wrong.size = 0.20;
  const Detected found = detect(frame, wrong);
  ASSERT_EQ(found.poses.poses.size(), 1u);
  EXPECT_NEAR(found.poses.poses[0].position.z, 2.0 * 0.20 / 0.22, 0.01);
}

// A camera whose images are not rectified: the same tags seen through a lens with barrel
// distortion are found at their ideal corners only when the node rectifies first.
TEST(AprilTag, RectifyingFirstFindsTheTagsOfADistortedCamera) {
  const AprilTagFrame ideal = render_apriltag_frame(
      {}, {{7, facing_pose(-0.55, 0.25, 1.6)}, {8, facing_pose(0.6, -0.25, 1.8)}});
  msgs::CameraInfo lens = ideal.info;
  lens.d = {-0.25, 0.08, 0.0, 0.0, 0.0};
  // Each pixel of the distorted image shows the ideal image where its undistorted ray goes.
  const cv::Mat k(3, 3, CV_64F, lens.k.data());
  std::vector<cv::Point2f> pixels;
  for (uint32_t v = 0; v < lens.height; ++v)
    for (uint32_t u = 0; u < lens.width; ++u) pixels.emplace_back(u, v);
  std::vector<cv::Point2f> sources;
  cv::undistortPoints(pixels, sources, k, lens.d, cv::noArray(), k);
  const cv::Mat map(static_cast<int>(lens.height), static_cast<int>(lens.width), CV_32FC2,
                    sources.data());
  msgs::Image distorted = ideal.image;
  const cv::Mat from(static_cast<int>(ideal.image.height), static_cast<int>(ideal.image.width),
                     CV_8UC3, const_cast<uint8_t*>(ideal.image.data.data()));
  cv::Mat to(from.size(), CV_8UC3, distorted.data.data());
  cv::remap(from, to, map, cv::noArray(), cv::INTER_LINEAR);

  auto worst_corner = [&](bool rectify) {
    AprilTagParams params;
    params.rectify = rectify;
    AprilTagDetector detector(params);
    msgs::AprilTagDetectionArray tags;
    msgs::PoseArray poses;
    detector.detect(distorted, lens, tags, poses);
    EXPECT_EQ(tags.detections.size(), 2u) << rectify;
    double worst = 0.0;
    for (const auto& d : tags.detections) {
      for (const auto& t : ideal.tags.detections) {
        if (t.id == d.id) worst = std::max(worst, corner_error(d, t));
      }
    }
    return worst;
  };
  EXPECT_LT(worst_corner(true), 1.0);
  EXPECT_GT(worst_corner(false), 3.0);
}

TEST(AprilTag, EveryEncodingGivesTheSameTagsAndBadInputIsRefused) {
  const AprilTagFrame frame = render_apriltag_frame({}, {{3, facing_pose(0.0, 0.0, 1.5)}});
  msgs::Image mono = frame.image;
  mono.encoding = "mono8";
  mono.step = mono.width;
  mono.data.resize(static_cast<std::size_t>(mono.width) * mono.height);
  for (std::size_t i = 0; i < mono.data.size(); ++i) mono.data[i] = frame.image.data[3 * i];
  AprilTagDetector detector({});
  msgs::AprilTagDetectionArray tags;
  msgs::PoseArray poses;
  detector.detect(mono, frame.info, tags, poses);
  ASSERT_EQ(tags.detections.size(), 1u);
  EXPECT_LT(corner_error(tags.detections[0], frame.tags.detections[0]), 0.5);

  msgs::Image depth = mono;
  depth.encoding = "32FC1";
  EXPECT_THROW(detector.detect(depth, frame.info, tags, poses), std::invalid_argument);
  msgs::CameraInfo small = frame.info;
  small.width = 640;
  EXPECT_THROW(detector.detect(mono, small, tags, poses), std::invalid_argument);
  msgs::CameraInfo uncalibrated = frame.info;
  uncalibrated.p[0] = 0.0;
  EXPECT_THROW(detector.detect(mono, uncalibrated, tags, poses), std::invalid_argument);

  AprilTagParams bad;
  bad.family = "99h1";
  EXPECT_THROW(AprilTagDetector{bad}, std::invalid_argument);
  bad = {};
  bad.max_hamming = 3;
  EXPECT_THROW(AprilTagDetector{bad}, std::invalid_argument);
  bad = {};
  bad.decimate = 0.5;
  EXPECT_THROW(AprilTagDetector{bad}, std::invalid_argument);
  EXPECT_THROW(render_apriltag_frame({}, {{3, facing_pose(5.0, 0.0, 1.0)}}), std::invalid_argument);
  EXPECT_THROW(render_apriltag_frame({}, {{9999, facing_pose(0.0, 0.0, 1.0)}}),
               std::invalid_argument);
}

TEST(AprilTagDataset, IsTheSameEveryTimeAndHoldsWhatItPromises) {
  SyntheticAprilTagConfig config;
  config.frames = 4;
  const auto a = generate_apriltag_sequence(config);
  const auto b = generate_apriltag_sequence(config);
  ASSERT_EQ(a.size(), 4u);
  std::size_t occluded = 0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].image, b[k].image);
    EXPECT_EQ(a[k].tags, b[k].tags);
    EXPECT_EQ(a[k].poses.poses.size(), a[k].tags.detections.size());
    EXPECT_EQ(a[k].image.header.stamp.to_ns(), std::llround(k * 1e9 / 30.0));
    for (const auto& t : a[k].tags.detections) occluded += t.goodness < 1.0f ? 1 : 0;
  }
  // Frame k holds tags_per_frame[k] tags (8, 16, 32, 64): 64 fit beside each other.
  EXPECT_EQ(a[0].tags.detections.size(), 8u);
  EXPECT_EQ(a[3].tags.detections.size(), 64u);
  EXPECT_GT(occluded, 0u);
}

// The evaluator over a whole rendered sequence, fed the detector's answers: the thresholds of
// b3 hold, and a kernel with a wrong tag size is caught by the pose error.
TEST(AprilTagDataset, TheDetectorMeetsB3sThresholdsAndAWrongSizeDoesNot) {
  const auto* dataset = plugin::registry().find_dataset("localization/apriltags");
  const auto* evaluator = plugin::registry().find_evaluator("apriltag_detection");
  ASSERT_NE(dataset, nullptr);
  ASSERT_NE(evaluator, nullptr);
  const auto streams = dataset->generate(plugin::Parameters({}, {}, "test"));
  ASSERT_EQ(streams.size(), 4u);
  const plugin::TruthStreams truth("apriltag_detection",
                                   {{"tags", &streams[2]}, {"poses", &streams[3]}});
  const plugin::Parameters parameters(evaluator->info.parameters, {}, "test");

  auto evaluate = [&](const AprilTagParams& params) {
    auto e = evaluator->make(truth, parameters);
    AprilTagDetector detector(params);
    for (std::size_t k = 0; k < streams[0].messages.size(); ++k) {
      msgs::AprilTagDetectionArray tags;
      msgs::PoseArray poses;
      detector.detect(*static_cast<const msgs::Image*>(streams[0].messages[k].get()),
                      *static_cast<const msgs::CameraInfo*>(streams[1].messages[k].get()), tags,
                      poses);
      e->add_observed(&tags, &poses, k);
    }
    EXPECT_TRUE(e->problems().empty());
    return e->metrics();
  };
  const auto good = evaluate({});
  EXPECT_GE(good.at("recall"), 0.99);
  EXPECT_GE(good.at("precision"), 0.99);
  EXPECT_LE(good.at("corner_rms_px"), 0.5);
  EXPECT_LE(good.at("translation_error_median_m"), 0.03);
  EXPECT_LE(good.at("rotation_error_median_deg"), 3.0);
  EXPECT_EQ(good.at("outputs_without_poses"), 0.0);
  EXPECT_LT(good.at("recall_occluded"), good.at("recall"));

  AprilTagParams wrong;
  wrong.size = 0.20;
  const auto bad = evaluate(wrong);
  EXPECT_GE(bad.at("recall"), 0.99);                     // the corners are right...
  EXPECT_GT(bad.at("translation_error_median_m"), 0.1);  // ...the distances are not
}

}  // namespace
}  // namespace robotperf::localization
