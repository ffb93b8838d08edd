#include "robotperf/control/forward_command_controller.hpp"

#include <stdexcept>

namespace robotperf::control {

ForwardCommandController::ForwardCommandController(std::string name,
                                                   ForwardCommandControllerConfig config,
                                                   Logger log)
    : name_(std::move(name)), config_(std::move(config)), log_(std::move(log)) {
  if (config_.joints.empty()) throw std::invalid_argument(name_ + ": no joints");
  const auto& k = config_.interface_name;
  if (k != "position" && k != "velocity" && k != "acceleration") {
    throw std::invalid_argument(name_ +
                                ": interface_name must be position, velocity or "
                                "acceleration, not '" +
                                k + "'");
  }
}

void ForwardCommandController::command(std::shared_ptr<const msgs::Float64MultiArray> command) {
  buffer_.write(std::move(command));
}

std::vector<std::string> ForwardCommandController::command_interfaces() const {
  std::vector<std::string> out;
  for (const auto& j : config_.joints) out.push_back(j + "/" + config_.interface_name);
  return out;
}

void ForwardCommandController::activate(SimulatedHardware& hw) {
  for (const auto& name : command_interfaces()) commands_.push_back(hw.command_interface(name));
}

int64_t ForwardCommandController::update(const UpdateContext&) {
  int64_t taken = kNoCommand;
  if (buffer_.take(incoming_)) {
    if (incoming_->data.size() != commands_.size()) {
      ++rejected_;
      // The error path may allocate; a correct command stream never takes it.
      log_("command size (" + std::to_string(incoming_->data.size()) +
           ") does not match number of interfaces (" + std::to_string(commands_.size()) + ")");
    } else {
      current_.swap(incoming_);  // the replaced command is released outside the loop
      taken = msgs::MessageTraits<msgs::Float64MultiArray>::id_ns(*current_);
    }
  }
  if (current_) {
    for (std::size_t i = 0; i < commands_.size(); ++i) *commands_[i] = current_->data[i];
  }
  return taken;
}

JointStateBroadcaster::JointStateBroadcaster(
    std::string name, std::vector<std::string> joints,
    std::unique_ptr<RealtimePublisher<msgs::JointState>> publisher)
    : name_(std::move(name)), joints_(std::move(joints)), publisher_(std::move(publisher)) {}

std::vector<std::string> JointStateBroadcaster::state_interfaces() const {
  std::vector<std::string> out;
  for (const auto& j : joints_) {
    out.push_back(j + "/position");
    out.push_back(j + "/velocity");
  }
  return out;
}

void JointStateBroadcaster::activate(SimulatedHardware& hw) {
  for (const auto& j : joints_) {
    positions_.push_back(hw.state_interface(j + "/position"));
    velocities_.push_back(hw.state_interface(j + "/velocity"));
  }
  auto& m = publisher_->msg();
  m.name = joints_;
  m.position.assign(joints_.size(), 0.0);
  m.velocity.assign(joints_.size(), 0.0);
}

int64_t JointStateBroadcaster::update(const UpdateContext& ctx) {
  if (ctx.observed_command == kNoCommand || !publisher_->try_lock()) return kNoCommand;
  auto& m = publisher_->msg();
  m.header.stamp.sec = static_cast<int32_t>(ctx.observed_command / 1'000'000'000);
  m.header.stamp.nanosec = static_cast<uint32_t>(ctx.observed_command % 1'000'000'000);
  for (std::size_t i = 0; i < joints_.size(); ++i) {
    m.position[i] = *positions_[i];
    m.velocity[i] = *velocities_[i];
  }
  publisher_->unlock_and_publish();
  return kNoCommand;
}

}  // namespace robotperf::control
