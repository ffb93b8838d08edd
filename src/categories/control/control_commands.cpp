#include "robotperf/control/control_commands.hpp"

#include <cmath>
#include <numbers>

namespace robotperf::control {

std::vector<msgs::JointTrajectory> rrbot_goals(double reach_s) {
  std::vector<msgs::JointTrajectory> goals;
  for (double target : {0.785, 0.0, -0.785, 0.0}) {
    msgs::JointTrajectory goal;
    goal.joint_names = {"joint1", "joint2"};
    msgs::JointTrajectoryPoint p;
    p.positions = {target, target};
    p.velocities = {0.0, 0.0};
    p.accelerations = {0.0, 0.0};
    const auto ns = static_cast<int64_t>(std::llround(reach_s * 1e9));
    p.time_from_start.sec = static_cast<int32_t>(ns / 1'000'000'000);
    p.time_from_start.nanosec = static_cast<uint32_t>(ns % 1'000'000'000);
    goal.points.push_back(std::move(p));
    goals.push_back(std::move(goal));
  }
  return goals;
}

std::vector<msgs::TwistStamped> diffbot_commands(double rate_hz, int frames) {
  std::vector<msgs::TwistStamped> out;
  const double pi = std::numbers::pi;
  for (int k = 0; k < frames; ++k) {
    const double t = k / rate_hz;
    msgs::TwistStamped c;
    c.header.frame_id = "base_link";
    c.twist.linear.x = 0.25 + 0.2 * std::sin(2 * pi * t / 10.0);
    if (std::fmod(t, 10.0) < 1.0) c.twist.linear.x += 0.5;
    c.twist.angular.z = 0.6 * std::sin(2 * pi * t / 5.0);
    out.push_back(c);
  }
  return out;
}

std::vector<msgs::Float64MultiArray> rrbot_commands(CommandInterface kind, double rate_hz,
                                                    int frames) {
  std::vector<msgs::Float64MultiArray> out;
  const double pi = std::numbers::pi;
  for (int k = 0; k < frames; ++k) {
    const double t = k / rate_hz;
    const double v =
        kind == CommandInterface::kVelocity ? 0.5 * std::cos(pi * t) : 0.5 * std::sin(pi * t);
    msgs::Float64MultiArray m;
    m.data = {v, -v};
    out.push_back(std::move(m));
  }
  return out;
}

}  // namespace robotperf::control
