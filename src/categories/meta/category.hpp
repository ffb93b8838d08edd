// Private to the meta category: the parts it registers, and the turtle demo's follow command,
// which the listener kernel and the dataset's truth both apply (to the transform each finds).
#pragma once

#include <cmath>

#include "robotperf/msgs/geometry_msgs.hpp"
#include "robotperf/plugin.hpp"

namespace robotperf::meta {

void register_kernels(plugin::Registrar& registrar);
void register_datasets(plugin::Registrar& registrar);
void register_evaluators(plugin::Registrar& registrar);

// turtle_tf2_listener's command for the leader at (x, y) in the follower's frame: turn towards it
// at 1.0 x its bearing, drive at 0.5 x its distance (geometry2's turtle_tf2 demo).
inline msgs::Twist follow_command(double x, double y) {
  constexpr double kRotationGain = 1.0, kForwardGain = 0.5;
  msgs::Twist t;
  t.angular.z = kRotationGain * std::atan2(y, x);
  t.linear.x = kForwardGain * std::sqrt(x * x + y * y);
  return t;
}

}  // namespace robotperf::meta
