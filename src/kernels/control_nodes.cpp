// Control kernels: a controller manager loop (src/control) with one controller on simulated
// hardware, as a graph node. Commands arrive on a subscription (the executor's thread) and reach
// the loop through a real-time buffer; states leave through real-time publishers, stamped with the
// ID of the newest command they reflect.
#include <stdexcept>

#include "builtin_kernels.hpp"
#include "robotperf/control/diff_drive_controller.hpp"
#include "robotperf/control/forward_command_controller.hpp"
#include "robotperf/control/joint_trajectory_controller.hpp"
#include "robotperf/msgs/geometry_msgs.hpp"

namespace robotperf::kernels {
namespace {

int64_t stamp_ns(const msgs::Header& h) {
  return int64_t{h.stamp.sec} * 1'000'000'000 + h.stamp.nanosec;
}

// The loop's parameters, shared by every control kernel.
control::LoopConfig loop_config(const KernelConfig& config) {
  const auto& p = config.parameters;
  control::LoopConfig c;
  c.name = config.node_name;
  c.update_rate_hz = p.get_double("update_rate", 100.0);
  c.cpu = static_cast<int>(p.get_int("cpu", -1));
  c.rt_priority = static_cast<int>(p.get_int("rt_priority", 0));
  const int64_t capacity = p.get_int("cycle_capacity", 360'000);
  if (capacity < 1)
    throw std::invalid_argument("node '" + config.node_name + "': cycle_capacity must be >= 1");
  c.cycle_capacity = static_cast<std::size_t>(capacity);
  return c;
}

control::HardwareConfig hardware_config(const KernelConfig& config, const std::string& fallback) {
  const auto& p = config.parameters;
  control::HardwareConfig h;
  h.type = p.get_string("hardware", fallback);
  if (h.type == "rrbot")
    h.position_time_constant_s = p.get_double("position_time_constant", h.position_time_constant_s);
  return h;
}

// A graph node owning a controller manager. Subclasses add their controllers, then call start().
class ControlNode : public graph::Node, public NodeCounters, public ControlLoopSource {
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
      : ControlNode(context, config, hardware_config(config, "rrbot")) {
    const auto& p = config.parameters;
    control::JointTrajectoryControllerConfig c;
    const std::size_t n = c.joints.size();
    c.path_tolerance.assign(n, p.get_double("path_tolerance", 0.0));
    c.goal_tolerance.assign(n, p.get_double("goal_tolerance", 0.0));
    c.goal_time_s = p.get_double("goal_time", 0.0);
    c.stopped_velocity_tolerance = p.get_double("stopped_velocity_tolerance", 0.01);
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
  l.has_velocity_limits = p.get_bool(axis + ".has_velocity_limits", false);
  l.max_velocity = p.get_double(axis + ".max_velocity", 0.0);
  l.min_velocity = p.get_double(axis + ".min_velocity", -l.max_velocity);
  l.has_acceleration_limits = p.get_bool(axis + ".has_acceleration_limits", false);
  l.max_acceleration = p.get_double(axis + ".max_acceleration", 0.0);
  l.min_acceleration = p.get_double(axis + ".min_acceleration", -l.max_acceleration);
  return l;
}

class DiffDriveControllerNode final : public ControlNode {
 public:
  DiffDriveControllerNode(graph::Context& context, const KernelConfig& config)
      : ControlNode(context, config, diffbot_config(config)) {
    const auto& p = config.parameters;
    control::DiffDriveControllerConfig c;
    c.wheel_separation = p.get_double("wheel_separation", c.wheel_separation);
    c.wheel_radius = p.get_double("wheel_radius", c.wheel_radius);
    c.open_loop = p.get_bool("open_loop", true);
    c.cmd_vel_timeout_s = p.get_double("cmd_vel_timeout", c.cmd_vel_timeout_s);
    c.publish_rate_hz = p.get_double("publish_rate", c.publish_rate_hz);
    c.linear = speed_limits(p, "linear.x");
    c.angular = speed_limits(p, "angular.z");
    controller_ = std::make_shared<control::DiffDriveController>("diff_drive_controller", c);
    controller_->set_publishers(realtime_publisher<msgs::Odometry>(config, "odom"),
                                realtime_publisher<msgs::TFMessage>(config, "tf"));
    manager().add_controller(controller_);
    // Ground truth of the simulated base, after the hardware moved it, in the cycles the
    // odometry goes out and with the same ID (as Gazebo's p3d plugin would report it).
    if (auto truth = realtime_publisher<msgs::Odometry>(config, "ground_truth")) {
      truth->msg().header.frame_id = "odom";
      truth->msg().child_frame_id = "base_link";
      truth_ = std::move(truth);
      manager().set_after_write([this](const control::UpdateContext& ctx) {
        if (!controller_->published_last_update() || !truth_->try_lock()) return;
        const control::BasePose& pose = *manager().hardware().base_pose();
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
    if (p.get_bool("use_stamped_vel", true)) {
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
    control::HardwareConfig h = hardware_config(config, "diffbot");
    // The simulated robot has the geometry the controller is configured with.
    h.wheel_separation_m = config.parameters.get_double("wheel_separation", h.wheel_separation_m);
    h.wheel_radius_m = config.parameters.get_double("wheel_radius", h.wheel_radius_m);
    return h;
  }

  std::shared_ptr<control::DiffDriveController> controller_;
  std::unique_ptr<control::RealtimePublisher<msgs::Odometry>> truth_;
  std::shared_ptr<graph::GenericSubscription> subscription_;
};

class ForwardCommandControllerNode final : public ControlNode {
 public:
  ForwardCommandControllerNode(graph::Context& context, const KernelConfig& config)
      : ControlNode(context, config, hardware_config(config, "rrbot_multi_interface")) {
    control::ForwardCommandControllerConfig c;
    c.interface_name = config.parameters.get_string("interface_name", "position");
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

}  // namespace

std::shared_ptr<graph::Node> make_joint_trajectory_controller_node(graph::Context& context,
                                                                   const KernelConfig& config) {
  return std::make_shared<JointTrajectoryControllerNode>(context, config);
}

std::shared_ptr<graph::Node> make_diff_drive_controller_node(graph::Context& context,
                                                             const KernelConfig& config) {
  return std::make_shared<DiffDriveControllerNode>(context, config);
}

std::shared_ptr<graph::Node> make_forward_command_controller_node(graph::Context& context,
                                                                  const KernelConfig& config) {
  return std::make_shared<ForwardCommandControllerNode>(context, config);
}

}  // namespace robotperf::kernels
