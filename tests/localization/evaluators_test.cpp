// The localization evaluators judge what the kernels answer: right answers pass b1-b3's
// thresholds, and a kernel fed or configured wrongly is caught.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>

#include "robotperf/localization/scan_matcher.hpp"
#include "robotperf/localization/stereo_odometry.hpp"
#include "robotperf/msgs/apriltag_msgs.hpp"
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

const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInfinity = std::numeric_limits<double>::infinity();

// A truth stream made by hand, for what the evaluators make of odd answers.
template <class T>
plugin::DatasetStream stream_of(const std::string& name, std::vector<T> messages) {
  auto stream = plugin::make_stream<T>(name, "/ground_truth/" + name);
  for (T& m : messages) plugin::append(stream, std::move(m));
  return stream;
}

msgs::Quaternion quaternion_of(const Eigen::AngleAxisd& rotation) {
  const Eigen::Quaterniond q(rotation);
  return {q.x(), q.y(), q.z(), q.w()};
}

// b2's truth: frames poses in "map", each at its own place and heading.
plugin::DatasetStream planar_truth(std::size_t frames) {
  std::vector<msgs::PoseStamped> poses(frames);
  for (std::size_t k = 0; k < frames; ++k) {
    poses[k].header.frame_id = "map";
    poses[k].pose.position = {0.5 * k, 1.0 - 0.2 * k, 0.0};
    poses[k].pose.orientation =
        quaternion_of(Eigen::AngleAxisd(-3.0 + 0.55 * k, Eigen::Vector3d::UnitZ()));
  }
  return stream_of("pose", std::move(poses));
}

// b2's evaluator given each true pose changed by `change`, with a covariance of 1 cm and 1 degree.
std::map<std::string, double> judge_planar(
    const plugin::DatasetStream& truth,
    const std::function<void(std::size_t, msgs::Pose&)>& change) {
  auto e = evaluator("map_localization", {{"pose", &truth}});
  for (std::size_t k = 0; k < truth.messages.size(); ++k) {
    const auto& t = *static_cast<const msgs::PoseStamped*>(truth.messages[k].get());
    msgs::PoseWithCovarianceStamped out;
    out.header = t.header;
    out.pose.pose = t.pose;
    change(k, out.pose.pose);
    out.pose.covariance[0] = out.pose.covariance[7] = 1e-4;
    out.pose.covariance[35] = 3e-4;
    e->add(&out, k);
  }
  EXPECT_TRUE(e->problems().empty());
  return e->metrics();
}

// b3's truth: one frame of three unoccluded tags, each turned its own way.
struct TagTruth {
  plugin::DatasetStream tags, poses;
};

TagTruth tag_truth() {
  msgs::AprilTagDetectionArray tags;
  msgs::PoseArray poses;
  for (int i = 0; i < 3; ++i) {
    msgs::AprilTagDetection tag;
    tag.family = "36h11";
    tag.id = i;
    tag.goodness = 1.0f;
    const double x = 200.0 * (i + 1), size = 40.0;
    tag.corners = {{{x, 300.0 + size}, {x + size, 300.0 + size}, {x + size, 300.0}, {x, 300.0}}};
    tags.detections.push_back(tag);
    msgs::Pose pose;
    pose.position = {0.4 * (i - 1), 0.1, 1.5 + i};
    pose.orientation =
        quaternion_of(Eigen::AngleAxisd(2.5 + 0.3 * i, Eigen::Vector3d(1.0, i, 2.0).normalized()));
    poses.poses.push_back(pose);
  }
  return {stream_of("tags", std::vector{tags}), stream_of("tag_poses", std::vector{poses})};
}

// b3's evaluator given the true tags, and their true poses changed by `change`.
std::map<std::string, double> judge_tag_poses(const std::function<void(msgs::Pose&)>& change) {
  const TagTruth truth = tag_truth();
  auto e = evaluator("apriltag_detection", {{"tags", &truth.tags}, {"poses", &truth.poses}});
  const auto& found =
      *static_cast<const msgs::AprilTagDetectionArray*>(truth.tags.messages[0].get());
  msgs::PoseArray poses = *static_cast<const msgs::PoseArray*>(truth.poses.messages[0].get());
  for (msgs::Pose& p : poses.poses) change(p);
  e->add_observed(&found, &poses, 0);
  EXPECT_TRUE(e->problems().empty());
  return e->metrics();
}

// A tag orientation holding NaN is no rotation, not a perfect one: its error is +inf, and b3's
// rotation threshold (3 degrees) fails. Positions holding NaN likewise.
TEST(LocalizationEvaluators, ATagPoseHoldingNaNIsWrongNotPerfect) {
  const auto exact = judge_tag_poses([](msgs::Pose&) {});
  EXPECT_NEAR(exact.at("rotation_error_median_deg"), 0.0, 1e-6);
  EXPECT_EQ(exact.at("recall"), 1.0);
  const auto nan_orientation = judge_tag_poses([](msgs::Pose& p) {
    p.orientation = {kNaN, kNaN, kNaN, kNaN};
  });
  EXPECT_EQ(nan_orientation.at("rotation_error_median_deg"), kInfinity);
  EXPECT_NEAR(nan_orientation.at("translation_error_median_m"), 0.0, 1e-12);
  const auto nan_w = judge_tag_poses([](msgs::Pose& p) { p.orientation.w = kNaN; });
  EXPECT_EQ(nan_w.at("rotation_error_median_deg"), kInfinity);
  const auto nan_position = judge_tag_poses([](msgs::Pose& p) { p.position.y = kNaN; });
  EXPECT_EQ(nan_position.at("translation_error_median_m"), kInfinity);
}

// Most answers NaN: the medians are +inf whatever order the answers came in (a NaN among the
// values is undefined behaviour for nth_element, and came out 1 mm or NaN by placement).
TEST(LocalizationEvaluators, MediansCountNaNAnswersAsWrong) {
  const std::vector<std::vector<std::size_t>> placements = {
      {0, 2, 4, 6, 8, 9}, {0, 1, 2, 3, 4, 5}, {4, 5, 6, 7, 8, 9}, {1, 3, 5, 7, 8, 9}};
  for (const std::size_t frames : {std::size_t{10}, std::size_t{11}}) {
    const plugin::DatasetStream truth = planar_truth(frames);
    for (const auto& placement : placements) {
      std::vector<bool> nan(frames, false);
      for (const std::size_t k : placement) nan[k] = true;
      if (frames == 11) nan[10] = true;  // 7 of 11
      const auto m = judge_planar(truth, [&](std::size_t k, msgs::Pose& p) {
        p.position.x += nan[k] ? kNaN : 0.001;
        if (nan[k]) p.orientation.z = kNaN;
      });
      EXPECT_EQ(m.at("position_error_median_m"), kInfinity) << frames << " answers";
      EXPECT_EQ(m.at("yaw_error_median_deg"), kInfinity) << frames << " answers";
      EXPECT_LE(m.at("success_rate"), 0.4);
      EXPECT_LE(m.at("covariance_coverage"), 0.4);
    }
  }
}

// A pose message's quaternion need not be of unit length: 0.7 times a rotation's is that
// rotation. One of length zero is none, and a failed answer.
TEST(LocalizationEvaluators, MapLocalizationNormalisesQuaternionsAndAZeroOneFails) {
  const plugin::DatasetStream truth = planar_truth(6);
  const auto scaled = judge_planar(truth, [](std::size_t, msgs::Pose& p) {
    p.orientation = {0.7 * p.orientation.x, 0.7 * p.orientation.y, 0.7 * p.orientation.z,
                     0.7 * p.orientation.w};
  });
  EXPECT_EQ(scaled.at("success_rate"), 1.0);
  EXPECT_NEAR(scaled.at("yaw_error_median_deg"), 0.0, 1e-9);
  EXPECT_EQ(scaled.at("covariance_coverage"), 1.0);
  const auto zero = judge_planar(truth, [](std::size_t, msgs::Pose& p) {
    p.orientation = {0.0, 0.0, 0.0, 0.0};
  });
  EXPECT_EQ(zero.at("success_rate"), 0.0);
  EXPECT_EQ(zero.at("yaw_error_median_deg"), kInfinity);
}

TEST(LocalizationEvaluators, AprilTagPosesNormaliseQuaternionsAndAZeroOneFails) {
  const auto scaled = judge_tag_poses([](msgs::Pose& p) {
    p.orientation = {0.7 * p.orientation.x, 0.7 * p.orientation.y, 0.7 * p.orientation.z,
                     0.7 * p.orientation.w};
  });
  EXPECT_NEAR(scaled.at("rotation_error_median_deg"), 0.0, 1e-6);
  const auto zero = judge_tag_poses([](msgs::Pose& p) { p.orientation = {0.0, 0.0, 0.0, 0.0}; });
  EXPECT_EQ(zero.at("rotation_error_median_deg"), kInfinity);
}

// b1 normalises too, but a quaternion of length zero is no rotation (Eigen's normalisation
// would leave it the identity): a defect, and the drift through it cannot be computed.
TEST(LocalizationEvaluators, AnOdometryOrientationOfNormZeroIsADefect) {
  std::vector<msgs::PoseStamped> poses(30);
  for (std::size_t k = 0; k < poses.size(); ++k) {
    poses[k].header.frame_id = "odom";
    poses[k].pose.position = {0.0, 0.0, 0.1 * k};
  }
  const plugin::DatasetStream truth = stream_of("pose", poses);
  auto judge = [&](const msgs::Quaternion& orientation) {
    auto e = evaluator("visual_odometry", {{"pose", &truth}});
    for (std::size_t k = 0; k < poses.size(); ++k) {
      msgs::Odometry out;
      out.header.frame_id = "odom";
      out.pose.pose = poses[k].pose;
      if (k == 12) out.pose.pose.orientation = orientation;
      e->add(&out, k);
    }
    return e;
  };
  const auto scaled = judge({0.0, 0.0, 0.0, 0.7});
  EXPECT_TRUE(scaled->problems().empty());
  EXPECT_NEAR(scaled->metrics().at("rotational_drift_deg_per_m"), 0.0, 1e-9);
  const auto zero = judge({0.0, 0.0, 0.0, 0.0});
  ASSERT_EQ(zero->problems().size(), 1u);
  EXPECT_NE(zero->problems().begin()->find("no rotation"), std::string::npos);
  EXPECT_TRUE(std::isnan(zero->metrics().at("rotational_drift_deg_per_m")));
}

// A covariance that is not positive definite bounds nothing: this one, all its variances
// positive and its determinant too, has two negative eigenvalues, along which an error of any
// size would lie inside its "ellipsoid".
TEST(LocalizationEvaluators, AnIndefiniteCovarianceCoversNothing) {
  const plugin::DatasetStream truth = planar_truth(2);
  auto covered = [&](const std::array<double, 9>& c, double dx, double dy) {
    auto e = evaluator("map_localization", {{"pose", &truth}});
    const auto& t = *static_cast<const msgs::PoseStamped*>(truth.messages[0].get());
    msgs::PoseWithCovarianceStamped out;
    out.header = t.header;
    out.pose.pose = t.pose;
    out.pose.pose.position.x += dx;
    out.pose.pose.position.y += dy;
    const std::size_t index[3] = {0, 1, 5};
    for (std::size_t i = 0; i < 3; ++i)
      for (std::size_t j = 0; j < 3; ++j)
        out.pose.covariance[6 * index[i] + index[j]] = c[3 * i + j];
    e->add(&out, 0);
    return e->metrics().at("covariance_coverage");
  };
  // Eigenvalues 5, -1, -1; (1, -1, 0) is an eigenvector of -1.
  const std::array<double, 9> indefinite = {1, 2, 2, 2, 1, 2, 2, 2, 1};
  EXPECT_EQ(covered(indefinite, 3.0, -3.0), 0.0);
  EXPECT_EQ(covered(indefinite, 0.01, -0.01), 0.0);
  // A positive definite one of 4 m^2 covers 3 m, and not 30.
  const std::array<double, 9> wide = {4, 0, 0, 0, 4, 0, 0, 0, 1};
  EXPECT_EQ(covered(wide, 3.0, -3.0), 1.0);
  EXPECT_EQ(covered(wide, 30.0, -30.0), 0.0);
}

}  // namespace
}  // namespace robotperf::localization
