#include "node_processes.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "robotperf/rmw/transport.hpp"

extern char** environ;

namespace robotperf::harness {
namespace {}  // namespace

std::string command_text(const std::vector<std::string>& words) {
  std::string out;
  for (const auto& w : words) out += (out.empty() ? "" : " ") + w;
  return out;
}

std::string describe_exit_status(int status) {
  if (WIFEXITED(status)) {
    return WEXITSTATUS(status) == 0 ? "ok"
                                    : "exited with status " + std::to_string(WEXITSTATUS(status));
  }
  if (WIFSIGNALED(status)) return std::string("killed by signal ") + strsignal(WTERMSIG(status));
  return "ended (status " + std::to_string(status) + ")";
}

namespace {

void make_pipe(int fds[2]) {
  if (pipe2(fds, O_CLOEXEC) != 0) throw std::runtime_error(std::string("pipe: ") + strerror(errno));
}

// The process group of the node processes under way (0: none): the children run in a group of
// their own, so that a terminal's Ctrl-C reaches only the runner, which stops them, and so that
// they can all be killed at once.
std::atomic<pid_t> g_children_group{0};

}  // namespace

std::atomic<pid_t> g_launched_group{0};

void kill_node_processes() noexcept {
  for (const pid_t group : {g_children_group.load(), g_launched_group.load()})
    if (group > 0) kill(-group, SIGKILL);
}

nlohmann::json this_host_identity() {
  char name[256] = {};
  gethostname(name, sizeof name - 1);
  std::string boot_id;
  std::ifstream("/proc/sys/kernel/random/boot_id") >> boot_id;
  return {{"hostname", name}, {"boot_id", boot_id}, {"pid", getpid()}};
}

std::vector<std::string> host_launcher(
    const std::string& host, const std::map<std::string, std::vector<std::string>>& launchers) {
  if (auto it = launchers.find(host); it != launchers.end()) return it->second;
  return {"ssh", host, "--"};
}

NodeProcesses::NodeProcesses(
    const BenchmarkSpec& spec, const std::vector<std::string>& command, const std::string& rmw,
    int domain_id, const std::vector<std::string>& extra,
    const std::map<std::string, std::vector<std::string>>& host_launchers) {
  if (command.empty()) throw std::invalid_argument("per-node runs need the robotperf node command");
  make_pipe(wake_pipe_);
  // A child that dies must not kill the runner with SIGPIPE when we write to it.
  signal(SIGPIPE, SIG_IGN);
  try {
    start(spec, command, rmw, domain_id, extra, host_launchers);
    supervisor_ = std::thread([this] { supervise(); });
  } catch (...) {
    // The children started before the one that failed go with it, and what they started.
    if (group_ > 0) kill(-group_, SIGKILL);
    for (auto& c : children_) {
      close(c.to_child);
      close(c.from_child);
      waitpid(c.pid, nullptr, 0);
    }
    g_children_group = 0;
    close(wake_pipe_[0]);
    close(wake_pipe_[1]);
    throw;
  }
}

void NodeProcesses::start(const BenchmarkSpec& spec, const std::vector<std::string>& command,
                          const std::string& rmw, int domain_id,
                          const std::vector<std::string>& extra,
                          const std::map<std::string, std::vector<std::string>>& host_launchers) {
  for (const auto& node : spec.nodes) {
    Child c;
    c.name = node.name;
    c.kernel = node.kernel;
    c.report = {node.name, node.kernel, 0,  "running", -1,           -1,
                {},        node.host,   "", true,      node.backend, {}};
    int in[2], out[2];
    make_pipe(in);
    try {
      make_pipe(out);
    } catch (...) {
      close(in[0]);
      close(in[1]);
      throw;
    }
    std::vector<std::string> args;
    if (!node.host.empty()) {
      args = host_launcher(node.host, host_launchers);
      c.launcher = command_text(args);
    }
    args.insert(args.end(), command.begin(), command.end());
    args.push_back(spec.dir.string());
    args.insert(args.end(),
                {"--node", node.name, "--rmw", rmw, "--domain", std::to_string(domain_id)});
    args.insert(args.end(), extra.begin(), extra.end());
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);

    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, in[0], STDIN_FILENO);
    posix_spawn_file_actions_adddup2(&actions, out[1], STDOUT_FILENO);
    // The first child leads a new process group; the others join it.
    posix_spawnattr_t attributes;
    posix_spawnattr_init(&attributes);
    posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETPGROUP);
    posix_spawnattr_setpgroup(&attributes, group_);
    // A launcher (ssh, ip) is looked up on PATH.
    const int rc = posix_spawnp(&c.pid, argv[0], &actions, &attributes, argv.data(), environ);
    posix_spawnattr_destroy(&attributes);
    posix_spawn_file_actions_destroy(&actions);
    close(in[0]);
    close(out[1]);
    if (rc != 0) {
      close(in[1]);
      close(out[0]);
      throw std::runtime_error("cannot start node '" + node.name + "' (" + args[0] +
                               "): " + strerror(rc));
    }
    c.to_child = in[1];
    c.from_child = out[0];
    c.report.pid = c.pid;
    if (group_ == 0) {
      group_ = c.pid;
      g_children_group = group_;
    }
    children_.push_back(std::move(c));
  }
}

NodeProcesses::~NodeProcesses() {
  shutdown(2.0);
  g_children_group = 0;
  close(wake_pipe_[0]);
  close(wake_pipe_[1]);
}

// Reads every child's stdout until all reach end of file: a line protocol
// ("ready", "stats {json}") and, at EOF, the child's end.
void NodeProcesses::supervise() {
  while (true) {
    std::vector<pollfd> fds{{wake_pipe_[0], POLLIN, 0}};
    std::vector<Child*> owners{nullptr};
    {
      std::lock_guard lock(mutex_);
      for (auto& c : children_) {
        if (!c.eof) {
          fds.push_back({c.from_child, POLLIN, 0});
          owners.push_back(&c);
        }
      }
    }
    if (fds.size() == 1) return;
    if (poll(fds.data(), fds.size(), -1) < 0 && errno != EINTR) return;
    if (fds[0].revents & POLLIN) {
      char b;
      if (read(wake_pipe_[0], &b, 1) <= 0) return;
    }
    for (std::size_t i = 1; i < fds.size(); ++i) {
      if (!(fds[i].revents & (POLLIN | POLLHUP | POLLERR))) continue;
      Child& c = *owners[i];
      char buf[4096];
      const ssize_t n = read(c.from_child, buf, sizeof buf);
      std::lock_guard lock(mutex_);
      if (n > 0) {
        c.buffer.append(buf, static_cast<std::size_t>(n));
        for (auto nl = c.buffer.find('\n'); nl != std::string::npos; nl = c.buffer.find('\n')) {
          on_line(c, c.buffer.substr(0, nl));
          c.buffer.erase(0, nl + 1);
        }
      } else {
        c.eof = true;
        close(c.from_child);
        reap(c, true);
        if (!stopping_ && failure_.empty()) {
          const std::string who =
              "node '" + c.name + "' (pid " + std::to_string(c.report.pid) + ")";
          failure_ = c.error.empty() ? who + " " + c.report.exit_status + " during the run"
                                     : who + ": " + c.error + " (" + c.report.exit_status + ")";
          if (!c.report.host.empty() && !c.ready) {
            failure_ += "; it was started on host " + c.report.host + " with '" + c.launcher +
                        "' (--host " + c.report.host + "=COMMAND, or --netns)";
          }
        }
      }
      cv_.notify_all();
    }
  }
}

void NodeProcesses::on_line(Child& child, const std::string& line) {
  if (line.rfind("host ", 0) == 0) {
    const auto j = nlohmann::json::parse(line.substr(5), nullptr, false);
    if (j.is_object()) {
      child.report.hostname = j.value("hostname", "");
      child.boot_id = j.value("boot_id", "");
      static const std::string ours = this_host_identity().value("boot_id", "");
      child.report.same_machine = !child.boot_id.empty() && child.boot_id == ours;
      // Behind a launcher, the node is not the process we started.
      if (child.report.same_machine) child.report.pid = j.value("pid", child.report.pid);
    }
  } else if (line.rfind("device ", 0) == 0) {
    const auto j = nlohmann::json::parse(line.substr(7), nullptr, false);
    if (j.is_object()) child.report.device = device_from_json(j);
  } else if (line == "ready") {
    child.ready = true;
  } else if (line.rfind("hung ", 0) == 0) {
    // The child's watchdog: one of its callbacks ran past the callback timeout.
    child.hung = true;
    if (failure_.empty()) {
      failure_ = "node '" + child.name + "' (pid " + std::to_string(child.report.pid) +
                 ") hung: " + line.substr(5);
    }
  } else if (line.rfind("error ", 0) == 0) {
    child.error = line.substr(6);
  } else if (line.rfind("stats ", 0) == 0) {
    const auto j = nlohmann::json::parse(line.substr(6), nullptr, false);
    if (!j.is_discarded()) {
      child.report.cpu_user_s = j.value("cpu_user_s", -1.0);
      child.report.cpu_system_s = j.value("cpu_system_s", -1.0);
      if (const auto c = j.find("counters"); c != j.end() && c->is_object()) {
        for (const auto& [name, value] : c->items()) {
          if (value.is_number_unsigned()) child.report.counters[name] = value.get<uint64_t>();
        }
      }
      if (const auto loop = j.find("control_loop"); loop != j.end() && loop->is_object())
        child.control_loop = *loop;
    }
  }
}

void NodeProcesses::reap(Child& child, bool wait) {
  if (child.pid <= 0) return;
  int status = 0;
  const pid_t r = waitpid(child.pid, &status, wait ? 0 : WNOHANG);
  if (r == child.pid) {
    child.report.exit_status = child.hung ? "hung: its watchdog ended it (a callback ran past the "
                                            "callback timeout)"
                                          : describe_exit_status(status);
    child.pid = -1;
  }
}

bool NodeProcesses::wait_ready(int64_t deadline_ns, const std::function<bool()>& abandon) {
  std::unique_lock lock(mutex_);
  auto done = [&] {
    if (!failure_.empty()) return true;
    for (const auto& c : children_) {
      if (!c.ready) return false;
    }
    return true;
  };
  // In slices of 100 ms, to see `abandon` too.
  bool ok = false;
  while (!(ok = done())) {
    const int64_t now = rmw::steady_now_ns();
    if (now >= deadline_ns) break;
    if (abandon()) return false;
    const int64_t until = std::min(deadline_ns, now + 100'000'000);
    cv_.wait_until(lock, std::chrono::steady_clock::time_point(std::chrono::nanoseconds(until)));
  }
  if (!failure_.empty()) throw std::runtime_error(failure_ + " (before it was ready)");
  if (!ok) {
    std::string waiting;
    for (const auto& c : children_) {
      if (!c.ready) waiting += (waiting.empty() ? "" : ", ") + c.name;
    }
    throw std::runtime_error("nodes not connected in time: " + waiting +
                             " (their topics found no peers; check the transport and graph.yaml)");
  }
  return true;
}

std::string NodeProcesses::failure() const {
  std::lock_guard lock(mutex_);
  return failure_;
}

std::vector<std::pair<int, std::string>> NodeProcesses::processes() const {
  std::lock_guard lock(mutex_);
  std::vector<std::pair<int, std::string>> out;
  for (const auto& c : children_) {
    if (c.report.same_machine) out.emplace_back(c.report.pid, c.name);
  }
  return out;
}

std::vector<nlohmann::json> NodeProcesses::control_loops() const {
  std::lock_guard lock(mutex_);
  std::vector<nlohmann::json> out;
  for (const auto& c : children_) {
    if (c.control_loop.is_null()) continue;
    out.push_back(c.control_loop);
    out.back()["same_machine"] = c.report.same_machine;
  }
  return out;
}

std::vector<NodeReport> NodeProcesses::shutdown(double grace_s) {
  {
    std::lock_guard lock(mutex_);
    if (!stopping_) {
      stopping_ = true;
      for (auto& c : children_) {
        close(c.to_child);
        c.to_child = -1;
      }
    }
  }
  {
    std::unique_lock lock(mutex_);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(grace_s);
    auto all_done = [&] {
      for (const auto& c : children_) {
        if (!c.eof) return false;
      }
      return true;
    };
    if (!cv_.wait_until(lock, deadline, all_done)) {
      for (auto& c : children_) c.killed = !c.eof && c.pid > 0;
      // The whole group: what a child started may hold its stdout open, and the supervisor
      // reads every stdout to its end.
      kill(-group_, SIGKILL);
    }
  }
  if (supervisor_.joinable()) {
    const char b = 0;
    if (write(wake_pipe_[1], &b, 1) < 0) {
      // The supervisor also ends once every child pipe reached EOF.
    }
    supervisor_.join();
  }
  std::vector<NodeReport> out;
  std::lock_guard lock(mutex_);
  for (auto& c : children_) {
    reap(c, true);
    if (c.killed) {
      std::ostringstream grace;
      grace << grace_s;
      c.report.exit_status = "did not stop within " + grace.str() + " s after the run: killed";
    }
    out.push_back(c.report);
  }
  return out;
}

}  // namespace robotperf::harness
