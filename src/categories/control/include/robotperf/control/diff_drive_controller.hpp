// The differential drive controller of ros2_controllers: body twist commands -> wheel velocities
// through a speed limiter, with a command timeout, odometry by second-order Runge-Kutta
// integration, published as nav_msgs/Odometry and tf2_msgs/TFMessage at its publish rate.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "robotperf/control/controller.hpp"
#include "robotperf/control/realtime.hpp"
#include "robotperf/msgs/nav_msgs.hpp"
#include "robotperf/msgs/tf2_msgs.hpp"

namespace robotperf::control {

// ros2_controllers' SpeedLimiter without jerk limits: first the acceleration (the change from the
// previous command over dt), then the velocity is clamped.
struct SpeedLimits {
  bool has_velocity_limits = false;
  double min_velocity = 0, max_velocity = 0;
  bool has_acceleration_limits = false;
  double min_acceleration = 0, max_acceleration = 0;  // min is negative (deceleration)

  // Returns the limited velocity.
  double limit(double velocity, double previous, double dt) const;
};

// Pose of the base in the odometry frame, integrated from body velocities.
class Odometry {
 public:
  // Second-order Runge-Kutta: the heading at the middle of the step.
  void integrate(double linear, double angular, double dt);
  // Closed loop: from the wheel positions (radians) since the previous call.
  void update_from_wheels(double left_position, double right_position, double dt,
                          double wheel_separation, double wheel_radius);
  double x() const { return x_; }
  double y() const { return y_; }
  double heading() const { return heading_; }
  double linear() const { return linear_; }
  double angular() const { return angular_; }

 private:
  double x_ = 0, y_ = 0, heading_ = 0, linear_ = 0, angular_ = 0;
  bool have_wheels_ = false;
  double left_previous_ = 0, right_previous_ = 0;
};

struct DiffDriveControllerConfig {
  std::string left_wheel = "left_wheel_joint";
  std::string right_wheel = "right_wheel_joint";
  double wheel_separation = 0.10;
  double wheel_radius = 0.015;
  // Odometry from the commanded velocities (true) or from the wheel positions (false).
  bool open_loop = true;
  double cmd_vel_timeout_s = 0.5;
  double publish_rate_hz = 50.0;
  std::string odom_frame_id = "odom";
  std::string base_frame_id = "base_link";
  SpeedLimits linear, angular;
};

struct TwistCommand {
  int64_t id = kNoCommand;
  double linear = 0, angular = 0;
  int64_t received_ns = 0;  // CLOCK_MONOTONIC, for the timeout
};

class DiffDriveController final : public Controller {
 public:
  DiffDriveController(std::string name, DiffDriveControllerConfig config);

  // From a subscription thread.
  void command(const TwistCommand& command);
  // Set before activation; absent ones are not published.
  void set_publishers(std::unique_ptr<RealtimePublisher<msgs::Odometry>> odometry,
                      std::unique_ptr<RealtimePublisher<msgs::TFMessage>> tf);

  const std::string& name() const override { return name_; }
  std::vector<std::string> command_interfaces() const override;
  std::vector<std::string> state_interfaces() const override;
  void activate(SimulatedHardware& hardware) override;
  int64_t update(const UpdateContext& context) override;

  // Whether update() published odometry in its last call (the ground truth goes out with it).
  bool published_last_update() const { return published_; }
  const Odometry& odometry() const { return odometry_; }
  double last_linear() const { return last_linear_; }
  double last_angular() const { return last_angular_; }
  uint64_t timeouts() const { return timeouts_; }

 private:
  std::string name_;
  DiffDriveControllerConfig config_;
  CommandBuffer<TwistCommand> buffer_;
  std::shared_ptr<const TwistCommand> current_;
  std::unique_ptr<RealtimePublisher<msgs::Odometry>> odom_publisher_;
  std::unique_ptr<RealtimePublisher<msgs::TFMessage>> tf_publisher_;
  double* left_command_ = nullptr;
  double* right_command_ = nullptr;
  const double* left_position_ = nullptr;
  const double* right_position_ = nullptr;
  Odometry odometry_;
  double last_linear_ = 0, last_angular_ = 0;
  int64_t next_publish_ns_ = 0;
  int64_t timeout_ns_ = 0;  // cmd_vel_timeout
  bool published_ = false;
  bool timed_out_ = false;
  uint64_t timeouts_ = 0;
};

// Yaw -> quaternion (x, y, z, w) about z.
msgs::Quaternion yaw_to_quaternion(double yaw);

}  // namespace robotperf::control
