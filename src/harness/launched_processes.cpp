#include "launched_processes.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <deque>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "node_processes.hpp"
#include "process_table.hpp"
#include "robotperf/files/paths.hpp"

extern char** environ;

namespace robotperf::harness {
namespace {

namespace fs = std::filesystem;

// The RMW a ROS 2 node must use to speak robotperf's transport.
std::string ros_rmw_of(const std::string& rmw) {
  return rmw == "cyclonedds" ? "rmw_cyclonedds_cpp" : "rmw_fastrtps_cpp";
}

std::string replaced(std::string text, const std::map<std::string, std::string>& values) {
  for (const auto& [key, value] : values) {
    const std::string token = "${" + key + "}";
    for (auto at = text.find(token); at != std::string::npos; at = text.find(token, at))
      text.replace(at, token.size(), value), at += value.size();
  }
  return text;
}

// Our environment with `extra` set over it.
std::vector<std::string> environment_with(const std::map<std::string, std::string>& extra) {
  std::vector<std::string> out;
  for (char** e = environ; *e != nullptr; ++e) {
    const std::string entry = *e;
    if (!extra.contains(entry.substr(0, entry.find('=')))) out.push_back(entry);
  }
  for (const auto& [key, value] : extra) out.push_back(key + "=" + value);
  return out;
}

}  // namespace

std::string log_tail(const fs::path& log, std::size_t lines) {
  std::ifstream in(log);
  std::deque<std::string> last;
  for (std::string line; std::getline(in, line);) {
    last.push_back(line);
    if (last.size() > lines) last.pop_front();
  }
  std::string out;
  for (const auto& line : last) out += "\n  | " + line;
  return out;
}

LaunchedProcesses::LaunchedProcesses(const BenchmarkSpec& spec, const std::string& rmw,
                                     int domain_id, const fs::path& log_dir,
                                     const std::string& log_prefix) {
  if (pipe2(wake_pipe_, O_CLOEXEC) != 0)
    throw std::runtime_error(std::string("pipe: ") + strerror(errno));
  const std::map<std::string, std::string> values = {
      {"domain", std::to_string(domain_id)}, {"rmw", rmw}, {"package", spec.dir.string()}};
  for (const auto& launch : spec.launch) {
    Process p;
    p.name = launch.name;
    std::vector<std::string> args;
    for (const auto& word : launch.command) args.push_back(replaced(word, values));
    p.command = command_text(args);
    std::map<std::string, std::string> env = {{"ROS_DOMAIN_ID", std::to_string(domain_id)},
                                              {"RMW_IMPLEMENTATION", ros_rmw_of(rmw)}};
    for (const auto& [key, value] : launch.env) env[key] = replaced(value, values);
    std::vector<std::string> environment = environment_with(env);
    p.log = files::path_inside(log_dir, log_prefix + launch.name + ".log");
    const fs::path cwd = launch.cwd.is_absolute() ? launch.cwd : spec.dir / launch.cwd;

    std::vector<char*> argv, envp;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    for (auto& e : environment) envp.push_back(e.data());
    envp.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, p.log.c_str(),
                                     O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW, 0644);
    posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
    posix_spawn_file_actions_addchdir_np(&actions, cwd.c_str());
    // One process group for all: a terminal's Ctrl-C reaches only the runner, which stops them,
    // and their own children are stopped with them.
    posix_spawnattr_t attributes;
    posix_spawnattr_init(&attributes);
    posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETPGROUP);
    posix_spawnattr_setpgroup(&attributes, group_);
    const int rc = posix_spawnp(&p.pid, argv[0], &actions, &attributes, argv.data(), envp.data());
    posix_spawnattr_destroy(&attributes);
    posix_spawn_file_actions_destroy(&actions);
    if (rc != 0) {
      stop(0.5);
      g_launched_group = 0;
      throw std::runtime_error("launch '" + launch.name + "': cannot start '" + p.command +
                               "' in " + cwd.string() + ": " + strerror(rc));
    }
    p.pidfd = static_cast<int>(syscall(SYS_pidfd_open, p.pid, 0));
    if (group_ == 0) {
      group_ = p.pid;
      g_launched_group = group_;
    }
    processes_.push_back(std::move(p));
  }
  supervisor_ = std::thread([this] { supervise(); });
}

LaunchedProcesses::~LaunchedProcesses() {
  stop(2.0);
  g_launched_group = 0;
  close(wake_pipe_[0]);
  close(wake_pipe_[1]);
}

void LaunchedProcesses::reap(Process& p, bool wait) {
  int status = 0;
  if (!p.ended && waitpid(p.pid, &status, wait ? 0 : WNOHANG) == p.pid) {
    p.ended = true;
    p.exit_status = describe_exit_status(status);
    if (p.pidfd >= 0) close(p.pidfd);
    p.pidfd = -1;
  }
}

// Waits for any process to end (its pidfd becomes readable), until stop() wakes it. A process
// without a pidfd (pidfd_open fails before Linux 5.3, or with no descriptor left) is looked at
// every kPollMs instead.
void LaunchedProcesses::supervise() {
  constexpr int kPollMs = 100;
  while (true) {
    std::vector<pollfd> fds{{wake_pipe_[0], POLLIN, 0}};
    bool polling = false;
    {
      std::lock_guard lock(mutex_);
      if (stopping_) return;
      for (auto& p : processes_) {
        if (p.ended) continue;
        if (p.pidfd >= 0) {
          fds.push_back({p.pidfd, POLLIN, 0});
        } else {
          polling = true;
        }
      }
    }
    if (fds.size() == 1 && !polling) return;
    if (poll(fds.data(), fds.size(), polling ? kPollMs : -1) < 0 && errno != EINTR) return;
    if (fds[0].revents & POLLIN) return;
    std::lock_guard lock(mutex_);
    for (auto& p : processes_) {
      if (p.ended) continue;
      reap(p);
      if (p.ended && !stopping_ && !failed_) {
        failed_ = static_cast<std::size_t>(&p - processes_.data());
        failed_log_tail_ = log_tail(p.log, 5);
      }
    }
  }
}

std::string LaunchedProcesses::failure(const std::string& when) const {
  std::lock_guard lock(mutex_);
  if (!failed_) return "";
  const Process& p = processes_[*failed_];
  return "launched process '" + p.name + "' (pid " + std::to_string(p.pid) + ") ended " + when +
         " (" + p.exit_status + "); its log " + p.log.string() +
         (failed_log_tail_.empty() ? " is empty" : " ends:" + failed_log_tail_);
}

std::vector<std::pair<int, std::string>> LaunchedProcesses::processes() const {
  std::lock_guard lock(mutex_);
  std::vector<std::pair<int, std::string>> out;
  for (const auto& p : processes_) out.emplace_back(p.pid, p.name);
  return out;
}

std::vector<LaunchedReport> LaunchedProcesses::stop(double grace_s) {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  if (supervisor_.joinable()) {
    const char b = 0;
    if (write(wake_pipe_[1], &b, 1) < 0) {
      // The supervisor also ends once every process has.
    }
    supervisor_.join();
  }
  std::lock_guard lock(mutex_);
  std::string sent;  // the last signal sent to the group
  auto all_ended = [&] {
    bool all = true;
    for (auto& p : processes_) {
      const bool was = p.ended;
      reap(p);
      if (p.ended && !was)
        p.stopped_by = sent.empty() ? "ended before the stop" : "stopped by " + sent;
      all = all && p.ended;
    }
    return all;
  };
  // Until the whole group is over, not only the processes we started: the node under `ros2 run`
  // or a wrapper script is their child, and may ignore the first signals.
  auto all_over = [&] { return all_ended() && !group_running(group_); };
  // As `ros2 launch` does: an interrupt first, so that nodes shut down cleanly.
  for (const auto& [signal_number, name] :
       {std::pair{SIGINT, "SIGINT"}, std::pair{SIGTERM, "SIGTERM"},
        std::pair{SIGKILL, "SIGKILL"}}) {
    if (group_ == 0 || all_over()) break;
    sent = name;
    kill(-group_, signal_number);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(grace_s);
    while (!all_over() && std::chrono::steady_clock::now() < deadline)
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  std::vector<LaunchedReport> out;
  for (auto& p : processes_) {
    if (!p.ended) {
      // Not even SIGKILL within the grace: wait for it, it cannot run on.
      reap(p, true);
      p.stopped_by = "stopped by SIGKILL";
    }
    if (p.stopped_by.empty()) p.stopped_by = "ended during the run";
    out.push_back({p.name, p.command, p.pid, p.exit_status, p.log.string(), p.stopped_by});
  }
  group_ = 0;
  return out;
}

}  // namespace robotperf::harness
