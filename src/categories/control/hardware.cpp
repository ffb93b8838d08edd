#include "robotperf/control/hardware.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace robotperf::control {
namespace {

constexpr double kUnset = std::numeric_limits<double>::quiet_NaN();

std::string names_of(const std::map<std::string, double>& m) {
  std::string out;
  for (const auto& [name, value] : m) out += (out.empty() ? "" : ", ") + name;
  return out;
}

// ros2_control_demos example 1: two revolute joints commanded by position.
class RRBot final : public SimulatedHardware {
 public:
  explicit RRBot(double time_constant_s)
      : SimulatedHardware("rrbot", {"joint1", "joint2"}), time_constant_s_(time_constant_s) {
    for (const auto& j : joints()) {
      add_command(j, "position");
      add_state(j, "position");
      add_state(j, "velocity");
    }
    position_.assign(joints().size(), 0.0);
    velocity_.assign(joints().size(), 0.0);
  }

  void read() override {
    for (std::size_t i = 0; i < joints().size(); ++i) {
      state(joints()[i], "position") = position_[i];
      state(joints()[i], "velocity") = velocity_[i];
    }
  }

  void write(double period_s) override {
    const double follow = time_constant_s_ > 0 ? 1.0 - std::exp(-period_s / time_constant_s_) : 1.0;
    for (std::size_t i = 0; i < joints().size(); ++i) {
      const double target = command(joints()[i], "position");
      const double before = position_[i];
      if (!std::isnan(target)) position_[i] += (target - position_[i]) * follow;
      velocity_[i] = period_s > 0 ? (position_[i] - before) / period_s : 0.0;
    }
  }

 private:
  double time_constant_s_;
  std::vector<double> position_, velocity_;
};

// ros2_control_demos example 3: each joint takes a position, velocity or acceleration command.
class RRBotMultiInterface final : public SimulatedHardware {
 public:
  RRBotMultiInterface() : SimulatedHardware("rrbot_multi_interface", {"joint1", "joint2"}) {
    for (const auto& j : joints()) {
      for (const char* kind : {"position", "velocity", "acceleration"}) {
        add_command(j, kind);
        add_state(j, kind);
      }
    }
    mode_.assign(joints().size(), Mode::kNone);
    position_.assign(joints().size(), 0.0);
    velocity_.assign(joints().size(), 0.0);
    acceleration_.assign(joints().size(), 0.0);
  }

  void claim(const std::vector<std::string>& interfaces) override {
    std::vector<Mode> modes = mode_;
    for (const auto& name : interfaces) {
      for (std::size_t i = 0; i < joints().size(); ++i) {
        const std::string& j = joints()[i];
        if (name.rfind(j + "/", 0) != 0) continue;
        const std::string kind = name.substr(j.size() + 1);
        const Mode m = kind == "position"   ? Mode::kPosition
                       : kind == "velocity" ? Mode::kVelocity
                                            : Mode::kAcceleration;
        if (modes[i] != Mode::kNone && modes[i] != m) {
          throw std::invalid_argument("rrbot_multi_interface: joint " + j +
                                      " already takes another command kind than " + kind);
        }
        modes[i] = m;
      }
    }
    SimulatedHardware::claim(interfaces);
    mode_ = modes;
  }

  void read() override {
    for (std::size_t i = 0; i < joints().size(); ++i) {
      state(joints()[i], "position") = position_[i];
      state(joints()[i], "velocity") = velocity_[i];
      state(joints()[i], "acceleration") = acceleration_[i];
    }
  }

  void write(double dt) override {
    for (std::size_t i = 0; i < joints().size(); ++i) {
      const std::string& j = joints()[i];
      const double v0 = velocity_[i];
      switch (mode_[i]) {
        case Mode::kPosition:
          if (const double p = command(j, "position"); !std::isnan(p)) {
            velocity_[i] = dt > 0 ? (p - position_[i]) / dt : 0.0;
            position_[i] = p;
          } else {
            velocity_[i] = 0;
          }
          break;
        case Mode::kVelocity:
          if (const double v = command(j, "velocity"); !std::isnan(v)) velocity_[i] = v;
          position_[i] += velocity_[i] * dt;
          break;
        case Mode::kAcceleration:
          // Semi-implicit Euler: the new velocity moves the joint during this period.
          if (const double a = command(j, "acceleration"); !std::isnan(a)) velocity_[i] += a * dt;
          position_[i] += velocity_[i] * dt;
          break;
        case Mode::kNone:
          velocity_[i] = 0;
          break;
      }
      acceleration_[i] = dt > 0 ? (velocity_[i] - v0) / dt : 0.0;
    }
  }

 private:
  enum class Mode { kNone, kPosition, kVelocity, kAcceleration };
  std::vector<Mode> mode_;
  std::vector<double> position_, velocity_, acceleration_;
};

// ros2_control_demos example 2: a differential drive base with two velocity-commanded wheels.
class DiffBot final : public SimulatedHardware {
 public:
  DiffBot(double separation, double radius)
      : SimulatedHardware("diffbot", {"left_wheel_joint", "right_wheel_joint"}),
        separation_(separation),
        radius_(radius) {
    for (const auto& j : joints()) {
      add_command(j, "velocity");
      add_state(j, "position");
      add_state(j, "velocity");
    }
  }

  void read() override {
    state("left_wheel_joint", "position") = wheel_position_[0];
    state("right_wheel_joint", "position") = wheel_position_[1];
    state("left_wheel_joint", "velocity") = wheel_velocity_[0];
    state("right_wheel_joint", "velocity") = wheel_velocity_[1];
  }

  void write(double dt) override {
    const double l = command("left_wheel_joint", "velocity");
    const double r = command("right_wheel_joint", "velocity");
    wheel_velocity_[0] = std::isnan(l) ? 0.0 : l;
    wheel_velocity_[1] = std::isnan(r) ? 0.0 : r;
    for (int i = 0; i < 2; ++i) wheel_position_[i] += wheel_velocity_[i] * dt;
    // The base moves on an exact arc while the wheel speeds are constant.
    const double v = radius_ * (wheel_velocity_[0] + wheel_velocity_[1]) / 2.0;
    const double w = radius_ * (wheel_velocity_[1] - wheel_velocity_[0]) / separation_;
    if (std::abs(w) < 1e-12) {
      pose_.x += v * dt * std::cos(pose_.yaw);
      pose_.y += v * dt * std::sin(pose_.yaw);
    } else {
      const double yaw1 = pose_.yaw + w * dt;
      pose_.x += v / w * (std::sin(yaw1) - std::sin(pose_.yaw));
      pose_.y -= v / w * (std::cos(yaw1) - std::cos(pose_.yaw));
    }
    pose_.yaw += w * dt;
    pose_.linear = v;
    pose_.angular = w;
  }

  const BasePose* base_pose() const override { return &pose_; }

 private:
  double separation_, radius_;
  double wheel_position_[2] = {0, 0};
  double wheel_velocity_[2] = {0, 0};
  BasePose pose_;
};

}  // namespace

SimulatedHardware::SimulatedHardware(std::string type, std::vector<std::string> joints)
    : type_(std::move(type)), joints_(std::move(joints)) {}

void SimulatedHardware::add_command(const std::string& joint, const std::string& kind) {
  commands_[joint + "/" + kind] = kUnset;
}

void SimulatedHardware::add_state(const std::string& joint, const std::string& kind) {
  states_[joint + "/" + kind] = 0.0;
}

double& SimulatedHardware::command(const std::string& joint, const std::string& kind) {
  return commands_.find(joint + "/" + kind)->second;
}

double& SimulatedHardware::state(const std::string& joint, const std::string& kind) {
  return states_.find(joint + "/" + kind)->second;
}

std::vector<std::string> SimulatedHardware::command_interface_names() const {
  std::vector<std::string> out;
  for (const auto& [name, v] : commands_) out.push_back(name);
  return out;
}

std::vector<std::string> SimulatedHardware::state_interface_names() const {
  std::vector<std::string> out;
  for (const auto& [name, v] : states_) out.push_back(name);
  return out;
}

double* SimulatedHardware::command_interface(const std::string& name) {
  auto it = commands_.find(name);
  if (it == commands_.end()) {
    throw std::invalid_argument(type_ + " has no command interface '" + name + "' (it has " +
                                names_of(commands_) + ")");
  }
  return &it->second;
}

const double* SimulatedHardware::state_interface(const std::string& name) const {
  auto it = states_.find(name);
  if (it == states_.end()) {
    throw std::invalid_argument(type_ + " has no state interface '" + name + "' (it has " +
                                names_of(states_) + ")");
  }
  return &it->second;
}

bool SimulatedHardware::claimed(const std::string& name) const {
  auto it = claimed_.find(name);
  return it != claimed_.end() && it->second;
}

void SimulatedHardware::claim(const std::vector<std::string>& interfaces) {
  for (const auto& name : interfaces) {
    command_interface(name);  // throws for an unknown name
    if (claimed(name))
      throw std::invalid_argument(type_ + ": command interface " + name + " is already claimed");
  }
  for (const auto& name : interfaces) claimed_[name] = true;
}

std::unique_ptr<SimulatedHardware> make_hardware(const HardwareConfig& config) {
  if (config.type == "rrbot") {
    if (!(config.position_time_constant_s >= 0))
      throw std::invalid_argument("rrbot: position_time_constant must be >= 0");
    return std::make_unique<RRBot>(config.position_time_constant_s);
  }
  if (config.type == "rrbot_multi_interface") return std::make_unique<RRBotMultiInterface>();
  if (config.type == "diffbot") {
    if (!(config.wheel_separation_m > 0) || !(config.wheel_radius_m > 0))
      throw std::invalid_argument("diffbot: wheel_separation and wheel_radius must be positive");
    return std::make_unique<DiffBot>(config.wheel_separation_m, config.wheel_radius_m);
  }
  throw std::invalid_argument("unknown hardware '" + config.type +
                              "' (known: rrbot, rrbot_multi_interface, diffbot)");
}

}  // namespace robotperf::control
