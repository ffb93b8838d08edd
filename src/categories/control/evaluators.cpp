// Functional evaluators of the control benchmarks.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "category.hpp"
#include "robotperf/msgs/nav_msgs.hpp"
#include "robotperf/msgs/trajectory_msgs.hpp"

namespace robotperf::control {
namespace {

using plugin::DatasetStream;
using plugin::FunctionalEvaluator;

// joint_trajectory_goals: the last controller state reported for each goal (state output: the
// Monitor keeps the last message carrying the goal's ID, just before the next goal starts).
class JointTrajectoryGoalsEvaluator final : public FunctionalEvaluator {
 public:
  explicit JointTrajectoryGoalsEvaluator(const DatasetStream& goals) : goals_(goals) {
    plugin::require_type<msgs::JointTrajectory>(goals, "joint_trajectory_goals");
  }

  void add(const void* output, std::size_t frame) override {
    const auto& state = *static_cast<const msgs::JointTrajectoryControllerState*>(output);
    const auto& goal = *static_cast<const msgs::JointTrajectory*>(goals_.messages[frame].get());
    const auto& target = goal.points.back().positions;
    if (state.feedback.positions.size() != goal.joint_names.size() ||
        state.reference.positions.size() != goal.joint_names.size() ||
        state.joint_names.size() != goal.joint_names.size()) {
      problem("controller state has " + std::to_string(state.feedback.positions.size()) +
              " joints, the goals " + std::to_string(goal.joint_names.size()));
      return;
    }
    double error = 0;
    bool reached = true;
    for (std::size_t j = 0; j < state.joint_names.size(); ++j) {
      const auto k = static_cast<std::size_t>(
          std::find(goal.joint_names.begin(), goal.joint_names.end(), state.joint_names[j]) -
          goal.joint_names.begin());
      if (k == goal.joint_names.size()) {
        problem("controller state names joint " + state.joint_names[j] + ", not in the goals");
        return;
      }
      error = std::max(error, std::abs(state.feedback.positions[j] - target[k]));
      // An aborted goal holds where the robot was instead of the goal.
      reached &= std::abs(state.reference.positions[j] - target[k]) < 1e-6;
    }
    ++evaluated_;
    reached_ += reached;
    max_error_ = std::max(max_error_, error);
  }

  std::map<std::string, double> metrics() const override {
    const double nan = std::nan("");
    return {{"goal_error_max_rad", evaluated_ ? max_error_ : nan},
            {"goals_reached_fraction",
             evaluated_ ? static_cast<double>(reached_) / static_cast<double>(evaluated_) : nan}};
  }

 private:
  const DatasetStream& goals_;
  std::size_t evaluated_ = 0, reached_ = 0;
  double max_error_ = 0;
};

// diff_drive_odometry: the odometry against the simulated robot's true pose in the same cycle.
class DiffDriveOdometryEvaluator final : public FunctionalEvaluator {
 public:
  void add(const void* output, std::size_t frame) override { add_observed(output, nullptr, frame); }

  void add_observed(const void* output, const void* truth, std::size_t) override {
    ++outputs_;
    if (truth == nullptr) return;
    const auto& odom = *static_cast<const msgs::Odometry*>(output);
    const auto& real = *static_cast<const msgs::Odometry*>(truth);
    const auto& a = odom.pose.pose;
    const auto& b = real.pose.pose;
    ++observed_;
    max_position_ = std::max(max_position_,
                             std::hypot(a.position.x - b.position.x, a.position.y - b.position.y));
    const double yaw_a = 2 * std::atan2(a.orientation.z, a.orientation.w);
    const double yaw_b = 2 * std::atan2(b.orientation.z, b.orientation.w);
    const double d = std::remainder(yaw_a - yaw_b, 2 * std::numbers::pi);
    max_heading_ = std::max(max_heading_, std::abs(d));
  }

  std::map<std::string, double> metrics() const override {
    const double nan = std::nan("");
    return {{"position_error_max_m", observed_ ? max_position_ : nan},
            {"heading_error_max_rad", observed_ ? max_heading_ : nan},
            {"truth_observed_fraction",
             outputs_ ? static_cast<double>(observed_) / static_cast<double>(outputs_) : nan}};
  }

 private:
  std::size_t outputs_ = 0, observed_ = 0;
  double max_position_ = 0, max_heading_ = 0;
};

}  // namespace

void register_evaluators(plugin::Registrar& registrar) {
  registrar.add_evaluator(
      {.name = "joint_trajectory_goals",
       .description =
           "each goal's last reported controller state: the measured position against the goal",
       .output_type = "control_msgs/msg/JointTrajectoryControllerState",
       .truth_roles = {"goals"},
       .metrics = {{"goal_error_max_rad", "rad",
                    "largest |measured position - goal| of any joint in the last state of any "
                    "goal"},
                   {"goals_reached_fraction", "fraction",
                    "share of goals whose trajectory ended at the goal (not aborted by a "
                    "tolerance)"}}},
      [](const plugin::TruthStreams& truth, const plugin::Parameters&) {
        return std::make_unique<JointTrajectoryGoalsEvaluator>(truth["goals"]);
      });
  registrar.add_evaluator(
      {.name = "diff_drive_odometry",
       .description = "odometry against the simulated robot's true pose reported in the same cycle",
       .output_type = "nav_msgs/msg/Odometry",
       .truth_roles = {"commands"},
       .metrics = {{"position_error_max_m", "m",
                    "largest distance between odometry and true position"},
                   {"heading_error_max_rad", "rad", "largest heading difference"},
                   {"truth_observed_fraction", "fraction",
                    "share of evaluated outputs for which the true pose was received"}},
       .observed_truth_type = "nav_msgs/msg/Odometry"},
      [](const plugin::TruthStreams&, const plugin::Parameters&) {
        return std::make_unique<DiffDriveOdometryEvaluator>();
      });
}

}  // namespace robotperf::control
