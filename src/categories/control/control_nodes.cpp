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

int64_t stamp_ns(const msgs::Header& h) {
  return int64_t{h.stamp.sec} * 1'000'000'000 + h.stamp.nanosec;
}

// The controller manager's loop and simulated hardware, shared by every control kernel.
struct LoopSettings {
  double update_rate = 0;
  int cpu = 0;
  int rt_priority = 0;
  int64_t cycle_capacity = 0;  // as given: checked below before it becomes a size
  std::string hardware;
  double position_time_constant = 0;
};

// Their parameters; the default hardware is the kernel's.
plugin::ParameterStruct<LoopSettings> loop_parameters(const std::string& default_hardware) {
  const LoopConfig loop;
  const HardwareConfig hardware;
  return plugin::ParameterStruct<LoopSettings>{
      plugin::field(&LoopSettings::update_rate, "update_rate", loop.update_rate_hz,
                    "the controller manager's loop rate, Hz (run --update-rate)"),
      plugin::field(&LoopSettings::cpu, "cpu", loop.cpu,
                    "pin the loop thread to this CPU; -1: not pinned"),
      plugin::field(&LoopSettings::rt_priority, "rt_priority", loop.rt_priority,
                    "SCHED_FIFO priority of the loop, 1-99; 0: the normal scheduler"),
      plugin::field(&LoopSettings::cycle_capacity, "cycle_capacity",
                    static_cast<int64_t>(loop.cycle_capacity),
                    "cycles whose timestamps are kept (later ones are only counted)"),
      plugin::field(&LoopSettings::hardware, "hardware", default_hardware,
                    "simulated hardware: rrbot, rrbot_multi_interface or diffbot"),
      plugin::field(&LoopSettings::position_time_constant, "position_time_constant",
                    hardware.position_time_constant_s,
                    "rrbot: first-order lag of the joints behind a position command, s (0: "
                    "reached within the cycle)")};
}

control::LoopConfig loop_config(const KernelConfig& config, const LoopSettings& s) {
  control::LoopConfig c;
  c.name = config.node_name;
  c.update_rate_hz = s.update_rate;
  c.cpu = s.cpu;
  c.rt_priority = s.rt_priority;
  if (s.cycle_capacity < 1)
    throw std::invalid_argument("node '" + config.node_name + "': cycle_capacity must be >= 1");
  c.cycle_capacity = static_cast<std::size_t>(s.cycle_capacity);
  return c;
}

// The hardware of `settings`, read with `parameters` (whose `loop` member is a LoopSettings).
template <class S>
control::HardwareConfig hardware_config(const KernelConfig& config,
                                        const plugin::ParameterStruct<S>& parameters,
                                        const S& settings) {
  control::HardwareConfig h;
  h.type = settings.loop.hardware;
  if (h.type == "rrbot") {
    h.position_time_constant_s = settings.loop.position_time_constant;
  } else if (parameters.given(config.parameters, settings, settings.loop.position_time_constant)) {
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
  ControlNode(graph::Context& context, const KernelConfig& config, const LoopSettings& loop,
              const control::HardwareConfig& hardware)
      : Node(context, config.node_name),
        manager_(std::make_unique<control::ControllerManager>(control::make_hardware(hardware),
                                                              loop_config(config, loop))) {}

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

struct JointTrajectorySettings {
  LoopSettings loop;
  double path_tolerance = 0;
  double goal_tolerance = 0;
  double goal_time = 0;
  double stopped_velocity_tolerance = 0;
};

const JointTrajectoryControllerConfig kJointTrajectory;
const plugin::ParameterStruct<JointTrajectorySettings> kJointTrajectoryParameters{
    plugin::nested(&JointTrajectorySettings::loop, loop_parameters("rrbot")),
    plugin::field(&JointTrajectorySettings::path_tolerance, "path_tolerance", 0,
                  "largest position error along the path, rad, every joint (0: not checked)"),
    plugin::field(&JointTrajectorySettings::goal_tolerance, "goal_tolerance", 0,
                  "largest position error at the goal, rad, every joint (0: not checked)"),
    plugin::field(&JointTrajectorySettings::goal_time, "goal_time", kJointTrajectory.goal_time_s,
                  "abort a goal not reached this long after its last point, s (0: no limit)"),
    plugin::field(&JointTrajectorySettings::stopped_velocity_tolerance,
                  "stopped_velocity_tolerance", kJointTrajectory.stopped_velocity_tolerance,
                  "velocity below which a joint has stopped, rad/s")};

class JointTrajectoryControllerNode final : public ControlNode {
 public:
  JointTrajectoryControllerNode(graph::Context& context, const KernelConfig& config)
      : JointTrajectoryControllerNode(context, config,
                                      kJointTrajectoryParameters.read(config.parameters)) {}

 private:
  JointTrajectoryControllerNode(graph::Context& context, const KernelConfig& config,
                                const JointTrajectorySettings& s)
      : ControlNode(context, config, s.loop,
                    hardware_config(config, kJointTrajectoryParameters, s)) {
    control::JointTrajectoryControllerConfig c;
    const std::size_t n = c.joints.size();
    c.path_tolerance.assign(n, s.path_tolerance);
    c.goal_tolerance.assign(n, s.goal_tolerance);
    c.goal_time_s = s.goal_time;
    c.stopped_velocity_tolerance = s.stopped_velocity_tolerance;
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

 public:
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

// One axis' limits; a minimum not given is the maximum's negative.
struct SpeedLimitSettings {
  bool has_velocity_limits = false;
  double max_velocity = 0;
  std::optional<double> min_velocity;
  bool has_acceleration_limits = false;
  double max_acceleration = 0;
  std::optional<double> min_acceleration;

  control::SpeedLimits limits() const {
    return {.has_velocity_limits = has_velocity_limits,
            .min_velocity = min_velocity.value_or(-max_velocity),
            .max_velocity = max_velocity,
            .has_acceleration_limits = has_acceleration_limits,
            .min_acceleration = min_acceleration.value_or(-max_acceleration),
            .max_acceleration = max_acceleration};
  }
};

// Named "<axis>.max_velocity" and so on.
plugin::ParameterStruct<SpeedLimitSettings> speed_limit_parameters(const std::string& axis) {
  const SpeedLimits l;
  using S = SpeedLimitSettings;
  return plugin::ParameterStruct<S>{
      plugin::field(&S::has_velocity_limits, axis + ".has_velocity_limits", l.has_velocity_limits,
                    "limit the " + axis + " velocity"),
      plugin::field(&S::max_velocity, axis + ".max_velocity", l.max_velocity, "largest velocity"),
      plugin::field(&S::min_velocity, axis + ".min_velocity",
                    "smallest velocity (default: -max_velocity)"),
      plugin::field(&S::has_acceleration_limits, axis + ".has_acceleration_limits",
                    l.has_acceleration_limits, "limit the " + axis + " acceleration"),
      plugin::field(&S::max_acceleration, axis + ".max_acceleration", l.max_acceleration,
                    "largest acceleration"),
      plugin::field(&S::min_acceleration, axis + ".min_acceleration",
                    "largest deceleration, negative (default: -max_acceleration)")};
}

struct DiffDriveSettings {
  LoopSettings loop;
  double wheel_separation = 0;
  double wheel_radius = 0;
  bool open_loop = false;
  double cmd_vel_timeout = 0;
  double publish_rate = 0;
  bool use_stamped_vel = false;
  SpeedLimitSettings linear, angular;
};

const DiffDriveControllerConfig kDiffDrive;
const plugin::ParameterStruct<DiffDriveSettings> kDiffDriveParameters{
    plugin::nested(&DiffDriveSettings::loop, loop_parameters("diffbot")),
    plugin::field(&DiffDriveSettings::wheel_separation, "wheel_separation",
                  kDiffDrive.wheel_separation,
                  "distance between the wheels, m (the controller's and the robot's)"),
    plugin::field(&DiffDriveSettings::wheel_radius, "wheel_radius", kDiffDrive.wheel_radius,
                  "wheel radius, m"),
    plugin::field(&DiffDriveSettings::open_loop, "open_loop", kDiffDrive.open_loop,
                  "odometry from the commands (true) or the wheel positions (false)"),
    plugin::field(&DiffDriveSettings::cmd_vel_timeout, "cmd_vel_timeout",
                  kDiffDrive.cmd_vel_timeout_s, "stop when no command came for this long, s"),
    plugin::field(&DiffDriveSettings::publish_rate, "publish_rate", kDiffDrive.publish_rate_hz,
                  "odometry and TF rate, Hz"),
    plugin::field(&DiffDriveSettings::use_stamped_vel, "use_stamped_vel", true,
                  "cmd_vel is geometry_msgs/TwistStamped (false: Twist, without an ID)"),
    plugin::nested(&DiffDriveSettings::linear, speed_limit_parameters("linear.x")),
    plugin::nested(&DiffDriveSettings::angular, speed_limit_parameters("angular.z"))};

class DiffDriveControllerNode final : public ControlNode {
 public:
  DiffDriveControllerNode(graph::Context& context, const KernelConfig& config)
      : DiffDriveControllerNode(context, config, kDiffDriveParameters.read(config.parameters)) {}

  // The loop calls back into truth_: stop it before the members go.
  ~DiffDriveControllerNode() override { manager().stop(); }

  std::map<std::string, uint64_t> counters() const override {
    return {{"cmd_vel_timeouts", controller_->timeouts()}};
  }

 private:
  DiffDriveControllerNode(graph::Context& context, const KernelConfig& config,
                          const DiffDriveSettings& s)
      : ControlNode(context, config, s.loop, diffbot_config(config, s)) {
    control::DiffDriveControllerConfig c;
    c.wheel_separation = s.wheel_separation;
    c.wheel_radius = s.wheel_radius;
    c.open_loop = s.open_loop;
    c.cmd_vel_timeout_s = s.cmd_vel_timeout;
    c.publish_rate_hz = s.publish_rate;
    c.linear = s.linear.limits();
    c.angular = s.angular.limits();
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
    if (s.use_stamped_vel) {
      subscription_ = create_subscription<msgs::TwistStamped>(
          config.topic("cmd_vel"), config.qos, [this](std::shared_ptr<const msgs::TwistStamped> m) {
            controller_->command(
                {stamp_ns(m->header), m->twist.linear.x, m->twist.angular.z, rmw::steady_now_ns()});
          });
    } else {
      // geometry_msgs/Twist has no header: the command is identified by its arrival time,
      // which no Playback ID matches (see docs/benchmarks/control.md).
      subscription_ = create_subscription<msgs::Twist>(
          config.topic("cmd_vel"), config.qos, [this](std::shared_ptr<const msgs::Twist> m) {
            const int64_t now = rmw::steady_now_ns();
            controller_->command({now, m->linear.x, m->angular.z, now});
          });
    }
    start();
  }

  static control::HardwareConfig diffbot_config(const KernelConfig& config,
                                                const DiffDriveSettings& s) {
    control::HardwareConfig h = hardware_config(config, kDiffDriveParameters, s);
    // The simulated robot has the geometry the controller is configured with.
    h.wheel_separation_m = s.wheel_separation;
    h.wheel_radius_m = s.wheel_radius;
    return h;
  }

  std::shared_ptr<control::DiffDriveController> controller_;
  std::unique_ptr<control::RealtimePublisher<msgs::Odometry>> truth_;
  control::BasePose pose_at_read_;  // the loop thread's alone
  std::shared_ptr<graph::GenericSubscription> subscription_;
};

struct ForwardCommandSettings {
  LoopSettings loop;
  std::string interface_name;
};

const plugin::ParameterStruct<ForwardCommandSettings> kForwardCommandParameters{
    plugin::nested(&ForwardCommandSettings::loop, loop_parameters("rrbot_multi_interface")),
    plugin::field(&ForwardCommandSettings::interface_name, "interface_name",
                  ForwardCommandControllerConfig{}.interface_name,
                  "command interface: position, velocity or acceleration")};

class ForwardCommandControllerNode final : public ControlNode {
 public:
  ForwardCommandControllerNode(graph::Context& context, const KernelConfig& config)
      : ForwardCommandControllerNode(context, config,
                                     kForwardCommandParameters.read(config.parameters)) {}

 private:
  ForwardCommandControllerNode(graph::Context& context, const KernelConfig& config,
                               const ForwardCommandSettings& s)
      : ControlNode(context, config, s.loop,
                    hardware_config(config, kForwardCommandParameters, s)) {
    control::ForwardCommandControllerConfig c;
    c.interface_name = s.interface_name;
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

 public:
  std::map<std::string, uint64_t> counters() const override {
    return {{"rejected_commands", controller_->rejected()}};
  }

 private:
  std::shared_ptr<control::ForwardCommandController> controller_;
  std::shared_ptr<graph::GenericSubscription> subscription_;
};

// The loop's rate parameter; a begin and an end event per controller update, two controllers at
// most per controller manager.
plugin::ControlLoopInfo control_loop() {
  return {"update_rate", 4.0};
}

}  // namespace

void register_kernels(plugin::Registrar& registrar) {
  registrar.add_kernel(
      {.name = "control/joint_trajectory_controller",
       .description = "controller manager loop with a joint trajectory controller (splines, "
                      "tolerances) on simulated hardware, as ros2_control + ros2_controllers",
       .inputs = {{"joint_trajectory", "trajectory_msgs/msg/JointTrajectory"}},
       .outputs = {{"controller_state", "control_msgs/msg/JointTrajectoryControllerState"}},
       .parameters = kJointTrajectoryParameters.declarations(),
       .control_loop = control_loop()},
      [](graph::Context& context, const KernelConfig& config) {
        return std::make_shared<JointTrajectoryControllerNode>(context, config);
      });
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
       .parameters = kDiffDriveParameters.declarations(),
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
       .parameters = kForwardCommandParameters.declarations(),
       .control_loop = control_loop()},
      [](graph::Context& context, const KernelConfig& config) {
        return std::make_shared<ForwardCommandControllerNode>(context, config);
      });
}

}  // namespace robotperf::control
