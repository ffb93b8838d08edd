// Deterministic request streams for the manipulation benchmarks (d1-d6) on the built-in xArm6
// and its one-box scene, generated from a seed.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "robotperf/msgs/geometry_msgs.hpp"
#include "robotperf/msgs/robotperf_msgs.hpp"
#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/msgs/trajectory_msgs.hpp"

namespace robotperf::manipulation {

struct ManipulationWorkload {
  uint64_t seed = 1;
  std::size_t requests = 200;
  // Collision states: the share whose flange is within 0.15 m of the box (the rest anywhere).
  double near_fraction = 0.5;
};

// Joint states uniform within the limits, and their flange poses by the Eigen transform chain of
// the URDF (independent of KDL): FK requests and truth; IK targets are the poses.
struct KinematicsRequests {
  std::vector<msgs::JointState> states;
  std::vector<msgs::PoseStamped> poses;
};
KinematicsRequests generate_kinematics_requests(const ManipulationWorkload& workload);

// Joint states near and far from the box whose answer the sampled ground truth knows for certain,
// and that answer. Near and far are interleaved: the first k states hold ceil(k * near / requests)
// near ones, `near` being near_fraction * requests rounded.
struct CollisionRequests {
  std::vector<msgs::JointState> states;
  std::vector<msgs::CollisionResult> truth;
};
CollisionRequests generate_collision_requests(const ManipulationWorkload& workload);

// Planning queries around the box: a JointTrajectory of two points, start (flange on one side of
// the box, low) and goal (on the other side); both certainly collision-free and free with every
// link grown by kPlanningQueryClearance, the straight joint-space line between them not.
inline constexpr double kPlanningQueryClearance = 0.01;  // m
std::vector<msgs::JointTrajectory> generate_planning_queries(const ManipulationWorkload& workload);

}  // namespace robotperf::manipulation
