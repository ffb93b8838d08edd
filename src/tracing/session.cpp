#include "robotperf/tracing/session.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <fstream>
#include <stdexcept>
#include <thread>

extern char** environ;

namespace robotperf::tracing {
namespace {

namespace fs = std::filesystem;

const char* const kInstallHint =
    "install lttng-tools (Debian: sudo apt-get install lttng-tools liblttng-ust-dev babeltrace2, "
    "or run scripts/install-deps.sh); black-box runs (the default --mode black) do not need it";

bool on_path(const std::string& program) {
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "/usr/bin:/bin";
  std::size_t start = 0;
  while (start <= dirs.size()) {
    const std::size_t end = std::min(dirs.find(':', start), dirs.size());
    const fs::path candidate = fs::path(dirs.substr(start, end - start)) / program;
    if (access(candidate.c_str(), X_OK) == 0) return true;
    start = end + 1;
  }
  return false;
}

struct CommandResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr together
};

// Runs a program (found on PATH) and collects its output.
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

std::string join(const std::vector<std::string>& args) {
  std::string out;
  for (const auto& a : args) out += (out.empty() ? "" : " ") + a;
  return out;
}

std::string lttng(const std::vector<std::string>& args) {
  std::vector<std::string> full{"lttng"};
  full.insert(full.end(), args.begin(), args.end());
  CommandResult r = run_command(full);
  if (r.exit_code != 0) {
    while (!r.output.empty() && (r.output.back() == '\n' || r.output.back() == ' '))
      r.output.pop_back();
    throw TracingError(join(full) + " failed: " + r.output);
  }
  return r.output;
}

bool daemon_answers() {
  return run_command({"lttng", "list"}).exit_code == 0;
}

// Whether the session daemon knows this process (it lists its tracepoints).
bool registered(pid_t pid) {
  const CommandResult r = run_command({"lttng", "list", "--userspace"});
  return r.exit_code == 0 &&
         r.output.find("PID: " + std::to_string(pid) + " ") != std::string::npos;
}

// Where the session daemon of this user writes its pid (lttng-sessiond(8): the root daemon in
// /var/run/lttng, a user's in $LTTNG_HOME/.lttng, else $HOME/.lttng).
fs::path daemon_pid_file() {
  if (getuid() == 0) return "/var/run/lttng/lttng-sessiond.pid";
  const char* home = std::getenv("LTTNG_HOME");
  if (home == nullptr || *home == '\0') home = std::getenv("HOME");
  return fs::path(home ? home : "") / ".lttng" / "lttng-sessiond.pid";
}

// Stops the session daemon once no recording session is left (another program may still use
// it), so that a daemon robotperf started does not outlive its run.
void stop_daemon_when_idle() {
  const CommandResult sessions = run_command({"lttng", "list"});
  // lttng-tools 2.13 says "recording session", earlier versions "tracing session".
  const bool idle =
      sessions.exit_code == 0 &&
      (sessions.output.find("Currently no available recording session") != std::string::npos ||
       sessions.output.find("Currently no available tracing session") != std::string::npos);
  if (!idle) return;
  std::ifstream in(daemon_pid_file());
  pid_t pid = 0;
  if (!(in >> pid) || pid <= 0 || kill(pid, SIGTERM) != 0) return;
  // It removes its pid file last: wait for it, briefly.
  for (int i = 0; i < 250 && kill(pid, 0) == 0; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
}

std::string unique_name(const std::string& hint) {
  static std::atomic<unsigned> counter{0};
  std::string clean;
  for (char c : hint) clean += (std::isalnum(static_cast<unsigned char>(c)) || c == '_') ? c : '_';
  const auto now = std::chrono::system_clock::now().time_since_epoch();
  return "robotperf-" + clean + "-" + std::to_string(getpid()) + "-" +
         std::to_string(std::chrono::duration_cast<std::chrono::microseconds>(now).count()) + "-" +
         std::to_string(counter++);
}

}  // namespace

bool lttng_available(std::string* why) {
  for (const char* tool : {"lttng", "lttng-sessiond"}) {
    if (!on_path(tool)) {
      if (why)
        *why = std::string("LTTng is not installed (no '") + tool + "' on PATH): " + kInstallHint;
      return false;
    }
  }
  return true;
}

bool ensure_session_daemon() {
  if (daemon_answers()) return false;
  const CommandResult r = run_command({"lttng-sessiond", "--daemonize"});
  // Two processes may race to start one; the loser's daemon exits, which is fine.
  if (r.exit_code != 0 && !daemon_answers())
    throw TracingError("cannot start the LTTng session daemon: " + r.output);
  return true;
}

std::size_t subbuffer_bytes_for(double events_per_second) {
  constexpr double kBytesPerEvent = 128;  // header, vpid/vtid/procname context, a few fields
  const double wanted = events_per_second * kBytesPerEvent * 0.5 / 4;
  std::size_t size = 256 * 1024;
  while (static_cast<double>(size) < wanted && size < 16 * 1024 * 1024) size *= 2;
  return size;
}

void check_subbuffer_bytes(std::size_t bytes) {
  const auto page = static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
  constexpr std::size_t kMax = std::size_t{1} << 30;
  if (bytes < page || bytes > kMax || (bytes & (bytes - 1)) != 0) {
    throw std::invalid_argument("trace sub-buffer size " + std::to_string(bytes) +
                                " bytes: LTTng takes a power of two from the page size (" +
                                std::to_string(page) + ") to 1 GiB, e.g. 262144");
  }
}

RecordingSession::RecordingSession(SessionOptions options) : options_(std::move(options)) {
  if (options_.subbuf_bytes != 0) check_subbuffer_bytes(options_.subbuf_bytes);
  std::string why;
  if (!lttng_available(&why)) throw TracingUnavailable(why);
  if (options_.subbuf_bytes == 0) options_.subbuf_bytes = subbuffer_bytes_for(0);
  if (fs::exists(options_.output_dir))
    throw TracingError("trace folder " + options_.output_dir.string() + " already exists");
  options_.output_dir = fs::absolute(options_.output_dir);
  started_daemon_ = ensure_session_daemon();
  try {
    start();
  } catch (...) {
    // No destructor runs after a throwing constructor: a daemon started for this session ends
    // with it here.
    if (started_daemon_) stop_daemon_when_idle();
    throw;
  }
}

void RecordingSession::start() {
  // A process that started before the daemon registers with it in the
  // background; its events would be missed until then.
  const auto deadline =
      std::chrono::steady_clock::now() +
      std::chrono::milliseconds(static_cast<int64_t>(options_.register_timeout_s * 1000));
  while (!registered(getpid())) {
    if (std::chrono::steady_clock::now() > deadline) {
      throw TracingError(
          "this process did not register with the LTTng session daemon within " +
          std::to_string(options_.register_timeout_s) +
          " s (is LTTNG_UST_ALLOW_BLOCKING or LTTNG_HOME set differently for the daemon?)");
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }

  name_ = unique_name(options_.name_hint);
  lttng({"create", name_, "--output=" + options_.output_dir.string()});
  active_ = true;
  try {
    const std::string session = "--session=" + name_;
    lttng({"enable-channel", "--userspace", session,
           "--subbuf-size=" + std::to_string(options_.subbuf_bytes),
           "--num-subbuf=" + std::to_string(options_.num_subbuf), "robotperf"});
    for (const auto& e : options_.events)
      lttng({"enable-event", "--userspace", session, "--channel=robotperf", e});
    lttng({"add-context", "--userspace", session, "--channel=robotperf", "--type=vpid",
           "--type=vtid", "--type=procname"});
    if (!options_.only_processes.empty()) {
      std::string pids;
      for (int pid : options_.only_processes)
        pids += (pids.empty() ? "" : ",") + std::to_string(pid);
      lttng({"track", "--userspace", session, "--vpid=" + pids});
    }
    lttng({"start", name_});
  } catch (...) {
    run_command({"lttng", "destroy", name_});
    active_ = false;
    throw;
  }
}

RecordingSession::~RecordingSession() {
  if (active_) run_command({"lttng", "destroy", name_});
  if (started_daemon_) stop_daemon_when_idle();
}

void RecordingSession::stop() {
  if (!active_) return;
  // The session stays active until it is destroyed: if destroying it fails here, the destructor
  // tries again (and a daemon started for it is stopped only once no session is left).
  try {
    lttng({"stop", name_});
  } catch (...) {
    if (run_command({"lttng", "destroy", name_}).exit_code == 0) active_ = false;
    throw;
  }
  lttng({"destroy", name_});
  active_ = false;
}

}  // namespace robotperf::tracing
