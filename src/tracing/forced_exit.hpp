// What the recording session tells clean_up_at_forced_exit() (leftovers.hpp) to undo.
#pragma once

#include <sys/types.h>

#include <string>

namespace robotperf::tracing::detail {

void note_session(const std::string& name);
void forget_session();
void note_started_daemon(pid_t pid);
void forget_started_daemon();
// The session's hold on the daemon (DaemonUseLock): released before the clean-up script runs,
// which stops the daemon only when it can take the lock file alone.
void note_daemon_use(int fd, const std::string& lock_file);
void forget_daemon_use();

}  // namespace robotperf::tracing::detail
