// How robotperf marks what a grey run makes outside its own process (an LTTng session, a session
// daemon it started, a temporary trace folder), so that a later run can tell its leftovers from
// anything else and whether the process that made them still runs.
#pragma once

#include <sys/types.h>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

namespace robotperf::tracing::detail {

// A process, told apart from a later one given the same pid: its start time (clock ticks after
// boot, /proc/<pid>/stat) and the boot it started in.
struct ProcessIdentity {
  pid_t pid = 0;
  uint64_t start_ticks = 0;
  std::string boot_id;
};

ProcessIdentity this_process();
ProcessIdentity process_identity(pid_t pid);  // start_ticks 0 when it does not run
// Whether that very process still runs.
bool still_runs(const ProcessIdentity& process);
std::string text_of(const ProcessIdentity& process);  // "pid start boot"
std::optional<ProcessIdentity> parse_identity(const std::string& text);

// robotperf-<hint>-<pid>-s<start ticks>-<n>: unique to this process's n-th session, and names
// the process that made it (sessions end with the boot).
std::string new_session_name(const std::string& hint);
std::optional<ProcessIdentity> session_maker(const std::string& name);

// In a temporary trace folder: who made it.
constexpr const char* kTraceFolderMarker = ".robotperf-trace-folder";

// Beside the session daemon's pid file: which daemon a robotperf process started, and who.
std::filesystem::path daemon_owner_file();
struct DaemonOwnership {
  ProcessIdentity daemon;
  ProcessIdentity starter;
};
void write_daemon_ownership(const DaemonOwnership& ownership);
std::optional<DaemonOwnership> read_daemon_ownership();

// The session daemon's users: every recording session holds this lock shared, from before it
// looks for a daemon until it is destroyed, and a process stops a daemon only while it holds the
// lock alone. Without it, a run that found a daemon answering could lose it to another process
// that saw no session yet and stopped it (a run ending, or one removing a killed run's leftovers).
// An flock on a file beside the daemon's pid file: the kernel releases it with the process.
class DaemonUseLock {
 public:
  // Waits while a process stopping a daemon holds it alone. Throws std::runtime_error, saying
  // why, when the lock file cannot be opened.
  static DaemonUseLock shared();
  // The lock alone, or nothing when another process holds it (now, without waiting).
  static std::optional<DaemonUseLock> alone_if_unused();

  DaemonUseLock(DaemonUseLock&& other) noexcept;
  DaemonUseLock& operator=(DaemonUseLock&& other) noexcept;
  DaemonUseLock(const DaemonUseLock&) = delete;
  DaemonUseLock& operator=(const DaemonUseLock&) = delete;
  ~DaemonUseLock();

  int fd() const { return fd_; }

 private:
  explicit DaemonUseLock(int fd) : fd_(fd) {}
  int fd_ = -1;
};
std::filesystem::path daemon_use_lock_file();

}  // namespace robotperf::tracing::detail
