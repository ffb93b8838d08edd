// Private to the harness: the processes of an external graph (graph.yaml `launch:`), started
// before timing in a process group of their own, supervised during the run and stopped after it
// (SIGINT, then SIGTERM, then SIGKILL, each after a bounded wait).
#pragma once

#include <sys/types.h>

#include <filesystem>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "robotperf/harness/benchmark_spec.hpp"
#include "robotperf/harness/run.hpp"

namespace robotperf::harness {

class LaunchedProcesses {
 public:
  // Starts every command of `spec.launch`, its ${domain}, ${rmw} and ${package} replaced, with
  // ROS_DOMAIN_ID and RMW_IMPLEMENTATION set to match the run; each one's stdout and stderr go to
  // <log_dir>/<log_prefix><name>.log. Throws std::runtime_error naming the command that cannot
  // start.
  LaunchedProcesses(const BenchmarkSpec& spec, const std::string& rmw, int domain_id,
                    const std::filesystem::path& log_dir, const std::string& log_prefix);
  ~LaunchedProcesses();
  LaunchedProcesses(const LaunchedProcesses&) = delete;
  LaunchedProcesses& operator=(const LaunchedProcesses&) = delete;

  // A process that ended before stop() was asked: what it was, when (`when`: "during the run",
  // "before the graph connected"), how it ended and the last lines of its log; empty while all
  // run.
  std::string failure(const std::string& when = "during the run") const;
  // Pid and name of every process.
  std::vector<std::pair<int, std::string>> processes() const;
  // Stops them all (the whole group, with what they started), at most `grace_s` per signal, and
  // reports each.
  std::vector<LaunchedReport> stop(double grace_s);

 private:
  struct Process {
    std::string name;
    std::string command;  // as run, one line
    std::filesystem::path log;
    pid_t pid = -1;
    int pidfd = -1;
    bool ended = false;
    std::string exit_status = "running";
    std::string stopped_by;  // how it came to end
  };
  void supervise();
  // Collects its exit status once it ended; with `wait`, waits for it to end.
  void reap(Process& p, bool wait = false);

  std::vector<Process> processes_;
  pid_t group_ = 0;
  mutable std::mutex mutex_;
  bool stopping_ = false;
  // The first process that ended by itself, and its log's last lines then.
  std::optional<std::size_t> failed_;
  std::string failed_log_tail_;
  int wake_pipe_[2] = {-1, -1};
  std::thread supervisor_;
};

// The last `lines` lines of a log file, each prefixed for the terminal; empty when none.
std::string log_tail(const std::filesystem::path& log, std::size_t lines);

}  // namespace robotperf::harness
