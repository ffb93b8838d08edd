// Control-loop reporting: what a kernel that runs a periodic control loop (a controller manager)
// hands the harness after the run, so that robotperf can report loop timing, deadline misses
// and the time from each command's send to its first write to the hardware.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace robotperf::plugin {

// CLOCK_MONOTONIC nanoseconds of one cycle.
struct CycleRecord {
  int64_t deadline_ns;  // start + k * period
  int64_t wake_ns;      // when the loop woke for it
  int64_t read_end_ns;
  int64_t update_end_ns;  // all controllers updated
  int64_t write_end_ns;   // hardware written: the cycle's work is done
};

// A command (its message ID) written to the hardware for the first time.
struct CommandWrite {
  int64_t command_id;
  int64_t write_end_ns;
};

struct LoopReport {
  std::string name;
  double update_rate_hz = 0;
  int cpu = -1;
  int rt_priority = 0;
  uint64_t cycles = 0;  // run, recorded or not
  // Cycles whose write ended after the next period began, plus periods skipped because the loop
  // woke after their deadline had passed.
  uint64_t deadline_misses = 0;
  std::vector<CycleRecord> records;
  std::vector<CommandWrite> writes;
  uint64_t writes_dropped = 0;  // beyond the buffer's capacity
};

// Implemented by kernel nodes that run a control loop: stops the loop and returns what it
// recorded. The harness calls it once, after the run, to report the loop metrics.
class ControlLoopSource {
 public:
  virtual ~ControlLoopSource();
  virtual LoopReport stop_and_report() = 0;
};

// Grey-box: a controller's update() in cycle `cycle` of controller manager `manager`, as
// robotperf:controller_update_begin (with the newest command the state it reads reflects) and
// robotperf:controller_update_end (with the command it took this cycle, -1 when none). A
// predicted branch when no session records them.
void trace_controller_update_begin(const char* manager, const char* controller, uint64_t cycle,
                                   int64_t observed_command);
void trace_controller_update_end(const char* manager, const char* controller, uint64_t cycle,
                                 int64_t taken_command);

}  // namespace robotperf::plugin
