#include "robotperf/control/diff_drive_controller.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace robotperf::control {
namespace {

void set_stamp(msgs::Header& h, int64_t ns) {
  h.stamp.sec = static_cast<int32_t>(ns / 1'000'000'000);
  h.stamp.nanosec = static_cast<uint32_t>(ns % 1'000'000'000);
}

}  // namespace

double SpeedLimits::limit(double v, double previous, double dt) const {
  if (has_acceleration_limits && dt > 0) {
    v = previous + std::clamp(v - previous, min_acceleration * dt, max_acceleration * dt);
  }
  if (has_velocity_limits) v = std::clamp(v, min_velocity, max_velocity);
  return v;
}

void Odometry::integrate(double linear, double angular, double dt) {
  linear_ = linear;
  angular_ = angular;
  const double direction = heading_ + angular * dt / 2.0;
  x_ += linear * dt * std::cos(direction);
  y_ += linear * dt * std::sin(direction);
  heading_ += angular * dt;
}

void Odometry::update_from_wheels(double left, double right, double dt, double separation,
                                  double radius) {
  if (!have_wheels_) {
    have_wheels_ = true;
    left_previous_ = left;
    right_previous_ = right;
    return;
  }
  const double dl = (left - left_previous_) * radius;
  const double dr = (right - right_previous_) * radius;
  left_previous_ = left;
  right_previous_ = right;
  const double distance = (dl + dr) / 2.0;
  const double rotation = (dr - dl) / separation;
  if (dt > 0) integrate(distance / dt, rotation / dt, dt);
}

msgs::Quaternion yaw_to_quaternion(double yaw) {
  msgs::Quaternion q;
  q.x = 0;
  q.y = 0;
  q.z = std::sin(yaw / 2.0);
  q.w = std::cos(yaw / 2.0);
  return q;
}

DiffDriveController::DiffDriveController(std::string name, DiffDriveControllerConfig config)
    : name_(std::move(name)), config_(std::move(config)) {
  if (!(config_.wheel_separation > 0) || !(config_.wheel_radius > 0))
    throw std::invalid_argument(name_ + ": wheel_separation and wheel_radius must be positive");
  if (!(config_.publish_rate_hz > 0) || !std::isfinite(config_.publish_rate_hz))
    throw std::invalid_argument(name_ + ": publish_rate must be a positive number");
  // In nanoseconds, it must fit an int64.
  if (!(config_.cmd_vel_timeout_s >= 0) || !(config_.cmd_vel_timeout_s <= 1e9))
    throw std::invalid_argument(name_ + ": cmd_vel_timeout must be from 0 to 1e9 s");
  timeout_ns_ = static_cast<int64_t>(config_.cmd_vel_timeout_s * 1e9);
  for (const SpeedLimits* l : {&config_.linear, &config_.angular}) {
    if (l->has_velocity_limits && !(l->min_velocity <= l->max_velocity))
      throw std::invalid_argument(name_ + ": a velocity limit's minimum is above its maximum");
    // An acceleration range without 0 would never let the speed settle (ros2_controllers'
    // speed limiter refuses a positive min_acceleration).
    if (l->has_acceleration_limits && !(l->min_acceleration <= 0 && 0 <= l->max_acceleration))
      throw std::invalid_argument(name_ +
                                  ": acceleration limits must hold 0 (min_acceleration <= 0 <= "
                                  "max_acceleration)");
  }
}

void DiffDriveController::command(const TwistCommand& c) {
  buffer_.write(std::make_shared<const TwistCommand>(c));
}

void DiffDriveController::set_publishers(
    std::unique_ptr<RealtimePublisher<msgs::Odometry>> odometry,
    std::unique_ptr<RealtimePublisher<msgs::TFMessage>> tf) {
  odom_publisher_ = std::move(odometry);
  tf_publisher_ = std::move(tf);
}

std::vector<std::string> DiffDriveController::command_interfaces() const {
  return {config_.left_wheel + "/velocity", config_.right_wheel + "/velocity"};
}

std::vector<std::string> DiffDriveController::state_interfaces() const {
  return {config_.left_wheel + "/position", config_.right_wheel + "/position"};
}

void DiffDriveController::activate(SimulatedHardware& hw) {
  left_command_ = hw.command_interface(config_.left_wheel + "/velocity");
  right_command_ = hw.command_interface(config_.right_wheel + "/velocity");
  left_position_ = hw.state_interface(config_.left_wheel + "/position");
  right_position_ = hw.state_interface(config_.right_wheel + "/position");
  if (odom_publisher_) {
    auto& m = odom_publisher_->msg();
    m.header.frame_id = config_.odom_frame_id;
    m.child_frame_id = config_.base_frame_id;
  }
  if (tf_publisher_) {
    auto& m = tf_publisher_->msg();
    m.transforms.resize(1);
    m.transforms[0].header.frame_id = config_.odom_frame_id;
    m.transforms[0].child_frame_id = config_.base_frame_id;
  }
}

int64_t DiffDriveController::update(const UpdateContext& ctx) {
  const double dt = ctx.period_s;
  int64_t taken = kNoCommand;
  if (buffer_.take(current_)) {
    taken = current_->id;
    timed_out_ = false;
  }
  double linear = 0, angular = 0;
  if (current_ && ctx.now_ns - current_->received_ns <= timeout_ns_) {
    linear = current_->linear;
    angular = current_->angular;
  } else if (current_ && !timed_out_) {
    timed_out_ = true;  // stop once, as the timeout says
    ++timeouts_;
  }
  linear = config_.linear.limit(linear, last_linear_, dt);
  angular = config_.angular.limit(angular, last_angular_, dt);
  last_linear_ = linear;
  last_angular_ = angular;

  if (config_.open_loop) {
    odometry_.integrate(linear, angular, dt);
  } else {
    odometry_.update_from_wheels(*left_position_, *right_position_, dt, config_.wheel_separation,
                                 config_.wheel_radius);
  }
  const double half = angular * config_.wheel_separation / 2.0;
  *left_command_ = (linear - half) / config_.wheel_radius;
  *right_command_ = (linear + half) / config_.wheel_radius;

  published_ = false;
  if (ctx.observed_command != kNoCommand && ctx.now_ns >= next_publish_ns_) {
    const auto period = static_cast<int64_t>(1e9 / config_.publish_rate_hz);
    // Keep the publish rate's phase; after a pause, start again from now.
    next_publish_ns_ = std::max(next_publish_ns_ + period, ctx.now_ns + period / 2);
    const msgs::Quaternion q = yaw_to_quaternion(odometry_.heading());
    if (odom_publisher_ && odom_publisher_->try_lock()) {
      auto& m = odom_publisher_->msg();
      set_stamp(m.header, ctx.observed_command);
      m.pose.pose.position.x = odometry_.x();
      m.pose.pose.position.y = odometry_.y();
      m.pose.pose.orientation = q;
      m.twist.twist.linear.x = odometry_.linear();
      m.twist.twist.angular.z = odometry_.angular();
      odom_publisher_->unlock_and_publish();
      published_ = true;
    }
    if (tf_publisher_ && tf_publisher_->try_lock()) {
      auto& t = tf_publisher_->msg().transforms[0];
      set_stamp(t.header, ctx.observed_command);
      t.transform.translation.x = odometry_.x();
      t.transform.translation.y = odometry_.y();
      t.transform.rotation = q;
      tf_publisher_->unlock_and_publish();
    }
  }
  return taken;
}

}  // namespace robotperf::control
