#include "robotperf/localization/trajectory_metrics.hpp"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

namespace robotperf::localization {
namespace {

void validate(const std::vector<Eigen::Isometry3d>& estimate,
              const std::vector<Eigen::Isometry3d>& truth) {
  if (estimate.size() != truth.size()) {
    throw std::invalid_argument("trajectory metrics: estimate has " +
                                std::to_string(estimate.size()) + " poses, truth " +
                                std::to_string(truth.size()));
  }
  if (truth.size() < 2) {
    throw std::invalid_argument("trajectory metrics: need at least 2 poses");
  }
}

// Rotation angle in radians, accurate for small angles too (unlike acos of the trace).
double rotation_angle(const Eigen::Matrix3d& r) {
  Eigen::Quaterniond q(r);
  q.normalize();
  return 2.0 * std::atan2(q.vec().norm(), std::abs(q.w()));
}

}  // namespace

AbsoluteTrajectoryError absolute_trajectory_error(const std::vector<Eigen::Isometry3d>& estimate,
                                                  const std::vector<Eigen::Isometry3d>& truth) {
  validate(estimate, truth);
  const auto n = static_cast<double>(truth.size());
  Eigen::Vector3d estimate_mean = Eigen::Vector3d::Zero();
  Eigen::Vector3d truth_mean = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < truth.size(); ++i) {
    estimate_mean += estimate[i].translation();
    truth_mean += truth[i].translation();
  }
  estimate_mean /= n;
  truth_mean /= n;
  // Umeyama: the rotation from the SVD of the cross-covariance, its sign fixed so that it is
  // proper.
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < truth.size(); ++i) {
    covariance += (truth[i].translation() - truth_mean) *
                  (estimate[i].translation() - estimate_mean).transpose();
  }
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(covariance,
                                              Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d sign = Eigen::Matrix3d::Identity();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0.0) sign(2, 2) = -1.0;
  AbsoluteTrajectoryError result;
  result.alignment.linear() = svd.matrixU() * sign * svd.matrixV().transpose();
  result.alignment.translation() = truth_mean - result.alignment.linear() * estimate_mean;
  double squares = 0.0;
  double sum = 0.0;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    const double error =
        (truth[i].translation() - result.alignment * estimate[i].translation()).norm();
    squares += error * error;
    sum += error;
    result.max_m = std::max(result.max_m, error);
  }
  result.rmse_m = std::sqrt(squares / n);
  result.mean_m = sum / n;
  return result;
}

RelativePoseError relative_pose_error(const std::vector<Eigen::Isometry3d>& estimate,
                                      const std::vector<Eigen::Isometry3d>& truth,
                                      const std::vector<double>& lengths_m, std::size_t step) {
  validate(estimate, truth);
  if (lengths_m.empty()) throw std::invalid_argument("relative pose error: no segment length");
  for (const double length : lengths_m) {
    if (!(length > 0.0) || !std::isfinite(length)) {
      throw std::invalid_argument("relative pose error: segment lengths must be positive");
    }
  }
  if (step == 0) throw std::invalid_argument("relative pose error: step must be positive");

  std::vector<double> travelled(truth.size(), 0.0);
  for (std::size_t i = 1; i < truth.size(); ++i) {
    travelled[i] = travelled[i - 1] + (truth[i].translation() - truth[i - 1].translation()).norm();
  }
  constexpr double kDegrees = 180.0 / std::numbers::pi;
  RelativePoseError result;
  double translation_sum = 0.0;
  double rotation_sum = 0.0;
  for (const double length : lengths_m) {
    SegmentDrift drift;
    drift.length_m = length;
    double segment_translation = 0.0;
    double segment_rotation = 0.0;
    for (std::size_t first = 0; first < truth.size(); first += step) {
      // Tolerates the rounding of summed steps (ten steps of 0.1 m make a 1 m segment).
      const double target = travelled[first] + length * (1.0 - 1e-9);
      const auto end = std::lower_bound(travelled.begin() + static_cast<std::ptrdiff_t>(first),
                                        travelled.end(), target);
      if (end == travelled.end()) break;  // no later first frame reaches the length either
      const auto last = static_cast<std::size_t>(end - travelled.begin());
      const Eigen::Isometry3d truth_motion = truth[first].inverse() * truth[last];
      const Eigen::Isometry3d estimate_motion = estimate[first].inverse() * estimate[last];
      const Eigen::Isometry3d error = truth_motion.inverse() * estimate_motion;
      segment_translation += error.translation().norm() / length;
      segment_rotation += rotation_angle(error.linear()) / length;
      ++drift.segments;
    }
    translation_sum += segment_translation;
    rotation_sum += segment_rotation;
    result.segments += drift.segments;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    drift.translation_percent =
        drift.segments > 0 ? 100.0 * segment_translation / static_cast<double>(drift.segments)
                           : nan;
    drift.rotation_deg_per_m =
        drift.segments > 0 ? kDegrees * segment_rotation / static_cast<double>(drift.segments)
                           : nan;
    result.by_length.push_back(drift);
  }
  const double count = static_cast<double>(result.segments);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  result.translation_percent = result.segments > 0 ? 100.0 * translation_sum / count : nan;
  result.rotation_deg_per_m = result.segments > 0 ? kDegrees * rotation_sum / count : nan;
  return result;
}

}  // namespace robotperf::localization
