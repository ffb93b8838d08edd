// Simulated robot hardware with ros2_control-style command and state interfaces.
//
// Interfaces are named "<joint>/<kind>" ("joint1/position", "left_wheel_joint/velocity") and are
// plain doubles owned by the hardware; controllers resolve pointers to them once, when they are
// activated, and read and write them in the loop without lookups. Each cycle the controller
// manager calls read() (simulated sensors -> state interfaces), the controllers' update(), then
// write(period) (command interfaces -> the simulated robot, which then integrates its state over
// one period, so the next read() shows the command's effect).
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

namespace robotperf::control {

struct HardwareConfig {
  // "rrbot" (2 revolute joints, position commands), "rrbot_multi_interface" (position, velocity
  // or acceleration commands per joint), "diffbot" (two wheels, velocity commands).
  std::string type = "rrbot";
  // rrbot: the joints follow a position command as a first-order lag with this time constant
  // (0: they reach it within the cycle), as the ros2_control demo's "slowdown".
  double position_time_constant_s = 0.05;
  // diffbot: the geometry of the simulated robot (the ground truth the odometry is checked
  // against).
  double wheel_separation_m = 0.10;
  double wheel_radius_m = 0.015;
};

// The true pose of a simulated mobile base, integrated exactly from its wheels.
struct BasePose {
  double x = 0, y = 0, yaw = 0;
  double linear = 0, angular = 0;  // body velocities
};

class SimulatedHardware {
 public:
  virtual ~SimulatedHardware() = default;
  SimulatedHardware(const SimulatedHardware&) = delete;
  SimulatedHardware& operator=(const SimulatedHardware&) = delete;

  const std::string& type() const { return type_; }
  const std::vector<std::string>& joints() const { return joints_; }
  std::vector<std::string> command_interface_names() const;
  std::vector<std::string> state_interface_names() const;

  // Throws std::invalid_argument naming the interfaces there are.
  double* command_interface(const std::string& name);
  const double* state_interface(const std::string& name) const;

  // Gives the named command interfaces to one controller (ros2_control's command mode switch):
  // an interface is claimed at most once, and the multi-interface RRBot accepts one command kind
  // per joint. Throws std::invalid_argument otherwise.
  virtual void claim(const std::vector<std::string>& command_interfaces);

  virtual void read() = 0;
  virtual void write(double period_s) = 0;

  // Ground truth of a mobile base (diffbot); null for arms.
  virtual const BasePose* base_pose() const { return nullptr; }

 protected:
  SimulatedHardware(std::string type, std::vector<std::string> joints);
  double& command(const std::string& joint, const std::string& kind);
  double& state(const std::string& joint, const std::string& kind);
  void add_command(const std::string& joint, const std::string& kind);
  void add_state(const std::string& joint, const std::string& kind);
  bool claimed(const std::string& name) const;

 private:
  std::string type_;
  std::vector<std::string> joints_;
  // std::map: element addresses stay valid, so controllers may keep pointers.
  std::map<std::string, double> commands_;
  std::map<std::string, double> states_;
  std::map<std::string, bool> claimed_;
};

// Throws std::invalid_argument for an unknown type or bad parameters.
std::unique_ptr<SimulatedHardware> make_hardware(const HardwareConfig& config);

}  // namespace robotperf::control
