#pragma once

// Deterministic command streams for the control benchmarks (c1-c5): what a ROS 2 user would
// publish to the controllers of the ros2_control demos. Stamps are left zero: the Playback gives
// every message its ID.

#include <vector>

#include "robotperf/msgs/geometry_msgs.hpp"
#include "robotperf/msgs/std_msgs.hpp"
#include "robotperf/msgs/trajectory_msgs.hpp"

namespace robotperf::control {

// c1: the RRBot demo's goals, one point each with zero velocity and acceleration (a quintic from
// the current state), [0.785, 0.785] -> [0, 0] -> [-0.785, -0.785] -> [0, 0], each to be reached
// `reach_s` after it starts; for joints joint1 and joint2.
std::vector<msgs::JointTrajectory> rrbot_goals(double reach_s = 4.0);

// c2: `frames` TwistStamped commands at `rate_hz` for the DiffBot: linear.x = 0.25 + 0.2
// sin(2 pi t / 10 s) m/s, angular.z = 0.6 sin(2 pi t / 5 s) rad/s, plus a step of +0.5 m/s in
// linear.x during the first second of every 10 s (so that the acceleration limiter acts). The
// stream loops without a jump when frames / rate_hz is a multiple of 10 s.
std::vector<msgs::TwistStamped> diffbot_commands(double rate_hz = 5.0, int frames = 100);

// c3-c5: 2-joint Float64MultiArray commands at `rate_hz` for `frames` frames:
// position = (0.5 sin(pi t), -0.5 sin(pi t)) rad, velocity = (0.5 cos(pi t), -0.5 cos(pi t))
// rad/s, acceleration = (0.5 sin(pi t), -0.5 sin(pi t)) rad/s^2; periodic over 2 s.
enum class CommandInterface { kPosition, kVelocity, kAcceleration };
std::vector<msgs::Float64MultiArray> rrbot_commands(CommandInterface kind, double rate_hz = 50.0,
                                                    int frames = 100);

}  // namespace robotperf::control
