// Private to the localization category: rotations as geometry_msgs/Quaternion.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

#include "robotperf/msgs/geometry_msgs.hpp"
#include "robotperf/perception/camera_model.hpp"

namespace robotperf::localization {

// The unit quaternion of rotation matrix `r` (anything with r(row, col)), by the largest of its
// diagonal terms for accuracy; + - * / and sqrt only, so the same bits everywhere.
template <class Matrix>
msgs::Quaternion quaternion_from_matrix(const Matrix& r) {
  msgs::Quaternion q;
  const double trace = r(0, 0) + r(1, 1) + r(2, 2);
  if (trace > 0.0) {
    const double s = 2.0 * std::sqrt(trace + 1.0);
    q.w = 0.25 * s;
    q.x = (r(2, 1) - r(1, 2)) / s;
    q.y = (r(0, 2) - r(2, 0)) / s;
    q.z = (r(1, 0) - r(0, 1)) / s;
  } else if (r(0, 0) > r(1, 1) && r(0, 0) > r(2, 2)) {
    const double s = 2.0 * std::sqrt(1.0 + r(0, 0) - r(1, 1) - r(2, 2));
    q.w = (r(2, 1) - r(1, 2)) / s;
    q.x = 0.25 * s;
    q.y = (r(0, 1) + r(1, 0)) / s;
    q.z = (r(0, 2) + r(2, 0)) / s;
  } else if (r(1, 1) > r(2, 2)) {
    const double s = 2.0 * std::sqrt(1.0 + r(1, 1) - r(0, 0) - r(2, 2));
    q.w = (r(0, 2) - r(2, 0)) / s;
    q.x = (r(0, 1) + r(1, 0)) / s;
    q.y = 0.25 * s;
    q.z = (r(1, 2) + r(2, 1)) / s;
  } else {
    const double s = 2.0 * std::sqrt(1.0 + r(2, 2) - r(0, 0) - r(1, 1));
    q.w = (r(1, 0) - r(0, 1)) / s;
    q.x = (r(0, 2) + r(2, 0)) / s;
    q.y = (r(1, 2) + r(2, 1)) / s;
    q.z = 0.25 * s;
  }
  return q;
}

// A rotation by `yaw` (rad, within [-2 pi, 2 pi]) about +z, a planar robot's heading; the same
// bits on every machine (datasets hold it).
inline msgs::Quaternion quaternion_from_yaw(double yaw) {
  const perception::SinCos half = perception::portable_sin_cos(0.5 * yaw);
  msgs::Quaternion q;
  q.z = half.sin;
  q.w = half.cos;
  return q;
}

// The heading of a rotation about +z (the yaw of any unit quaternion, by its z-y-x angles).
inline double yaw_of(const msgs::Quaternion& q) {
  return std::atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z));
}

// `q` scaled to unit length: a message may hold any non-zero multiple of a rotation's
// quaternion. All NaN when its norm is zero or not finite, for it names no rotation: what is
// computed from it is NaN too.
inline msgs::Quaternion normalized(const msgs::Quaternion& q) {
  const double norm = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
  if (!(norm > 0.0) || !std::isfinite(norm)) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    return {nan, nan, nan, nan};
  }
  return {q.x / norm, q.y / norm, q.z / norm, q.w / norm};
}

// The angle (rad, 0..pi) of the rotation from unit quaternion a to b; NaN when either holds a
// NaN or an infinity (std::min would take a NaN for 1, a perfect match).
inline double rotation_angle_between(const msgs::Quaternion& a, const msgs::Quaternion& b) {
  const double dot = std::abs(a.x * b.x + a.y * b.y + a.z * b.z + a.w * b.w);
  if (!std::isfinite(dot)) return std::numeric_limits<double>::quiet_NaN();
  return 2.0 * std::acos(std::min(1.0, dot));
}

}  // namespace robotperf::localization
