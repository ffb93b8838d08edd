// The lttng command line, shared by the recording session and the removal of what killed runs
// left.
#pragma once

#include <sys/types.h>

#include <filesystem>
#include <string>
#include <vector>

namespace robotperf::tracing::detail {

extern const char* const kInstallHint;

struct CommandResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr together
};

// Runs a program (found on PATH) and collects its output; throws TracingUnavailable when it
// cannot be started.
CommandResult run_command(const std::vector<std::string>& args);

// Where the session daemon of this user writes its pid (lttng-sessiond(8)).
std::filesystem::path daemon_pid_file();
// The pid in it, 0 when there is none.
pid_t daemon_pid();

// Whether a session daemon answers and has no recording session.
bool daemon_idle();

// Ends the daemon `pid` and waits for it, briefly (it removes its pid file last).
void stop_daemon(pid_t pid);

}  // namespace robotperf::tracing::detail
