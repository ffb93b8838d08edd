#include "robotperf/tracing/session.hpp"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <stdexcept>
#include <thread>

#include "forced_exit.hpp"
#include "lttng_command.hpp"
#include "ownership.hpp"

namespace robotperf::tracing {
namespace {

namespace fs = std::filesystem;
using namespace detail;

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

// Records the daemon this process started: beside its pid file for a later run, should this
// process be killed, and for a forced exit.
void own_started_daemon() {
  const pid_t pid = daemon_pid();
  if (pid == 0) return;
  write_daemon_ownership({process_identity(pid), this_process()});
  note_started_daemon(pid);
}

// Stops the session daemon once no recording session is left (another program may still use
// it), so that a daemon robotperf started does not outlive its run. One left running is
// stopped by a later run once idle (remove_leftovers).
void stop_daemon_when_idle() {
  forget_started_daemon();
  const auto alone = DaemonUseLock::alone_if_unused();
  if (!alone || !daemon_idle()) return;
  stop_daemon(daemon_pid());
  std::error_code ec;
  fs::remove(daemon_owner_file(), ec);
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
  // A daemon that is being stopped (another run's, ending with it) still holds its lock file for
  // a moment and makes a new one refuse to start: try again until it is gone, at most 10 s.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  for (;;) {
    const CommandResult r = run_command({"lttng-sessiond", "--daemonize"});
    if (r.exit_code == 0) return true;
    // Two processes may race to start one; the loser's daemon exits, which is fine.
    if (daemon_answers()) return false;
    if (std::chrono::steady_clock::now() > deadline)
      throw TracingError("cannot start the LTTng session daemon: " + r.output);
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
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
  try {
    daemon_use_ = std::make_unique<DaemonUseLock>(DaemonUseLock::shared());
    note_daemon_use(daemon_use_->fd(), daemon_use_lock_file().string());
  } catch (const std::runtime_error& e) {
    throw TracingError(e.what());
  }
  started_daemon_ = ensure_session_daemon();
  try {
    if (started_daemon_) own_started_daemon();
    start();
  } catch (...) {
    // No destructor runs after a throwing constructor: a daemon started for this session ends
    // with it here.
    forget_daemon_use();
    daemon_use_.reset();
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

  name_ = new_session_name(options_.name_hint);
  lttng({"create", name_, "--output=" + options_.output_dir.string()});
  active_ = true;
  note_session(name_);
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
    destroy();
    throw;
  }
}

bool RecordingSession::destroy() {
  if (run_command({"lttng", "destroy", name_}).exit_code != 0) return false;
  active_ = false;
  forget_session();
  return true;
}

RecordingSession::~RecordingSession() {
  if (active_) destroy();
  forget_daemon_use();
  daemon_use_.reset();
  if (started_daemon_) stop_daemon_when_idle();
}

void RecordingSession::stop() {
  if (!active_) return;
  // The session stays active until it is destroyed: if destroying it fails here, the destructor
  // tries again (and a daemon started for it is stopped only once no session is left).
  try {
    lttng({"stop", name_});
  } catch (...) {
    destroy();
    throw;
  }
  lttng({"destroy", name_});
  active_ = false;
  forget_session();
}

}  // namespace robotperf::tracing
