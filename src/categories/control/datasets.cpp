// The control datasets: the commands a ROS 2 user would send the ros2_control demos' controllers.
#include "category.hpp"
#include "robotperf/control/control_commands.hpp"

namespace robotperf::control {
namespace {

using plugin::append;
using plugin::DatasetStream;
using plugin::make_stream;

constexpr double kGoalRateHz = 1.0 / 6.0;  // one goal every 6 s, 4 s to reach it
constexpr double kCmdVelRateHz = 5.0;
constexpr double kCommandRateHz = 50.0;
constexpr int kFrames = 100;

std::vector<DatasetStream> goal_streams(const plugin::Parameters&) {
  auto goals =
      make_stream<msgs::JointTrajectory>("goals", "/joint_trajectory_controller/joint_trajectory");
  for (auto& g : rrbot_goals()) append(goals, std::move(g));
  return {std::move(goals)};
}

std::vector<DatasetStream> cmd_vel_streams(const plugin::Parameters&) {
  auto cmd = make_stream<msgs::TwistStamped>("cmd_vel", "/diff_drive_controller/cmd_vel");
  for (auto& c : diffbot_commands(kCmdVelRateHz, kFrames)) append(cmd, std::move(c));
  return {std::move(cmd)};
}

std::vector<DatasetStream> command_streams(const plugin::Parameters&) {
  std::vector<DatasetStream> streams;
  for (auto [name, kind] : {std::pair{"position", CommandInterface::kPosition},
                            std::pair{"velocity", CommandInterface::kVelocity},
                            std::pair{"acceleration", CommandInterface::kAcceleration}}) {
    auto s = make_stream<msgs::Float64MultiArray>(
        name, std::string("/forward_") + name + "_controller/commands");
    for (auto& c : rrbot_commands(kind, kCommandRateHz, kFrames)) append(s, std::move(c));
    streams.push_back(std::move(s));
  }
  return streams;
}

}  // namespace

void register_datasets(plugin::Registrar& registrar) {
  registrar.add_dataset(
      {.name = "control/rrbot_goals",
       .description = "the RRBot demo's joint trajectory goals, one point each (zero velocity and "
                      "acceleration: quintic), [0.785, 0.785] -> [0, 0] -> [-0.785, -0.785] -> "
                      "[0, 0], 4 s to reach each, one goal every 6 s",
       .rate_hz = kGoalRateHz,
       .frames = 4,
       .streams = {{"goals", "/joint_trajectory_controller/joint_trajectory",
                    "trajectory_msgs/msg/JointTrajectory", false,
                    "the goals; also the truth the final states are checked against"}}},
      goal_streams);
  registrar.add_dataset(
      {.name = "control/diffbot_cmd_vel",
       .description = "DiffBot velocity commands, 5 Hz, 100 frames (20 s): linear.x = 0.25 + 0.2 "
                      "sin(2 pi t / 10 s) m/s with a +0.5 m/s step in the first second of every "
                      "10 s, angular.z = 0.6 sin(2 pi t / 5 s) rad/s",
       .rate_hz = kCmdVelRateHz,
       .frames = kFrames,
       .streams = {{"cmd_vel", "/diff_drive_controller/cmd_vel", "geometry_msgs/msg/TwistStamped",
                    false, "the velocity commands"}}},
      cmd_vel_streams);
  registrar.add_dataset(
      {.name = "control/rrbot_commands",
       .description = "2-joint forward commands, 50 Hz, 100 frames (2 s period): position (0.5 "
                      "sin(pi t), -0.5 sin(pi t)) rad, velocity (0.5 cos(pi t), ...) rad/s, "
                      "acceleration (0.5 sin(pi t), ...) rad/s^2; the message ID travels in "
                      "layout.dim[0].label",
       .rate_hz = kCommandRateHz,
       .frames = kFrames,
       .streams = {{"position", "/forward_position_controller/commands",
                    "std_msgs/msg/Float64MultiArray", false, "position commands, rad"},
                   {"velocity", "/forward_velocity_controller/commands",
                    "std_msgs/msg/Float64MultiArray", false, "velocity commands, rad/s"},
                   {"acceleration", "/forward_acceleration_controller/commands",
                    "std_msgs/msg/Float64MultiArray", false, "acceleration commands, rad/s^2"}}},
      command_streams);
}

}  // namespace robotperf::control
