// What a controller is to the controller manager (ros2_control's ControllerInterface, reduced to
// what the loop needs).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "robotperf/control/hardware.hpp"

namespace robotperf::control {

// A command's message ID (its header stamp in ns, docs/design.md §3.1); kNoCommand when none.
inline constexpr int64_t kNoCommand = -1;

struct UpdateContext {
  int64_t now_ns = 0;   // CLOCK_MONOTONIC at the start of the cycle
  double period_s = 0;  // since the previous cycle started (the nominal period on the first)
  uint64_t cycle = 0;
  // The newest command whose effect the state interfaces now show (written to the hardware in an
  // earlier cycle, then read back): the ID state messages published in this cycle carry.
  int64_t observed_command = kNoCommand;
};

// Where controllers report errors from the loop (e.g. a rejected command); default: stderr.
using Logger = std::function<void(std::string_view)>;
Logger stderr_logger(std::string prefix);

class Controller {
 public:
  virtual ~Controller() = default;
  virtual const std::string& name() const = 0;
  // Full interface names ("joint1/position") the controller writes and reads.
  virtual std::vector<std::string> command_interfaces() const = 0;
  virtual std::vector<std::string> state_interfaces() const = 0;
  // Resolves the interfaces (the hardware has already granted the command interfaces) and sizes
  // every buffer the loop uses. Not real-time.
  virtual void activate(SimulatedHardware& hardware) = 0;
  // One cycle: reads states, takes the newest command, writes commands, publishes state. Returns
  // the ID of a command it took and wrote for the first time in this cycle, else kNoCommand.
  virtual int64_t update(const UpdateContext& context) = 0;
};

}  // namespace robotperf::control
