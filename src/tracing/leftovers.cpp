#include "robotperf/tracing/leftovers.hpp"

#include <limits.h>
#include <signal.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "forced_exit.hpp"
#include "lttng_command.hpp"
#include "ownership.hpp"
#include "robotperf/tracing/session.hpp"

extern char** environ;

namespace robotperf::tracing {
namespace {

namespace fs = std::filesystem;
using namespace detail;

// What a forced exit must undo, in storage set aside beforehand: the signal handler reads it
// without allocating. A slot is emptied before it is rewritten, so that the handler never reads
// half a name; one too long for it is left to the next run's clean-up.
class Slot {
 public:
  void hold(const std::string& text) {
    set_ = false;
    if (text.size() >= sizeof text_) return;
    std::memcpy(text_, text.c_str(), text.size() + 1);
    set_ = true;
  }
  void clear() { set_ = false; }
  const char* text() const { return set_ ? text_ : ""; }

 private:
  std::atomic<bool> set_{false};
  char text_[PATH_MAX] = {};
};

Slot g_session;
Slot g_started_daemon;
Slot g_trace_folder;
Slot g_daemon_use_file;
std::atomic<int> g_daemon_use_fd{-1};

// What the destructors would do, as the forced exit may: the handler can only fork and exec,
// so a fixed shell script does it with the recorded names as arguments ($1 session, $2 daemon
// pid, $3 folder, $4 the daemon's lock file); the daemon is stopped only when no other session
// uses it and no other run holds the lock file (one about to use the daemon).
constexpr const char* kForcedCleanupScript =
    "exec >/dev/null 2>&1\n"
    "[ -n \"$1\" ] && lttng destroy \"$1\"\n"
    "[ -n \"$2\" ] && flock -n -x \"$4\" sh -c "
    "'lttng list | grep -q \"Currently no available\" && kill \"$0\"' \"$2\"\n"
    "[ -n \"$3\" ] && rm -rf -- \"$3\"\n"
    "exit 0\n";

// The trace folders under `output_folder` whose maker no longer runs; a folder without
// robotperf's marker is never touched.
void remove_stale_trace_folders(const fs::path& output_folder, std::vector<std::string>& removed) {
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(output_folder, ec)) {
    if (!entry.path().filename().string().starts_with(".trace-") || !entry.is_directory(ec))
      continue;
    std::ifstream marker(entry.path() / kTraceFolderMarker);
    std::string line;
    if (!std::getline(marker, line)) continue;
    const auto maker = parse_identity(line);
    if (!maker || still_runs(*maker)) continue;
    fs::remove_all(entry.path(), ec);
    if (!ec) removed.push_back("the trace folder " + entry.path().string());
  }
}

// `lttng list` names each session on a line "  N) NAME [state]".
std::vector<std::string> session_names(const std::string& listing) {
  std::vector<std::string> names;
  std::istringstream lines(listing);
  for (std::string line; std::getline(lines, line);) {
    std::istringstream words(line);
    std::string number, name;
    if (words >> number >> name && number.size() > 1 && number.back() == ')') names.push_back(name);
  }
  return names;
}

void destroy_stale_sessions(std::vector<std::string>& removed) {
  const CommandResult listing = run_command({"lttng", "list"});
  if (listing.exit_code != 0) return;
  for (const std::string& name : session_names(listing.output)) {
    const auto maker = session_maker(name);
    if (!maker || still_runs(*maker)) continue;
    if (run_command({"lttng", "destroy", name}).exit_code == 0)
      removed.push_back("the LTTng session " + name);
  }
}

// A session daemon a run started and could not stop: stopped once no session uses it.
void stop_orphaned_daemon(std::vector<std::string>& removed) {
  const auto ownership = read_daemon_ownership();
  if (!ownership) return;
  std::error_code ec;
  if (!still_runs(ownership->daemon)) {
    fs::remove(daemon_owner_file(), ec);
    return;
  }
  if (still_runs(ownership->starter)) return;
  // A run that found the daemon answering and has not made its session yet holds the lock.
  const auto alone = DaemonUseLock::alone_if_unused();
  if (!alone || !daemon_idle()) return;
  stop_daemon(ownership->daemon.pid);
  fs::remove(daemon_owner_file(), ec);
  removed.push_back("the LTTng session daemon (pid " + std::to_string(ownership->daemon.pid) +
                    ") such a run started");
}

}  // namespace

namespace detail {

void note_session(const std::string& name) {
  g_session.hold(name);
}
void forget_session() {
  g_session.clear();
}
void note_started_daemon(pid_t pid) {
  g_started_daemon.hold(std::to_string(pid));
}
void forget_started_daemon() {
  g_started_daemon.clear();
}
void note_daemon_use(int fd, const std::string& lock_file) {
  g_daemon_use_file.hold(lock_file);
  g_daemon_use_fd = fd;
}
void forget_daemon_use() {
  g_daemon_use_fd = -1;
  g_daemon_use_file.clear();
}

}  // namespace detail

TemporaryTraceFolder::TemporaryTraceFolder(const fs::path& parent) {
  std::string pattern = fs::absolute(parent / ".trace-XXXXXX").string();
  if (mkdtemp(pattern.data()) == nullptr) {
    throw std::runtime_error("cannot make a trace folder in " + parent.string() + ": " +
                             std::strerror(errno));
  }
  folder_ = pattern;
  std::ofstream marker(folder_ / kTraceFolderMarker);
  marker << text_of(this_process()) << "\n";
  marker.close();
  if (!marker) {
    std::error_code ec;
    fs::remove_all(folder_, ec);
    throw std::runtime_error("cannot write in the trace folder " + folder_.string());
  }
  g_trace_folder.hold(folder_.string());
}

TemporaryTraceFolder::~TemporaryTraceFolder() {
  g_trace_folder.clear();
  std::error_code ec;
  fs::remove_all(folder_, ec);
}

void clean_up_at_forced_exit() noexcept {
  const char* session = g_session.text();
  const char* daemon = g_started_daemon.text();
  const char* folder = g_trace_folder.text();
  const char* lock_file = g_daemon_use_file.text();
  if (*session == '\0' && *daemon == '\0' && *folder == '\0') return;
  // This process's own hold on the daemon goes first, or the script could never take it alone.
  if (const int fd = g_daemon_use_fd.exchange(-1); fd >= 0) close(fd);
  const char* argv[] = {
      "sh", "-c", kForcedCleanupScript, "robotperf", session, daemon, folder, lock_file, nullptr};
  // _Fork, unlike fork, runs no atfork handlers: it is async-signal-safe.
  const pid_t child = _Fork();
  if (child == 0) {
    // In a session of its own, so that a terminal's next Ctrl-C does not stop it halfway, and
    // with no signal blocked by the handler.
    setsid();
    sigset_t none;
    sigemptyset(&none);
    sigprocmask(SIG_SETMASK, &none, nullptr);
    execve("/bin/sh", const_cast<char* const*>(argv), environ);
    _exit(127);
  }
  if (child < 0) return;
  // A daemon that does not answer must not keep the process from ending: 10 s at most.
  for (int i = 0; i < 1000; ++i) {
    const pid_t done = waitpid(child, nullptr, WNOHANG);
    if (done == child || (done < 0 && errno != EINTR)) return;
    const timespec ten_ms{0, 10'000'000};
    nanosleep(&ten_ms, nullptr);
  }
}

std::vector<std::string> remove_leftovers(const fs::path& output_folder) {
  std::vector<std::string> removed;
  remove_stale_trace_folders(output_folder, removed);
  if (!lttng_available()) return removed;
  try {
    destroy_stale_sessions(removed);
    stop_orphaned_daemon(removed);
  } catch (const std::exception&) {
    // lttng could not be run: the run that follows says so.
  }
  return removed;
}

}  // namespace robotperf::tracing
