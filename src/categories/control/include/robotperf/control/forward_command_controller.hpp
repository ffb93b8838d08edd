// The forward command controller of ros2_controllers (position, velocity or acceleration
// flavour): each std_msgs/Float64MultiArray command is copied to one command interface per
// joint; a command of the wrong size is rejected with a logged error and nothing is written.
// And the joint state broadcaster, which publishes the joints' states as sensor_msgs/JointState.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "robotperf/control/controller.hpp"
#include "robotperf/control/realtime.hpp"
#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/msgs/std_msgs.hpp"

namespace robotperf::control {

struct ForwardCommandControllerConfig {
  std::vector<std::string> joints{"joint1", "joint2"};
  std::string interface_name = "position";  // position, velocity or acceleration
};

class ForwardCommandController final : public Controller {
 public:
  ForwardCommandController(std::string name, ForwardCommandControllerConfig config,
                           Logger log = stderr_logger("forward_command_controller"));

  // From a subscription thread.
  void command(std::shared_ptr<const msgs::Float64MultiArray> command);

  const std::string& name() const override { return name_; }
  std::vector<std::string> command_interfaces() const override;
  std::vector<std::string> state_interfaces() const override { return {}; }
  void activate(SimulatedHardware& hardware) override;
  int64_t update(const UpdateContext& context) override;

  uint64_t rejected() const { return rejected_; }

 private:
  std::string name_;
  ForwardCommandControllerConfig config_;
  Logger log_;
  CommandBuffer<msgs::Float64MultiArray> buffer_;
  std::shared_ptr<const msgs::Float64MultiArray> incoming_, current_;
  std::vector<double*> commands_;
  uint64_t rejected_ = 0;
};

// Publishes position, velocity (and effort where the hardware has it) of every joint each cycle,
// stamped with the newest command the state reflects.
class JointStateBroadcaster final : public Controller {
 public:
  JointStateBroadcaster(std::string name, std::vector<std::string> joints,
                        std::unique_ptr<RealtimePublisher<msgs::JointState>> publisher);

  const std::string& name() const override { return name_; }
  std::vector<std::string> command_interfaces() const override { return {}; }
  std::vector<std::string> state_interfaces() const override;
  void activate(SimulatedHardware& hardware) override;
  int64_t update(const UpdateContext& context) override;

 private:
  std::string name_;
  std::vector<std::string> joints_;
  std::unique_ptr<RealtimePublisher<msgs::JointState>> publisher_;
  std::vector<const double*> positions_, velocities_;
};

}  // namespace robotperf::control
