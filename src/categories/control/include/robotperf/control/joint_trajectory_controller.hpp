// The joint trajectory controller of ros2_controllers: samples a spline through the goal's points
// (starting from the current state), writes position commands, checks path and goal tolerances
// and reports control_msgs/JointTrajectoryControllerState.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "robotperf/control/controller.hpp"
#include "robotperf/control/realtime.hpp"
#include "robotperf/msgs/trajectory_msgs.hpp"

namespace robotperf::control {

// Position, velocity and acceleration of one joint at one time.
struct JointSample {
  double position = 0, velocity = 0, acceleration = 0;
};

// The segment from `start` (at 0) to `end` (at duration_s), of the degree ros2_controllers picks
// from what the end point gives: positions only -> linear, with velocities -> cubic, with
// accelerations too -> quintic (matching position, velocity and acceleration at both ends).
enum class SplineKind { kLinear, kCubic, kQuintic };
struct SplineSegment {
  SplineKind kind = SplineKind::kLinear;
  double duration_s = 0;
  std::array<double, 6> coefficients{};  // position = sum c_i t^i
  static SplineSegment make(SplineKind kind, const JointSample& start, const JointSample& end,
                            double duration_s);
  // Clamped to [0, duration_s].
  JointSample sample(double t) const;
};

struct JointTrajectoryControllerConfig {
  std::vector<std::string> joints{"joint1", "joint2"};
  // Per joint, 0 = not checked (ros2_controllers' constraints.<joint>.trajectory / .goal).
  std::vector<double> path_tolerance;
  std::vector<double> goal_tolerance;
  // A goal not within tolerance this long after its last point's time is aborted (0: no limit).
  double goal_time_s = 0.0;
  // rad/s a joint may still move at when its goal counts as reached (0: not checked).
  double stopped_velocity_tolerance = 0.01;
};

// A goal checked and reordered to the controller's joints (outside the loop).
struct PreparedTrajectory {
  int64_t id = kNoCommand;
  std::vector<double> times_s;                   // time_from_start of each point
  std::vector<std::vector<JointSample>> points;  // [point][joint]
  SplineKind kind = SplineKind::kLinear;
  // segments[i][joint] from point i - 1 to point i, for i >= 1 (segments[0] is empty: the
  // segment into the first point starts from the state when the trajectory starts).
  std::vector<std::vector<SplineSegment>> segments;
};

class JointTrajectoryController final : public Controller {
 public:
  using State = msgs::JointTrajectoryControllerState;
  JointTrajectoryController(std::string name, JointTrajectoryControllerConfig config,
                            Logger log = stderr_logger("joint_trajectory_controller"));

  // From a subscription thread: checks the goal (joint names, sizes, increasing times) and queues
  // it; returns false (and logs why) when rejected.
  bool command(const msgs::JointTrajectory& goal, int64_t id);
  // Where the state is published from (set before activation; absent: not published).
  void set_state_publisher(std::unique_ptr<RealtimePublisher<State>> publisher);

  const std::string& name() const override { return name_; }
  std::vector<std::string> command_interfaces() const override;
  std::vector<std::string> state_interfaces() const override;
  void activate(SimulatedHardware& hardware) override;
  int64_t update(const UpdateContext& context) override;

  // Counters; read while the loop is stopped.
  uint64_t goals_accepted() const { return accepted_; }
  uint64_t goals_rejected() const { return rejected_; }
  uint64_t goals_succeeded() const { return succeeded_; }
  uint64_t goals_aborted() const { return aborted_; }
  bool active() const { return trajectory_ != nullptr; }
  const std::vector<JointSample>& reference() const { return reference_; }

 private:
  void start_trajectory(double now_s);
  void hold(const std::vector<double>& positions);
  void publish(const UpdateContext& context);

  std::string name_;
  JointTrajectoryControllerConfig config_;
  Logger log_;
  CommandBuffer<PreparedTrajectory> buffer_;
  std::unique_ptr<RealtimePublisher<State>> publisher_;
  std::vector<double*> position_commands_;
  std::vector<const double*> position_states_, velocity_states_;
  // The trajectory being followed (null when holding) and, per joint, its first segment.
  std::shared_ptr<const PreparedTrajectory> trajectory_;
  std::vector<SplineSegment> first_segment_;
  double trajectory_start_s_ = 0;
  bool have_reference_ = false;
  std::vector<JointSample> reference_;
  std::vector<double> feedback_position_, feedback_velocity_;
  uint64_t accepted_ = 0, rejected_ = 0, succeeded_ = 0, aborted_ = 0;
};

}  // namespace robotperf::control
