// Private to the harness: what is measured over the window besides latency — power and energy
// from every source found, and the resources of the graph's processes — plus the run-rule
// checks before the window opens.
#pragma once

#include <memory>
#include <vector>

#include "robotperf/harness/run.hpp"
#include "robotperf/metrics/power.hpp"
#include "robotperf/metrics/resources.hpp"

namespace robotperf::harness {

class WindowMeasurement {
 public:
  // Finds the power sources (before any timing) and starts the idle sampling thread. Throws
  // std::invalid_argument for a power meter command that does not work.
  WindowMeasurement(const RunOptions& options,
                    std::vector<metrics::ResourceMonitor::Process> graph);

  // The window opens: cheap enough to call from the Playback thread right after a send.
  void begin();
  // The window closes: last readings, then r.power and r.resources.
  void end(RunResult& r);

  // CPU used by every process but the graph's over a short interval, in % of one core.
  std::optional<double> probe_other_load() const;

 private:
  std::vector<metrics::ResourceMonitor::Process> graph_;
  metrics::PowerMeter meter_;
  metrics::ResourceMonitor resources_;
  metrics::PowerSampler sampler_;
};

// The run rules for this run (sysinfo::check_run_rules with this build and configuration).
std::vector<sysinfo::RunWarning> check_run_rules_for(const RunResult& r,
                                                     std::optional<double> other_load_percent);

}  // namespace robotperf::harness
