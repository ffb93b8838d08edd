// Private to the harness: what is measured over the window besides latency — power and energy
// from every source found, and the resources of the graph's processes — plus the run-rule
// checks before the window opens.
#pragma once

#include <sys/types.h>

#include <cstdint>
#include <memory>
#include <vector>

#include "robotperf/harness/run.hpp"
#include "robotperf/metrics/power.hpp"
#include "robotperf/metrics/resources.hpp"

namespace robotperf::harness {

// The processes below some of the graph's processes (their children, theirs, ...), sampled as
// theirs: a launched command's real node runs under `ros2 run`, `ros2 launch` or a wrapper script.
// Each end of the window lists them anew from /proc, so that those started meanwhile count too
// (one that ends inside the window is not there at its end, and its time in it is not counted).
class Descendants {
 public:
  explicit Descendants(std::vector<pid_t> roots) : roots_(std::move(roots)) {}
  void begin() { first_ = snapshot(); }
  void end() { last_ = snapshot(); }
  // Adds each root's descendants' use over the window to the root's entry in `usage` (by pid;
  // peak RSS as the sum of their peaks), and takes their CPU out of the other processes'.
  void add_to(metrics::ResourceUsage& usage) const;

 private:
  struct Member {
    pid_t root;
    pid_t pid;
    uint64_t start_ticks;
    metrics::ProcessSnapshot counters;
  };
  std::vector<Member> snapshot() const;

  std::vector<pid_t> roots_;
  std::vector<Member> first_, last_;
};

class WindowMeasurement {
 public:
  // Finds the power sources (before any timing) and starts the idle sampling thread. Throws
  // std::invalid_argument for a power meter command that does not work. The processes of `graph`
  // whose pids are in `with_descendants` are sampled with their descendants.
  WindowMeasurement(const RunOptions& options, std::vector<metrics::ResourceMonitor::Process> graph,
                    std::vector<pid_t> with_descendants = {});

  // The window opens: cheap enough to call from the Playback thread right after a send.
  void begin();
  // The window closes: last readings, then r.power and r.resources.
  void end(RunResult& r);

  // CPU used by every process but the graph's over a short interval, in % of one core.
  std::optional<double> probe_other_load() const;

 private:
  std::vector<metrics::ResourceMonitor::Process> graph_;
  std::vector<pid_t> with_descendants_;
  metrics::PowerMeter meter_;
  metrics::ResourceMonitor resources_;
  Descendants descendants_;
  metrics::PowerSampler sampler_;
};

// The run rules for this run (sysinfo::check_run_rules with this build and configuration).
std::vector<sysinfo::RunWarning> check_run_rules_for(const RunResult& r,
                                                     std::optional<double> other_load_percent);

}  // namespace robotperf::harness
