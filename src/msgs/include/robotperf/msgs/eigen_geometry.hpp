// geometry_msgs/Pose and Transform <-> Eigen rigid transform, for the kernels, datasets and checks
// that turn messages into poses they compute with. Header-only: who includes it needs Eigen (the
// msgs library itself does not).
#pragma once

#include <Eigen/Geometry>

#include "robotperf/msgs/geometry_msgs.hpp"

namespace robotperf::msgs {

// The quaternion is normalised: a message rounds it, the model needs a rotation.
inline Eigen::Isometry3d isometry_of(const Pose& p) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() =
      Eigen::Quaterniond(p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z)
          .normalized()
          .toRotationMatrix();
  t.translation() = Eigen::Vector3d(p.position.x, p.position.y, p.position.z);
  return t;
}

inline Pose pose_msg_of(const Eigen::Isometry3d& t) {
  const Eigen::Quaterniond r(t.linear());
  Pose p;
  p.position = {t.translation().x(), t.translation().y(), t.translation().z()};
  p.orientation = {r.x(), r.y(), r.z(), r.w()};
  return p;
}

// A tf2 transform is a pose of the child frame in its parent: the same conversions.
inline Eigen::Isometry3d isometry_of(const Transform& t) {
  return isometry_of(Pose{{t.translation.x, t.translation.y, t.translation.z}, t.rotation});
}

inline Transform transform_msg_of(const Eigen::Isometry3d& t) {
  const Pose p = pose_msg_of(t);
  return {{p.position.x, p.position.y, p.position.z}, p.orientation};
}

}  // namespace robotperf::msgs
