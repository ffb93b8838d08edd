// Control kernels: a controller manager loop with one controller on simulated
// hardware, as a graph node. Commands arrive on a subscription (the executor's thread) and reach
// the loop through a real-time buffer; states leave through real-time publishers, stamped with the
// ID of the newest command they reflect.
#include <stdexcept>

#include "category.hpp"
#include "robotperf/control/controller_manager.hpp"
#include "robotperf/control/diff_drive_controller.hpp"
#include "robotperf/control/forward_command_controller.hpp"
#include "robotperf/control/joint_trajectory_controller.hpp"
#include "robotperf/msgs/geometry_msgs.hpp"

namespace robotperf::control {
namespace {

using plugin::KernelConfig;
using plugin::Parameters;

int64_t stamp_ns(const msgs::Header& h) {
  return int64_t{h.stamp.sec} * 1'000'000'000 + h.stamp.nanosec;
}

// The loop's parameters, shared by every control kernel.
control::LoopConfig loop_config(const KernelConfig& config) {
  const auto& p = config.parameters;
  control::LoopConfig c;
  c.name = config.node_name;
  c.update_rate_hz = p.get_double("update_rate");
  c.cpu = p.get_int32("cpu");
  c.rt_priority = p.get_int32("rt_priority");
  const int64_t capacity = p.get_int("cycle_capacity");
  if (capacity < 1)
    throw std::invalid_argument("node '" + config.node_name + "': cycle_capacity must be >= 1");
  c.cycle_capacity = static_cast<std::size_t>(capacity);
  return c;
}

control::HardwareConfig hardware_config(const KernelConfig& config) {
  const auto& p = config.parameters;
  control::HardwareConfig h;
  h.type = p.get_string("hardware");
  if (h.type == "rrbot") {
    h.position_time_constant_s = p.get_double("position_time_constant");
  } else if (p.has("position_time_constant")) {
    throw std::invalid_argument("node '" + config.node_name +
                                "': position_time_constant applies to rrbot hardware only");
  }
  return h;
}

// A graph node owning a controller manager. Subclasses add their controllers, then call start().
class ControlNode : public graph::Node,
                    public plugin::NodeCounters,
                    public plugin::ControlLoopSource {
 public:
  ~ControlNode() override { manager_->stop(); }

  control::LoopReport stop_and_report() override {
    manager_->stop();
    return manager_->report();
  }

 protected:
  ControlNode(graph::Context& context, const KernelConfig& config,
              const control::HardwareConfig& hardware)
      : Node(context, config.node_name),
        manager_(std::make_unique<control::ControllerManager>(control::make_hardware(hardware),
                                                              loop_config(config))) {}

  // A real-time publisher on the topic wired to `port`, or null when the port is not wired.
  template <class T>
  std::unique_ptr<control::RealtimePublisher<T>> realtime_publisher(const KernelConfig& config,
                                                                    const std::string& port) {
    if (!config.topics.contains(port)) return nullptr;
    auto pub = create_publisher<T>(config.topic(port), config.qos);
    return std::make_unique<control::RealtimePublisher<T>>([pub](const T& m) { pub->publish(m); });
  }

  control::ControllerManager& manager() { return *manager_; }
  void start() {
    try {
      manager_->start();
    } catch (const std::runtime_error& e) {
      throw std::invalid_argument(e.what());  // a configuration the machine does not permit
    }
  }

 private:
  std::unique_ptr<control::ControllerManager> manager_;
};

class JointTrajectoryControllerNode final : public ControlNode {
 public:
  JointTrajectoryControllerNode(graph::Context& context, const KernelConfig& config)
      : ControlNode(context, config, hardware_config(config)) {
    const auto& p = config.parameters;
    control::JointTrajectoryControllerConfig c;
    const std::size_t n = c.joints.size();
    c.path_tolerance.assign(n, p.get_double("path_tolerance"));
    c.goal_tolerance.assign(n, p.get_double("goal_tolerance"));
    c.goal_time_s = p.get_double("goal_time");
    c.stopped_velocity_tolerance = p.get_double("stopped_velocity_tolerance");
    controller_ = std::make_shared<control::JointTrajectoryController>(
        "joint_trajectory_controller", c, control::stderr_logger(name()));
    controller_->set_state_publisher(
        realtime_publisher<control::JointTrajectoryController::State>(config, "controller_state"));
    manager().add_controller(controller_);
    subscription_ = create_subscription<msgs::JointTrajectory>(
        config.topic("joint_trajectory"), config.qos,
        [this](std::shared_ptr<const msgs::JointTrajectory> m) {
          controller_->command(*m, stamp_ns(m->header));
        });
    start();
  }

  std::map<std::string, uint64_t> counters() const override {
    return {{"goals_accepted", controller_->goals_accepted()},
            {"goals_rejected", controller_->goals_rejected()},
            {"goals_succeeded", controller_->goals_succeeded()},
            {"goals_aborted", controller_->goals_aborted()}};
  }

 private:
  std::shared_ptr<control::JointTrajectoryController> controller_;
  std::shared_ptr<graph::GenericSubscription> subscription_;
};

control::SpeedLimits speed_limits(const Parameters& p, const std::string& axis) {
  control::SpeedLimits l;
  l.has_velocity_limits = p.get_bool(axis + ".has_velocity_limits");
  l.max_velocity = p.get_double(axis + ".max_velocity");
  l.min_velocity = p.get_double(axis + ".min_velocity", -l.max_velocity);
  l.has_acceleration_limits = p.get_bool(axis + ".has_acceleration_limits");
  l.max_acceleration = p.get_double(axis + ".max_acceleration");
  l.min_acceleration = p.get_double(axis + ".min_acceleration", -l.max_acceleration);
  return l;
}

class DiffDriveControllerNode final : public ControlNode {
 public:
  DiffDriveControllerNode(graph::Context& context, const KernelConfig& config)
      : ControlNode(context, config, diffbot_config(config)) {
    const auto& p = config.parameters;
    control::DiffDriveControllerConfig c;
    c.wheel_separation = p.get_double("wheel_separation");
    c.wheel_radius = p.get_double("wheel_radius");
    c.open_loop = p.get_bool("open_loop");
    c.cmd_vel_timeout_s = p.get_double("cmd_vel_timeout");
    c.publish_rate_hz = p.get_double("publish_rate");
    c.linear = speed_limits(p, "linear.x");
    c.angular = speed_limits(p, "angular.z");
    controller_ = std::make_shared<control::DiffDriveController>("diff_drive_controller", c);
    controller_->set_publishers(realtime_publisher<msgs::Odometry>(config, "odom"),
                                realtime_publisher<msgs::TFMessage>(config, "tf"));
    manager().add_controller(controller_);
    // Ground truth of the simulated base in the cycles the odometry goes out and with the same
    // ID (as Gazebo's p3d plugin would report it), at the instant the odometry describes:
    // open-loop odometry integrates the cycle's command, which write() has just applied;
    // closed-loop odometry is of the wheel positions read() gave before it, the pose after the
    // previous cycle's write.
    if (auto truth = realtime_publisher<msgs::Odometry>(config, "ground_truth")) {
      truth->msg().header.frame_id = "odom";
      truth->msg().child_frame_id = "base_link";
      truth_ = std::move(truth);
      manager().set_after_write([this, open_loop = c.open_loop](const control::UpdateContext& ctx) {
        const control::BasePose& moved = *manager().hardware().base_pose();
        const control::BasePose pose = open_loop ? moved : pose_at_read_;
        pose_at_read_ = moved;
        if (!controller_->published_last_update() || !truth_->try_lock()) return;
        auto& m = truth_->msg();
        m.header.stamp.sec = static_cast<int32_t>(ctx.observed_command / 1'000'000'000);
        m.header.stamp.nanosec = static_cast<uint32_t>(ctx.observed_command % 1'000'000'000);
        m.pose.pose.position.x = pose.x;
        m.pose.pose.position.y = pose.y;
        m.pose.pose.orientation = control::yaw_to_quaternion(pose.yaw);
        m.twist.twist.linear.x = pose.linear;
        m.twist.twist.angular.z = pose.angular;
        truth_->unlock_and_publish();
      });
    }
    if (p.get_bool("use_stamped_vel")) {
      subscription_ = create_subscription<msgs::TwistStamped>(
          config.topic("cmd_vel"), config.qos, [this](std::shared_ptr<const msgs::TwistStamped> m) {
            controller_->command(
                {stamp_ns(m->header), m->twist.linear.x, m->twist.angular.z, rmw::steady_now_ns()});
          });
    } else {
      // geometry_msgs/Twist has no header: the command is identified by its arrival time,
      // which no Playback ID matches (see the README).
      subscription_ = create_subscription<msgs::Twist>(
          config.topic("cmd_vel"), config.qos, [this](std::shared_ptr<const msgs::Twist> m) {
            const int64_t now = rmw::steady_now_ns();
            controller_->command({now, m->linear.x, m->angular.z, now});
          });
    }
    start();
  }

  // The loop calls back into truth_: stop it before the members go.
  ~DiffDriveControllerNode() override { manager().stop(); }

  std::map<std::string, uint64_t> counters() const override {
    return {{"cmd_vel_timeouts", controller_->timeouts()}};
  }

 private:
  static control::HardwareConfig diffbot_config(const KernelConfig& config) {
    control::HardwareConfig h = hardware_config(config);
    // The simulated robot has the geometry the controller is configured with.
    h.wheel_separation_m = config.parameters.get_double("wheel_separation");
    h.wheel_radius_m = config.parameters.get_double("wheel_radius");
    return h;
  }

  std::shared_ptr<control::DiffDriveController> controller_;
  std::unique_ptr<control::RealtimePublisher<msgs::Odometry>> truth_;
  control::BasePose pose_at_read_;  // the loop thread's alone
  std::shared_ptr<graph::GenericSubscription> subscription_;
};

class ForwardCommandControllerNode final : public ControlNode {
 public:
  ForwardCommandControllerNode(graph::Context& context, const KernelConfig& config)
      : ControlNode(context, config, hardware_config(config)) {
    control::ForwardCommandControllerConfig c;
    c.interface_name = config.parameters.get_string("interface_name");
    controller_ = std::make_shared<control::ForwardCommandController>(
        "forward_" + c.interface_name + "_controller", c, control::stderr_logger(name()));
    manager().add_controller(controller_);
    if (auto pub = realtime_publisher<msgs::JointState>(config, "joint_states")) {
      manager().add_controller(std::make_shared<control::JointStateBroadcaster>(
          "joint_state_broadcaster", c.joints, std::move(pub)));
    }
    subscription_ = create_subscription<msgs::Float64MultiArray>(
        config.topic("commands"), config.qos,
        [this](std::shared_ptr<const msgs::Float64MultiArray> m) {
          controller_->command(std::move(m));
        });
    start();
  }

  std::map<std::string, uint64_t> counters() const override {
    return {{"rejected_commands", controller_->rejected()}};
  }

 private:
  std::shared_ptr<control::ForwardCommandController> controller_;
  std::shared_ptr<graph::GenericSubscription> subscription_;
};

// The controller manager's parameters, shared by every control kernel.
std::vector<plugin::ParameterInfo> loop_parameters(const std::string& default_hardware) {
  const LoopConfig loop;
  const HardwareConfig hardware;
  return {
      plugin::double_parameter("update_rate", loop.update_rate_hz,
                               "the controller manager's loop rate, Hz (run --update-rate)"),
      plugin::int_parameter("cpu", loop.cpu, "pin the loop thread to this CPU; -1: not pinned"),
      plugin::int_parameter("rt_priority", loop.rt_priority,
                            "SCHED_FIFO priority of the loop, 1-99; 0: the normal scheduler"),
      plugin::int_parameter("cycle_capacity", static_cast<int64_t>(loop.cycle_capacity),
                            "cycles whose timestamps are kept (later ones are only counted)"),
      plugin::string_parameter("hardware", default_hardware,
                               "simulated hardware: rrbot, rrbot_multi_interface or diffbot"),
      plugin::double_parameter("position_time_constant", hardware.position_time_constant_s,
                               "rrbot: first-order lag of the joints behind a position command, "
                               "s (0: reached within the cycle)"),
  };
}

// The loop's rate parameter; a begin and an end event per controller update, two controllers at
// most per controller manager.
plugin::ControlLoopInfo control_loop() {
  return {"update_rate", 4.0};
}

std::vector<plugin::ParameterInfo> with(std::vector<plugin::ParameterInfo> a,
                                        const std::vector<plugin::ParameterInfo>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

std::vector<plugin::ParameterInfo> speed_limit_parameters(const std::string& axis) {
  const SpeedLimits l;
  return {
      plugin::bool_parameter(axis + ".has_velocity_limits", l.has_velocity_limits,
                             "limit the " + axis + " velocity"),
      plugin::double_parameter(axis + ".max_velocity", l.max_velocity, "largest velocity"),
      plugin::computed_parameter(axis + ".min_velocity", plugin::ParameterType::kDouble,
                                 "smallest velocity (default: -max_velocity)"),
      plugin::bool_parameter(axis + ".has_acceleration_limits", l.has_acceleration_limits,
                             "limit the " + axis + " acceleration"),
      plugin::double_parameter(axis + ".max_acceleration", l.max_acceleration,
                               "largest acceleration"),
      plugin::computed_parameter(axis + ".min_acceleration", plugin::ParameterType::kDouble,
                                 "largest deceleration, negative (default: -max_acceleration)"),
  };
}

}  // namespace

void register_kernels(plugin::Registrar& registrar) {
  const JointTrajectoryControllerConfig jtc;
  registrar.add_kernel(
      {.name = "control/joint_trajectory_controller",
       .description = "controller manager loop with a joint trajectory controller (splines, "
                      "tolerances) on simulated hardware, as ros2_control + ros2_controllers",
       .inputs = {{"joint_trajectory", "trajectory_msgs/msg/JointTrajectory"}},
       .outputs = {{"controller_state", "control_msgs/msg/JointTrajectoryControllerState"}},
       .parameters = with(
           loop_parameters("rrbot"),
           {plugin::double_parameter("path_tolerance", 0.0,
                                     "largest position error along the path, "
                                     "rad, every joint (0: not checked)"),
            plugin::double_parameter("goal_tolerance", 0.0,
                                     "largest position error at the goal, rad, "
                                     "every joint (0: not checked)"),
            plugin::double_parameter("goal_time", jtc.goal_time_s,
                                     "abort a goal not reached this long after "
                                     "its last point, s (0: no limit)"),
            plugin::double_parameter("stopped_velocity_tolerance", jtc.stopped_velocity_tolerance,
                                     "velocity below which a joint has stopped, "
                                     "rad/s")}),
       .control_loop = control_loop()},
      [](graph::Context& context, const KernelConfig& config) {
        return std::make_shared<JointTrajectoryControllerNode>(context, config);
      });
  const DiffDriveControllerConfig dd;
  registrar.add_kernel(
      {.name = "control/diff_drive_controller",
       .description = "controller manager loop with a differential drive controller (limiter, "
                      "timeout, RK2 odometry) on a simulated DiffBot, as ros2_control + "
                      "ros2_controllers",
       // TwistStamped, or Twist with use_stamped_vel: false.
       .inputs = {{"cmd_vel", ""}},
       .outputs = {{"odom", "nav_msgs/msg/Odometry"},
                   {"tf", "tf2_msgs/msg/TFMessage"},
                   {"ground_truth", "nav_msgs/msg/Odometry"}},
       .parameters =
           with(with(loop_parameters("diffbot"),
                     {plugin::double_parameter("wheel_separation", dd.wheel_separation,
                                               "distance between the wheels, m (the "
                                               "controller's and the robot's)"),
                      plugin::double_parameter("wheel_radius", dd.wheel_radius, "wheel radius, m"),
                      plugin::bool_parameter("open_loop", dd.open_loop,
                                             "odometry from the commands (true) or "
                                             "the wheel positions (false)"),
                      plugin::double_parameter("cmd_vel_timeout", dd.cmd_vel_timeout_s,
                                               "stop when no command came for this "
                                               "long, s"),
                      plugin::double_parameter("publish_rate", dd.publish_rate_hz,
                                               "odometry and TF rate, Hz"),
                      plugin::bool_parameter("use_stamped_vel", true,
                                             "cmd_vel is geometry_msgs/TwistStamped "
                                             "(false: Twist, without an ID)")}),
                with(speed_limit_parameters("linear.x"), speed_limit_parameters("angular.z"))),
       .control_loop = control_loop()},
      [](graph::Context& context, const KernelConfig& config) {
        return std::make_shared<DiffDriveControllerNode>(context, config);
      });
  registrar.add_kernel(
      {.name = "control/forward_command_controller",
       .description = "controller manager loop with a forward command controller (position, "
                      "velocity or acceleration) and a joint state broadcaster on simulated "
                      "hardware",
       .inputs = {{"commands", "std_msgs/msg/Float64MultiArray"}},
       .outputs = {{"joint_states", "sensor_msgs/msg/JointState"}},
       .parameters = with(loop_parameters("rrbot_multi_interface"),
                          {plugin::string_parameter("interface_name",
                                                    ForwardCommandControllerConfig{}.interface_name,
                                                    "command interface: position, velocity or "
                                                    "acceleration")}),
       .control_loop = control_loop()},
      [](graph::Context& context, const KernelConfig& config) {
        return std::make_shared<ForwardCommandControllerNode>(context, config);
      });
}

}  // namespace robotperf::control
