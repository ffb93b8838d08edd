// Private to the harness: the children of a per-node run, one process per
// node of the graph, supervised by the runner.
#pragma once

#include <sys/types.h>

#include <atomic>
#include <condition_variable>
#include <functional>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "robotperf/harness/run.hpp"

namespace robotperf::harness {

// The process group of an external graph's launched processes under way (0: none), which
// kill_node_processes() kills too.
extern std::atomic<pid_t> g_launched_group;

// A waitpid() status as results say it: "ok", "exited with status N", "killed by signal ...".
std::string describe_exit_status(int status);

// A command's words as one line, for messages and results.
std::string command_text(const std::vector<std::string>& words);

// Where a node process runs, as it reports itself on its first line ("host {json}"): the
// machine's host name and boot id, and its own pid there.
nlohmann::json this_host_identity();

// The command prefix that starts a process on `host` (graph.yaml `host:`): `launchers`' entry
// for it, else `ssh HOST --`.
std::vector<std::string> host_launcher(
    const std::string& host, const std::map<std::string, std::vector<std::string>>& launchers);

class NodeProcesses {
 public:
  // Starts `command` + [<package dir>, --node, NAME, --rmw, RMW, --domain, D] + `extra` for
  // every node, behind its host's launcher (host_launcher) for a node placed on a host.
  NodeProcesses(const BenchmarkSpec& spec, const std::vector<std::string>& command,
                const std::string& rmw, int domain_id, const std::vector<std::string>& extra = {},
                const std::map<std::string, std::vector<std::string>>& host_launchers = {});
  ~NodeProcesses();
  NodeProcesses(const NodeProcesses&) = delete;
  NodeProcesses& operator=(const NodeProcesses&) = delete;

  // Waits until every child reported ready; throws std::runtime_error when one
  // died or the deadline passed first.
  // Gives up (returns false) as soon as `abandon` returns true.
  bool wait_ready(int64_t deadline_ns, const std::function<bool()>& abandon);
  // A child that ended before shutdown() was asked: its description, else empty.
  std::string failure() const;
  // Pid and node name of every child that runs on this machine (after wait_ready(): as each
  // reported itself, so that a launcher in between does not count instead of the node).
  std::vector<std::pair<int, std::string>> processes() const;
  // Asks every child to finish (closes its stdin), collects its report, and
  // kills those that do not exit within `grace_s` (with the processes they started).
  std::vector<NodeReport> shutdown(double grace_s);
  // After shutdown(): the control loop reports the children sent (see control_loop.hpp), in the
  // order of the graph's nodes, each with "same_machine": whether its child ran on this one.
  std::vector<nlohmann::json> control_loops() const;

 private:
  struct Child {
    std::string name;
    std::string kernel;
    pid_t pid = -1;
    int to_child = -1;    // its stdin
    int from_child = -1;  // its stdout
    std::string buffer;
    bool ready = false;
    bool eof = false;
    bool killed = false;  // did not stop when asked: SIGKILL
    bool hung = false;    // its watchdog reported a stuck callback
    std::string error;    // what it reported before failing on its own (a callback threw)
    NodeReport report;
    nlohmann::json control_loop;  // null unless its kernel runs a control loop
    std::string boot_id;          // of the machine it runs on, as it reported
    std::string launcher;         // what started it on its host; empty: started here
  };
  // Starts a child for every node of `spec` (the constructor's arguments).
  void start(const BenchmarkSpec& spec, const std::vector<std::string>& command,
             const std::string& rmw, int domain_id, const std::vector<std::string>& extra,
             const std::map<std::string, std::vector<std::string>>& host_launchers);
  void supervise();
  void on_line(Child& child, const std::string& line);
  void reap(Child& child, bool wait);

  std::vector<Child> children_;
  pid_t group_ = 0;  // the children's process group
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  bool stopping_ = false;
  std::string failure_;
  int wake_pipe_[2] = {-1, -1};
  std::thread supervisor_;
};

}  // namespace robotperf::harness
