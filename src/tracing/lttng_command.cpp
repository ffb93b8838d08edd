#include "lttng_command.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <fstream>
#include <thread>

#include "robotperf/tracing/session.hpp"

extern char** environ;

namespace robotperf::tracing::detail {

namespace fs = std::filesystem;

const char* const kInstallHint =
    "install lttng-tools (Debian: sudo apt-get install lttng-tools liblttng-ust-dev babeltrace2, "
    "or run scripts/install-deps.sh); black-box runs (the default --mode black) do not need it";

CommandResult run_command(const std::vector<std::string>& args) {
  int pipe_fds[2];
  if (pipe2(pipe_fds, O_CLOEXEC) != 0) throw TracingError("cannot create a pipe for " + args[0]);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, pipe_fds[1], STDOUT_FILENO);
  posix_spawn_file_actions_adddup2(&actions, pipe_fds[1], STDERR_FILENO);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  pid_t pid = 0;
  const int rc = posix_spawnp(&pid, args[0].c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  close(pipe_fds[1]);
  if (rc != 0) {
    close(pipe_fds[0]);
    throw TracingUnavailable("cannot run " + args[0] + ": " + kInstallHint);
  }
  CommandResult result;
  char buf[4096];
  ssize_t n;
  while ((n = read(pipe_fds[0], buf, sizeof buf)) > 0 || (n < 0 && errno == EINTR)) {
    if (n > 0) result.output.append(buf, static_cast<std::size_t>(n));
  }
  close(pipe_fds[0]);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return result;
}

// The root daemon in /var/run/lttng, a user's in $LTTNG_HOME/.lttng, else $HOME/.lttng.
fs::path daemon_pid_file() {
  if (getuid() == 0) return "/var/run/lttng/lttng-sessiond.pid";
  const char* home = std::getenv("LTTNG_HOME");
  if (home == nullptr || *home == '\0') home = std::getenv("HOME");
  return fs::path(home ? home : "") / ".lttng" / "lttng-sessiond.pid";
}

pid_t daemon_pid() {
  std::ifstream in(daemon_pid_file());
  pid_t pid = 0;
  return in >> pid && pid > 0 ? pid : 0;
}

bool daemon_idle() {
  const CommandResult sessions = run_command({"lttng", "list"});
  // lttng-tools 2.13 says "recording session", earlier versions "tracing session".
  return sessions.exit_code == 0 &&
         (sessions.output.find("Currently no available recording session") != std::string::npos ||
          sessions.output.find("Currently no available tracing session") != std::string::npos);
}

void stop_daemon(pid_t pid) {
  if (pid <= 0 || kill(pid, SIGTERM) != 0) return;
  for (int i = 0; i < 250 && kill(pid, 0) == 0; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
}

}  // namespace robotperf::tracing::detail
