// The localization evaluators judge what the kernels answer: right answers pass b1-b3's
// thresholds, and a kernel fed or configured wrongly is caught.
#include <gtest/gtest.h>

#include <cmath>

#include "robotperf/localization/scan_matcher.hpp"
#include "robotperf/localization/stereo_odometry.hpp"
#include "robotperf/msgs/eigen_geometry.hpp"
#include "robotperf/msgs/geometry_msgs.hpp"
#include "robotperf/msgs/nav_msgs.hpp"
#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/perception/image_proc.hpp"
#include "robotperf/plugin/registry.hpp"

namespace robotperf::localization {
namespace {

using plugin::registry;

struct Streams {
  std::vector<plugin::DatasetStream> streams;
  const plugin::DatasetStream& operator[](const std::string& name) const {
    for (const auto& s : streams)
      if (s.name == name) return s;
    throw std::invalid_argument("no stream " + name);
  }
};

Streams generate(const std::string& dataset) {
  const auto* entry = registry().find_dataset(dataset);
  EXPECT_NE(entry, nullptr) << dataset;
  return {entry->generate(plugin::Parameters(entry->info.workload, {}, "test"))};
}

std::unique_ptr<plugin::FunctionalEvaluator> evaluator(
    const std::string& name, std::map<std::string, const plugin::DatasetStream*> truth) {
  const auto* entry = registry().find_evaluator(name);
  EXPECT_NE(entry, nullptr) << name;
  return entry->make(plugin::TruthStreams(name, std::move(truth)),
                     plugin::Parameters(entry->info.parameters, {}, "test"));
}

// b2: the localizer's answers on the dataset's scans, and on the same scans from a scanner whose
// ranges read 20 % long (a miscalibration), which must fail the success threshold.
TEST(LocalizationEvaluators, MapLocalizationPassesAndAMiscalibratedScannerFails) {
  const Streams data = generate("localization/map_scans");
  const auto& grid = *static_cast<const msgs::OccupancyGrid*>(data["map"].messages[0].get());
  GridMap map{grid.info.width,
              grid.info.height,
              grid.info.resolution,
              grid.info.origin.position.x,
              grid.info.origin.position.y,
              grid.data};
  const GlobalLocalizer localizer(map);
  auto judge = [&](double range_scale, std::size_t frames) {
    auto e = evaluator("map_localization", {{"pose", &data["pose_truth"]}});
    for (std::size_t k = 0; k < frames; ++k) {
      const auto& in = *static_cast<const msgs::LaserScan*>(data["scan"].messages[k].get());
      Scan scan{in.angle_min, in.angle_increment, in.range_min, in.range_max, in.ranges};
      for (float& r : scan.ranges) r *= static_cast<float>(range_scale);
      const LocalizationResult r = localizer.localize(scan);
      msgs::PoseWithCovarianceStamped out;
      out.header.frame_id = "map";
      out.pose.pose.position = {r.x, r.y, 0.0};
      out.pose.pose.orientation = {0.0, 0.0, std::sin(r.yaw / 2), std::cos(r.yaw / 2)};
      const std::size_t index[3] = {0, 1, 5};
      for (std::size_t i = 0; i < 3; ++i)
        for (std::size_t j = 0; j < 3; ++j)
          out.pose.covariance[6 * index[i] + index[j]] = r.covariance[3 * i + j];
      e->add(&out, k);
    }
    EXPECT_TRUE(e->problems().empty());
    return e->metrics();
  };
  const auto good = judge(1.0, data["scan"].messages.size());
  EXPECT_GE(good.at("success_rate"), 0.98);
  EXPECT_LE(good.at("position_error_median_m"), 0.05);
  EXPECT_LE(good.at("yaw_error_median_deg"), 1.0);
  EXPECT_GE(good.at("covariance_coverage"), 0.9);
  const auto bad = judge(1.2, 10);
  EXPECT_LT(bad.at("success_rate"), 0.5);
}

// b1: the odometry over the dataset's lap, and the same with a focal length 10 % off (a wrong
// calibration), which must break the drift threshold.
TEST(LocalizationEvaluators, VisualOdometryPassesAndAWrongFocalLengthFails) {
  const Streams data = generate("localization/stereo_odometry");
  const auto& left_info =
      *static_cast<const msgs::CameraInfo*>(data["left_camera_info"].messages[0].get());
  const auto& right_info =
      *static_cast<const msgs::CameraInfo*>(data["right_camera_info"].messages[0].get());
  const double baseline = -right_info.p[3] / right_info.p[0];
  auto judge = [&](double focal_scale) {
    StereoOdometry odometry(left_info.p[0] * focal_scale, left_info.p[5] * focal_scale,
                            left_info.p[2], left_info.p[6], baseline);
    auto e = evaluator("visual_odometry", {{"pose", &data["pose_truth"]}});
    cv::Mat left, right;
    for (std::size_t k = 0; k < data["left_image"].messages.size(); ++k) {
      perception::to_mono8(*static_cast<const msgs::Image*>(data["left_image"].messages[k].get()),
                           "left", left);
      perception::to_mono8(*static_cast<const msgs::Image*>(data["right_image"].messages[k].get()),
                           "right", right);
      const Eigen::Isometry3d pose = odometry.process(left, right).pose;
      msgs::Odometry out;
      out.header.frame_id = "odom";
      out.pose.pose = msgs::pose_msg_of(pose);
      e->add(&out, k);
    }
    EXPECT_TRUE(e->problems().empty());
    return e->metrics();
  };
  const auto good = judge(1.0);
  EXPECT_LE(good.at("translational_drift_percent"), 2.0);
  EXPECT_LE(good.at("rotational_drift_deg_per_m"), 0.5);
  EXPECT_LE(good.at("ate_rmse_m"), 0.1);
  const auto bad = judge(1.1);
  EXPECT_GT(bad.at("translational_drift_percent"), 2.0);
}

TEST(LocalizationEvaluators, AnAnswerInAnotherFrameIsADefect) {
  const Streams data = generate("localization/map_scans");
  auto e = evaluator("map_localization", {{"pose", &data["pose_truth"]}});
  msgs::PoseWithCovarianceStamped out;
  out.header.frame_id = "odom";
  e->add(&out, 0);
  ASSERT_EQ(e->problems().size(), 1u);
  EXPECT_NE(e->problems().begin()->find("pose frame is 'odom', expected 'map'"), std::string::npos);
}

// The medians are those of the answers: for an even count, the mean of the two middle errors.
TEST(LocalizationEvaluators, MediansOfAnEvenCountAreTheMeanOfTheMiddleTwo) {
  const Streams data = generate("localization/map_scans");
  auto e = evaluator("map_localization", {{"pose", &data["pose_truth"]}});
  const double offsets_m[] = {0.0, 0.01, 0.03, 0.2};
  for (std::size_t k = 0; k < std::size(offsets_m); ++k) {
    const auto& truth =
        *static_cast<const msgs::PoseStamped*>(data["pose_truth"].messages[k].get());
    msgs::PoseWithCovarianceStamped out;
    out.header = truth.header;
    out.pose.pose = truth.pose;
    out.pose.pose.position.x += offsets_m[k];
    e->add(&out, k);
  }
  ASSERT_TRUE(e->problems().empty());
  EXPECT_NEAR(e->metrics().at("position_error_median_m"), 0.02, 1e-9);
  EXPECT_NEAR(e->metrics().at("yaw_error_median_deg"), 0.0, 1e-9);
}

}  // namespace
}  // namespace robotperf::localization
