// How the graph runs on the CPUs: pinned to a set of CPUs, with a real-time priority, with its
// memory locked. Recorded in every result, since each changes latency.
#pragma once

#include <sched.h>

#include <string>
#include <vector>

namespace robotperf::harness {

struct SchedulingOptions {
  std::vector<unsigned> cpus;  // empty = wherever the OS puts it
  int rt_priority = 0;         // SCHED_FIFO priority 1-99; 0 = the normal scheduler
  bool lock_memory = false;    // mlockall: no page faults to disk during the run

  bool any() const { return !cpus.empty() || rt_priority != 0 || lock_memory; }
  // The same settings as arguments of `robotperf node`.
  std::vector<std::string> node_arguments() const;
};

// "0-3,6" -> {0, 1, 2, 3, 6}. Throws std::invalid_argument naming the bad part.
std::vector<unsigned> parse_cpu_list(const std::string& text);
std::string format_cpu_list(const std::vector<unsigned>& cpus);

// The CPUs this process may run on (its affinity mask).
std::vector<unsigned> allowed_cpus();
// Throws std::invalid_argument naming the CPUs of `cpus` this process may not run on.
void check_cpus_allowed(const std::vector<unsigned>& cpus);

// Applies the options to the calling thread (threads it creates afterwards inherit them) and,
// for memory, to the process; undoes them when destroyed. Throws std::invalid_argument for CPUs
// this process may not use, std::runtime_error saying what else the OS refused and what to do.
class ScopedScheduling {
 public:
  explicit ScopedScheduling(const SchedulingOptions& options);
  ~ScopedScheduling();
  ScopedScheduling(const ScopedScheduling&) = delete;
  ScopedScheduling& operator=(const ScopedScheduling&) = delete;

 private:
  void restore();

  bool restore_affinity_ = false;
  cpu_set_t affinity_{};
  bool restore_policy_ = false;
  int policy_ = SCHED_OTHER;
  sched_param param_{};
  bool unlock_memory_ = false;
};

}  // namespace robotperf::harness
