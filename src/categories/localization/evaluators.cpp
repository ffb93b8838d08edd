// Functional evaluators of the localization benchmarks: every answer against the dataset's
// ground truth.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "category.hpp"
#include "quaternion.hpp"
#include "robotperf/localization/trajectory_metrics.hpp"
#include "robotperf/msgs/apriltag_msgs.hpp"
#include "robotperf/msgs/eigen_geometry.hpp"
#include "robotperf/msgs/geometry_msgs.hpp"
#include "robotperf/msgs/nav_msgs.hpp"

namespace robotperf::localization {
namespace {

using plugin::DatasetStream;
using plugin::FunctionalEvaluator;

const double kNaN = std::nan("");
const double kInfinity = std::numeric_limits<double>::infinity();

// The middle value; for an even count, the mean of the two middle ones. A NaN error (an answer
// holding a NaN) counts as +inf, as wrong as an answer can be: it fails a threshold once most
// answers are, and keeps the order nth_element needs (NaN compares false with everything).
double median(std::vector<double> v) {
  if (v.empty()) return kNaN;
  for (double& x : v) x = std::isnan(x) ? kInfinity : x;
  const auto upper = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), upper, v.end());
  if (v.size() % 2 == 1) return *upper;
  return (*std::max_element(v.begin(), upper) + *upper) / 2.0;
}

// The distance between two points, NaN when either holds one. Not std::hypot's three-argument
// form: libstdc++'s (GCC 12) gives 0 for (0, NaN, 0), a perfect answer.
double distance(const msgs::Point& a, const msgs::Point& b) {
  const double dx = a.x - b.x, dy = a.y - b.y, dz = a.z - b.z;
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

// Detections against the true tags of their frame. A detection is correct when a true tag of
// its id lies within `match_px` (mean corner distance): a wrong id, or the right id far from
// its tag, is a false positive. Recall and corner accuracy count the unoccluded tags (goodness
// 1); occluded ones have a recall of their own. Poses come from the graph's second output, in
// the order of the detections.
class AprilTagEvaluator final : public FunctionalEvaluator {
 public:
  AprilTagEvaluator(const DatasetStream& tags, const DatasetStream& poses, double match_px)
      : tags_(tags), poses_(poses), match_px_(match_px) {
    plugin::require_type<msgs::AprilTagDetectionArray>(tags, "apriltag_detection");
    plugin::require_type<msgs::PoseArray>(poses, "apriltag_detection");
  }

  void add(const void* output, std::size_t frame) override { add_observed(output, nullptr, frame); }

  void add_observed(const void* output, const void* observed, std::size_t frame) override {
    const auto& found = *static_cast<const msgs::AprilTagDetectionArray*>(output);
    const auto& truth =
        *static_cast<const msgs::AprilTagDetectionArray*>(tags_.messages[frame].get());
    const auto& true_poses = *static_cast<const msgs::PoseArray*>(poses_.messages[frame].get());
    const auto* poses = static_cast<const msgs::PoseArray*>(observed);
    if (poses == nullptr) {
      ++missing_poses_;
    } else if (poses->poses.size() != found.detections.size()) {
      problem("the poses output holds " + std::to_string(poses->poses.size()) + " poses for " +
              std::to_string(found.detections.size()) + " detections");
      poses = nullptr;
    }
    for (const auto& t : truth.detections) (t.goodness >= 1.0f ? unoccluded_ : occluded_) += 1;
    std::vector<bool> taken(truth.detections.size(), false);
    for (std::size_t i = 0; i < found.detections.size(); ++i) {
      const auto& d = found.detections[i];
      ++detections_;
      std::size_t best = truth.detections.size();
      double best_error = match_px_;
      for (std::size_t j = 0; j < truth.detections.size(); ++j) {
        const auto& t = truth.detections[j];
        if (t.id != d.id || taken[j]) continue;
        const double e = mean_corner_distance(d, t);
        if (e <= best_error) {
          best_error = e;
          best = j;
        }
      }
      if (best == truth.detections.size()) continue;
      taken[best] = true;
      ++correct_;
      const auto& t = truth.detections[best];
      if (t.goodness < 1.0f) {
        ++occluded_found_;
        continue;
      }
      ++unoccluded_found_;
      for (std::size_t c = 0; c < 4; ++c) {
        const double dx = d.corners[c].x - t.corners[c].x;
        const double dy = d.corners[c].y - t.corners[c].y;
        corner_sq_sum_ += dx * dx + dy * dy;
        ++corners_;
      }
      if (poses != nullptr) {
        const msgs::Pose& p = poses->poses[i];
        const msgs::Pose& q = true_poses.poses[best];
        translation_errors_.push_back(distance(p.position, q.position));
        // Normalised: a pose message may round its quaternion, or scale it.
        rotation_errors_.push_back(
            rotation_angle_between(normalized(p.orientation), normalized(q.orientation)) * 180.0 /
            std::numbers::pi);
      }
    }
  }

  std::map<std::string, double> metrics() const override {
    auto ratio = [](std::size_t a, std::size_t b) { return b == 0 ? kNaN : double(a) / b; };
    return {{"recall", ratio(unoccluded_found_, unoccluded_)},
            {"recall_occluded", ratio(occluded_found_, occluded_)},
            {"precision", detections_ == 0 ? kNaN : ratio(correct_, detections_)},
            {"corner_rms_px", corners_ == 0 ? kNaN : std::sqrt(corner_sq_sum_ / corners_)},
            {"translation_error_median_m", median(translation_errors_)},
            {"rotation_error_median_deg", median(rotation_errors_)},
            {"outputs_without_poses", static_cast<double>(missing_poses_)}};
  }

 private:
  static double mean_corner_distance(const msgs::AprilTagDetection& a,
                                     const msgs::AprilTagDetection& b) {
    double sum = 0.0;
    for (std::size_t c = 0; c < 4; ++c) {
      sum += std::hypot(a.corners[c].x - b.corners[c].x, a.corners[c].y - b.corners[c].y);
    }
    return sum / 4.0;
  }

  const DatasetStream& tags_;
  const DatasetStream& poses_;
  double match_px_;
  std::size_t unoccluded_ = 0, occluded_ = 0, detections_ = 0, correct_ = 0;
  std::size_t unoccluded_found_ = 0, occluded_found_ = 0, corners_ = 0, missing_poses_ = 0;
  double corner_sq_sum_ = 0.0;
  std::vector<double> translation_errors_, rotation_errors_;
};

// Global localizations against the true poses: a success is within `max_position_error` and
// `max_yaw_error` (Isaac ROS's and the 0.1 m and 2 degrees). The covariance is judged
// too: a localizer that is wrong must say it is unsure, so the share of answers whose error lies
// inside the 99 % ellipsoid of their own covariance (chi-square, 3 degrees of freedom) is
// reported.
class MapLocalizationEvaluator final : public FunctionalEvaluator {
 public:
  MapLocalizationEvaluator(const DatasetStream& truth, double max_position_m, double max_yaw_deg)
      : truth_(truth), max_position_m_(max_position_m), max_yaw_rad_(max_yaw_deg * kDegree) {
    plugin::require_type<msgs::PoseStamped>(truth, "map_localization");
  }

  void add(const void* output, std::size_t frame) override {
    const auto& out = *static_cast<const msgs::PoseWithCovarianceStamped*>(output);
    const auto& truth = *static_cast<const msgs::PoseStamped*>(truth_.messages[frame].get());
    if (out.header.frame_id != truth.header.frame_id)
      problem("pose frame is '" + out.header.frame_id + "', expected '" + truth.header.frame_id +
              "'");
    const double dx = out.pose.pose.position.x - truth.pose.position.x;
    const double dy = out.pose.pose.position.y - truth.pose.position.y;
    // Normalised: a pose message may round its quaternion, or scale it.
    const double dyaw = std::remainder(
        yaw_of(normalized(out.pose.pose.orientation)) - yaw_of(normalized(truth.pose.orientation)),
        2.0 * std::numbers::pi);
    const double position = std::hypot(dx, dy);
    positions_.push_back(position);
    yaws_.push_back(std::abs(dyaw) / kDegree);
    successes_ += position <= max_position_m_ && std::abs(dyaw) <= max_yaw_rad_ ? 1 : 0;
    covered_ += inside_99_percent(out.pose.covariance, dx, dy, dyaw) ? 1 : 0;
  }

  std::map<std::string, double> metrics() const override {
    const double n = static_cast<double>(positions_.size());
    return {{"success_rate", positions_.empty() ? kNaN : successes_ / n},
            {"position_error_median_m", median(positions_)},
            {"yaw_error_median_deg", median(yaws_)},
            {"covariance_coverage", positions_.empty() ? kNaN : covered_ / n}};
  }

 private:
  static constexpr double kDegree = std::numbers::pi / 180.0;

  // e^T C^-1 e <= 11.345 (chi-square, 3 degrees of freedom, 99 %) over (x, y, yaw). A
  // covariance that is not positive definite bounds nothing (an indefinite one has a positive
  // determinant with two negative eigenvalues, and negative distances along them): every
  // leading principal minor must be positive (Sylvester's criterion).
  static bool inside_99_percent(const msgs::Covariance6& c, double dx, double dy, double dyaw) {
    const std::size_t index[3] = {0, 1, 5};
    double m[3][3];
    for (std::size_t i = 0; i < 3; ++i) {
      for (std::size_t j = 0; j < 3; ++j) m[i][j] = c[6 * index[i] + index[j]];
    }
    const double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                       m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                       m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    const double minor2 = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    if (!(m[0][0] > 0.0 && minor2 > 0.0 && det > 0.0)) return false;
    const double inv[3][3] = {{(m[1][1] * m[2][2] - m[1][2] * m[2][1]) / det,
                               (m[0][2] * m[2][1] - m[0][1] * m[2][2]) / det,
                               (m[0][1] * m[1][2] - m[0][2] * m[1][1]) / det},
                              {(m[1][2] * m[2][0] - m[1][0] * m[2][2]) / det,
                               (m[0][0] * m[2][2] - m[0][2] * m[2][0]) / det,
                               (m[0][2] * m[1][0] - m[0][0] * m[1][2]) / det},
                              {(m[1][0] * m[2][1] - m[1][1] * m[2][0]) / det,
                               (m[0][1] * m[2][0] - m[0][0] * m[2][1]) / det,
                               (m[0][0] * m[1][1] - m[0][1] * m[1][0]) / det}};
    const double e[3] = {dx, dy, dyaw};
    double d2 = 0.0;
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) d2 += e[i] * inv[i][j] * e[j];
    }
    return d2 <= 11.345;
  }

  const DatasetStream& truth_;
  double max_position_m_, max_yaw_rad_;
  std::vector<double> positions_, yaws_;
  std::size_t successes_ = 0, covered_ = 0;
};

// Odometry against the true trajectory, as TUM and KITTI evaluate it: the absolute trajectory
// error after a rigid alignment, and the drift over path segments of the given lengths. The
// outputs are taken in the order they arrive, which is the order of the frames.
class VisualOdometryEvaluator final : public FunctionalEvaluator {
 public:
  VisualOdometryEvaluator(const DatasetStream& truth, std::vector<double> lengths_m)
      : truth_(truth), lengths_m_(std::move(lengths_m)) {
    plugin::require_type<msgs::PoseStamped>(truth, "visual_odometry");
  }

  void add(const void* output, std::size_t frame) override {
    const auto& out = *static_cast<const msgs::Odometry*>(output);
    const auto& truth = *static_cast<const msgs::PoseStamped*>(truth_.messages[frame].get());
    if (out.header.frame_id != truth.header.frame_id)
      problem("odometry frame is '" + out.header.frame_id + "', expected '" +
              truth.header.frame_id + "'");
    Eigen::Isometry3d estimate = msgs::isometry_of(out.pose.pose);
    // A quaternion of norm zero or not finite names no rotation (Eigen would take a zero one for
    // the identity): the drift over the segments through it cannot be computed.
    if (std::isnan(normalized(out.pose.pose.orientation).w)) {
      problem(
          "an odometry orientation is no rotation (its quaternion's norm is zero or not finite)");
      estimate.linear().setConstant(kNaN);
    }
    estimate_.push_back(estimate);
    truth_poses_.push_back(msgs::isometry_of(truth.pose));
  }

  std::map<std::string, double> metrics() const override {
    if (estimate_.size() < 2) {
      return {{"ate_rmse_m", kNaN},
              {"translational_drift_percent", kNaN},
              {"rotational_drift_deg_per_m", kNaN}};
    }
    const AbsoluteTrajectoryError ate = absolute_trajectory_error(estimate_, truth_poses_);
    const RelativePoseError rpe = relative_pose_error(estimate_, truth_poses_, lengths_m_);
    return {{"ate_rmse_m", ate.rmse_m},
            {"translational_drift_percent", rpe.translation_percent},
            {"rotational_drift_deg_per_m", rpe.rotation_deg_per_m}};
  }

 private:
  const DatasetStream& truth_;
  std::vector<double> lengths_m_;
  std::vector<Eigen::Isometry3d> estimate_, truth_poses_;
};

struct AprilTagScoring {
  double match_px = 0;
};

const plugin::ParameterStruct<AprilTagScoring> kAprilTagScoring{
    plugin::field(&AprilTagScoring::match_px, "match_px", 3.0,
                  "largest mean corner distance (px) of a detection from its tag")};

struct LocalizationScoring {
  double max_position_error_m = 0;
  double max_yaw_error_deg = 0;
};

const plugin::ParameterStruct<LocalizationScoring> kLocalizationScoring{
    plugin::field(&LocalizationScoring::max_position_error_m, "max_position_error_m", 0.1,
                  "a success is at most this far off"),
    plugin::field(&LocalizationScoring::max_yaw_error_deg, "max_yaw_error_deg", 2.0,
                  "and at most this many degrees off")};

struct OdometryScoring {
  double segment_m = 0;
};

const plugin::ParameterStruct<OdometryScoring> kOdometryScoring{
    plugin::field(&OdometryScoring::segment_m, "segment_m", 1.0,
                  "drift over segments of 1, 2, 4 and 8 times this length of path")};

}  // namespace

void register_evaluators(plugin::Registrar& registrar) {
  registrar.add_evaluator(
      {.name = "apriltag_detection",
       .description = "detections against the true tags (ids, corners) and their poses against "
                      "the true poses",
       .output_type = "apriltag_msgs/msg/AprilTagDetectionArray",
       .truth_roles = {"tags", "poses"},
       .metrics = {{"recall", "fraction", "unoccluded tags detected with their id and corners"},
                   {"recall_occluded", "fraction", "partly occluded tags detected"},
                   {"precision", "fraction", "detections that are a true tag at its place"},
                   {"corner_rms_px", "px", "RMS corner error of the unoccluded tags detected"},
                   {"translation_error_median_m", "m",
                    "median distance of a detected tag's position from the truth"},
                   {"rotation_error_median_deg", "deg",
                    "median rotation between a detected tag's orientation and the truth"},
                   {"outputs_without_poses", "count", "outputs whose poses message never arrived"}},
       .observed_truth_type = "geometry_msgs/msg/PoseArray",
       .parameters = kAprilTagScoring.declarations()},
      [](const plugin::TruthStreams& t, const plugin::Parameters& p) {
        return std::make_unique<AprilTagEvaluator>(t["tags"], t["poses"],
                                                   kAprilTagScoring.read(p).match_px);
      });
  registrar.add_evaluator(
      {.name = "map_localization",
       .description = "global localizations against the true poses, and their covariance against "
                      "their errors",
       .output_type = "geometry_msgs/msg/PoseWithCovarianceStamped",
       .truth_roles = {"pose"},
       .metrics = {{"success_rate", "fraction",
                    "answers within max_position_error_m and max_yaw_error_deg"},
                   {"position_error_median_m", "m", "median distance from the true position"},
                   {"yaw_error_median_deg", "deg", "median heading error"},
                   {"covariance_coverage", "fraction",
                    "answers whose (x, y, yaw) error lies in the 99 % ellipsoid of their own "
                    "covariance"}},
       .parameters = kLocalizationScoring.declarations(),
       .on_arrival = true},
      [](const plugin::TruthStreams& t, const plugin::Parameters& p) {
        const LocalizationScoring s = kLocalizationScoring.read(p);
        return std::make_unique<MapLocalizationEvaluator>(t["pose"], s.max_position_error_m,
                                                          s.max_yaw_error_deg);
      });
  registrar.add_evaluator(
      {.name = "visual_odometry",
       .description = "odometry against the true trajectory: absolute trajectory error and drift "
                      "per path length (TUM, KITTI)",
       .output_type = "nav_msgs/msg/Odometry",
       .truth_roles = {"pose"},
       .metrics = {{"ate_rmse_m", "m",
                    "RMS position error after the rigid alignment that minimises it"},
                   {"translational_drift_percent", "%",
                    "mean translation error of the relative motion over path segments, per "
                    "length"},
                   {"rotational_drift_deg_per_m", "deg/m",
                    "mean rotation error of the relative motion over path segments, per length"}},
       .parameters = kOdometryScoring.declarations(),
       .on_arrival = true},
      [](const plugin::TruthStreams& t, const plugin::Parameters& p) {
        const double unit = kOdometryScoring.read(p).segment_m;
        if (!(unit > 0.0)) throw std::invalid_argument("visual_odometry: segment_m must be > 0");
        return std::make_unique<VisualOdometryEvaluator>(
            t["pose"], std::vector<double>{unit, 2 * unit, 4 * unit, 8 * unit});
      });
}

}  // namespace robotperf::localization
