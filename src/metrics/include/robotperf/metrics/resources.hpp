// What the graph's processes used during the measured window, and how busy the rest of the
// machine was meanwhile (interference), from /proc. Reading happens at the window's two ends
// only, so it costs nothing while messages flow.
#pragma once

#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace robotperf::metrics {

// Cumulative counters of one process (all its threads), from /proc/<pid>/{stat,status,task}.
struct ProcessSnapshot {
  bool ok = false;
  std::string error;
  double cpu_user_s = 0;
  double cpu_system_s = 0;
  uint64_t minor_faults = 0;
  uint64_t major_faults = 0;
  uint64_t voluntary_switches = 0;  // summed over the threads alive at the snapshot
  uint64_t involuntary_switches = 0;
  std::optional<uint64_t> peak_rss_bytes;  // VmHWM: the process's peak since it started
};

// Busy and total CPU time, in clock ticks, from /proc/stat.
struct CpuTicks {
  uint64_t busy = 0;
  uint64_t total = 0;
};

struct SystemCpuSnapshot {
  bool ok = false;
  CpuTicks all;
  std::vector<CpuTicks> per_cpu;  // index = position of the cpuN line
  std::vector<unsigned> cpu_ids;  // N of each cpuN line
};

ProcessSnapshot read_process(const std::filesystem::path& proc_root, int pid);
SystemCpuSnapshot read_system_cpu(const std::filesystem::path& proc_root);

struct ProcessUsage {
  std::string label;  // e.g. the node name, or "runner" for the process of Playback and Monitor
  int pid = 0;
  bool measured = false;
  std::string error;  // why not measured
  double cpu_user_s = 0;
  double cpu_system_s = 0;
  double cpu_percent = 0;  // (user + system) / window, in % of one core
  std::optional<uint64_t> peak_rss_bytes;
  uint64_t voluntary_switches = 0;
  uint64_t involuntary_switches = 0;
  uint64_t minor_faults = 0;
  uint64_t major_faults = 0;
};

struct ResourceUsage {
  bool measured = false;  // begin() and end() both ran
  double window_s = 0;
  std::vector<ProcessUsage> processes;
  // Whole machine, from /proc/stat: busy % of each CPU, and of all CPUs together.
  std::vector<unsigned> cpu_ids;
  std::vector<double> per_cpu_busy_percent;
  std::optional<double> system_busy_percent;
  // CPU time used by every process other than the graph's, in % of one core: interference.
  std::optional<double> other_cpu_percent;
};

class ResourceMonitor {
 public:
  struct Process {
    int pid = 0;
    std::string label;
  };
  ResourceMonitor(std::filesystem::path proc_root, std::vector<Process> processes);

  // Snapshots at the ends of the window; times are CLOCK_MONOTONIC nanoseconds.
  void begin(int64_t now_ns);
  void end(int64_t now_ns);
  ResourceUsage usage() const;

 private:
  std::filesystem::path proc_root_;
  std::vector<Process> processes_;
  std::vector<ProcessSnapshot> first_, last_;
  SystemCpuSnapshot system_first_, system_last_;
  int64_t begin_ns_ = -1;
  int64_t end_ns_ = -1;
};

nlohmann::json to_json(const ResourceUsage& usage);

}  // namespace robotperf::metrics
