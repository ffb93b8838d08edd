#pragma once

// Trajectory accuracy as the TUM RGB-D and KITTI odometry benchmarks define it, on poses
// T_world_camera (estimate and ground truth of the same frames, in order):
// - absolute trajectory error (TUM): the RMSE of the position differences once the estimate is
//   aligned to the truth by the rigid motion (no scale: stereo observes it) that minimises them,
//   in closed form (Horn / Umeyama);
// - relative pose error as drift (KITTI): for every first frame and every segment length L, the
//   segment ends at the first frame whose distance travelled along the truth reaches L; the
//   error of the estimated relative motion over it, E = (T_i^-1 T_j)_truth^-1 (T_i^-1 T_j)_est,
//   gives ||translation(E)|| / L and angle(E) / L, averaged over all segments.

#include <Eigen/Geometry>
#include <cstddef>
#include <vector>

namespace robotperf::localization {

struct AbsoluteTrajectoryError {
  double rmse_m = 0;
  double mean_m = 0;
  double max_m = 0;
  Eigen::Isometry3d alignment = Eigen::Isometry3d::Identity();  // truth ~ alignment * estimate
};

// Throws std::invalid_argument when the two differ in length or hold fewer than 2 poses.
AbsoluteTrajectoryError absolute_trajectory_error(const std::vector<Eigen::Isometry3d>& estimate,
                                                  const std::vector<Eigen::Isometry3d>& truth);

struct SegmentDrift {
  double length_m = 0;
  std::size_t segments = 0;        // first frames from which the length was reached
  double translation_percent = 0;  // mean ||translation(E)|| / L * 100; NaN if no segment
  double rotation_deg_per_m = 0;   // mean angle(E) / L in degrees; NaN if no segment
};

struct RelativePoseError {
  std::size_t segments = 0;        // over all lengths
  double translation_percent = 0;  // mean over all segments of all lengths (as KITTI); NaN if none
  double rotation_deg_per_m = 0;
  std::vector<SegmentDrift> by_length;  // in the order of the lengths given
};

// The segment lengths for a sequence of about 15 m (KITTI's 100 .. 800 m scaled down).
inline const std::vector<double> kDefaultSegmentLengthsM{1.0, 2.0, 4.0, 8.0};

// `step` is the spacing of the first frames (KITTI: 10; 1 takes every frame). Throws
// std::invalid_argument when the two differ in length, hold fewer than 2 poses, no length is
// given, a length is not positive and finite, or step is 0.
RelativePoseError relative_pose_error(
    const std::vector<Eigen::Isometry3d>& estimate, const std::vector<Eigen::Isometry3d>& truth,
    const std::vector<double>& lengths_m = kDefaultSegmentLengthsM, std::size_t step = 1);

}  // namespace robotperf::localization
