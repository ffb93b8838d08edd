// The controller manager of ros2_control: a periodic loop on a thread of its own that reads the
// hardware, updates every active controller and writes the hardware, at absolute deadlines
// (clock_nanosleep TIMER_ABSTIME on CLOCK_MONOTONIC), optionally pinned to a CPU and at a
// SCHED_FIFO priority, recording the timestamps of every cycle into a buffer allocated before
// the loop starts.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "robotperf/control/controller.hpp"
#include "robotperf/control/hardware.hpp"
#include "robotperf/plugin/control_loop.hpp"

namespace robotperf::control {

struct LoopConfig {
  std::string name = "controller_manager";  // for traces and messages
  double update_rate_hz = 100.0;
  int cpu = -1;         // pin the loop thread to this CPU; -1: not pinned
  int rt_priority = 0;  // SCHED_FIFO priority 1-99; 0: the normal scheduler
  // Cycles whose timestamps are kept (beyond it cycles are counted, not recorded).
  std::size_t cycle_capacity = 360'000;
};

// What the loop records, as the plug-in API's control-loop reporting defines it.
using plugin::CommandWrite;
using plugin::CycleRecord;
using plugin::LoopReport;

class ControllerManager {
 public:
  ControllerManager(std::unique_ptr<SimulatedHardware> hardware, LoopConfig config);
  ~ControllerManager();
  ControllerManager(const ControllerManager&) = delete;
  ControllerManager& operator=(const ControllerManager&) = delete;

  // Claims the controller's command interfaces and activates it. Before start().
  void add_controller(std::shared_ptr<Controller> controller);
  // Called in the loop after each cycle's write (e.g. to publish ground truth), on its thread.
  void set_after_write(std::function<void(const UpdateContext&)> callback);

  // Starts the loop thread and returns once it runs with its CPU and priority; throws
  // std::runtime_error with one line saying what the OS refused and what to do.
  void start();
  void stop();
  bool running() const { return thread_.joinable(); }

  // One cycle at time `now_ns` (the loop calls this; tests call it to step simulated time).
  void cycle(int64_t now_ns);

  // After stop(): what the loop recorded.
  LoopReport report() const;
  SimulatedHardware& hardware() { return *hardware_; }
  const LoopConfig& config() const { return config_; }

 private:
  void loop(int64_t start_ns);
  // Returns when the hardware write ended.
  int64_t run_cycle(int64_t deadline_ns, int64_t now_ns);

  std::unique_ptr<SimulatedHardware> hardware_;
  LoopConfig config_;
  int64_t period_ns_;
  std::vector<std::shared_ptr<Controller>> controllers_;
  std::function<void(const UpdateContext&)> after_write_;
  std::vector<CycleRecord> records_;
  std::vector<CommandWrite> writes_;
  std::size_t record_count_ = 0, write_count_ = 0;
  uint64_t cycles_ = 0, misses_ = 0, writes_dropped_ = 0;
  int64_t previous_now_ns_ = -1;
  int64_t actuated_command_ = kNoCommand;  // newest command written to the hardware
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace robotperf::control
