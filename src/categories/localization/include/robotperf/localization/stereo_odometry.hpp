#pragma once

// Stereo visual odometry, the SLAM front end of benchmark b1: feature-based, frame to keyframe.
// Per frame:
// - FAST corners in both rectified images, kept strongest first per cell of a grid (so that
//   they cover the image), with upright ORB (rBRIEF) descriptors;
// - stereo matches along rows (|dy| <= max_row_offset_px, disparity in range, Hamming distance
//   with a ratio test), the disparity refined to a fraction of a pixel by SSD block matching
//   and a parabola, triangulated as Z = fx * baseline / (d - (cx - right_cx)), as
//   image_geometry's StereoCameraModel does;
// - tracking: the keyframe's 3-D points are projected with a constant-velocity prediction and
//   matched to the current left features near their prediction; the pose comes from
//   cv::solvePnPRansac and is refined on the inliers (cv::solvePnPRefineLM), then once more on
//   every match within the RANSAC threshold of the refined pose;
// - the current frame becomes the keyframe when the inliers fall below a threshold.
// When tracking fails (too few inliers, an unusable image) the pose follows the constant
// velocity and the current frame starts a new keyframe if it has the stereo points for one;
// a bad frame never throws.

#include <Eigen/Geometry>
#include <limits>
#include <memory>
#include <opencv2/core.hpp>

namespace robotperf::localization {

// A rectified pair, as its CameraInfos' P matrices give it (pixels, m): both cameras have fx, fy
// and cy; the right one sits baseline_m along the left's +x axis, with the same orientation, and
// its principal point may lie at another column, right_cx (a rectification that keeps all of
// both images may move the two apart): a point at depth Z is then seen at
// u_left - u_right = fx * baseline_m / Z + (cx - right_cx). Every field must be given: one left
// out is NaN, and refused.
struct StereoCalibration {
  double fx = std::numeric_limits<double>::quiet_NaN();
  double fy = std::numeric_limits<double>::quiet_NaN();
  double cx = std::numeric_limits<double>::quiet_NaN();
  double cy = std::numeric_limits<double>::quiet_NaN();
  double right_cx = std::numeric_limits<double>::quiet_NaN();
  double baseline_m = std::numeric_limits<double>::quiet_NaN();
  friend bool operator==(const StereoCalibration&, const StereoCalibration&) = default;
};

struct StereoOdometryOptions {
  // Features (per image).
  int max_features = 1200;  // kept after bucketing
  int grid_columns = 12;    // bucketing grid: max_features / (columns * rows) per cell
  int grid_rows = 9;
  int fast_threshold = 10;  // cv::FAST intensity threshold, 1 .. 255
  // Stereo matching.
  double max_row_offset_px = 1.5;
  double min_disparity_px = 1.0;
  double max_disparity_px = 128.0;
  int max_descriptor_distance = 64;  // Hamming, of 256 bits
  double ratio = 0.8;                // best distance < ratio * second best, in (0, 1]
  bool subpixel = true;              // refine disparities by block matching
  // Tracking.
  double search_radius_px = 16.0;  // around the constant-velocity prediction
  // When the velocity is unknown (second frame, after a loss): the first search's radius; the
  // keyframe is then matched again within search_radius_px of that first estimate.
  double unpredicted_search_radius_px = 64.0;
  // Pose.
  double ransac_reprojection_px = 2.0;
  int ransac_iterations = 100;
  int min_inliers = 20;  // fewer: tracking lost (>= 6)
  // Keyframes: a new one when the inliers fall below keyframe_inlier_fraction of the
  // keyframe's 3-D points, or below keyframe_min_inliers (and the frame has at least
  // min_inliers stereo points).
  double keyframe_inlier_fraction = 0.5;
  int keyframe_min_inliers = 120;
};

struct StereoOdometryResult {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  // T_odom_left; the first frame's
                                                           // left camera is the identity
  int features = 0;                                        // left features detected
  int stereo_matches = 0;                                  // left-right matches triangulated
  int tracked = 0;                                         // keyframe points matched in this frame
  int inliers = 0;                                         // of those, PnP inliers
  bool new_keyframe = false;
  bool tracking_lost = false;  // the pose is the constant-velocity prediction
};

// Not thread-safe: one instance per stream.
class StereoOdometry {
 public:
  // Throws std::invalid_argument for fx, fy or baseline_m not positive and finite, cx, cy or
  // right_cx not finite, or an option out of its range (the message names it).
  explicit StereoOdometry(const StereoCalibration& calibration,
                          const StereoOdometryOptions& options = {});
  // Rectified pinhole intrinsics (pixels) shared by both cameras, principal point included, and
  // the baseline (m) along the left camera's +x.
  StereoOdometry(double fx, double fy, double cx, double cy, double baseline_m,
                 const StereoOdometryOptions& options = {});
  ~StereoOdometry();
  StereoOdometry(StereoOdometry&&) noexcept;
  StereoOdometry& operator=(StereoOdometry&&) noexcept;

  // Processes one rectified pair and returns the left camera's pose in the odometry frame.
  // Throws std::invalid_argument when an image is not CV_8UC1, is empty or smaller than 64x64,
  // the two differ in size, or the size differs from the first frame's.
  StereoOdometryResult process(const cv::Mat& left, const cv::Mat& right);

  // Forgets every frame: the next one starts a new odometry frame at the identity.
  void reset();

  const StereoOdometryOptions& options() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace robotperf::localization
