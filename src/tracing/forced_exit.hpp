// What the recording session tells clean_up_at_forced_exit() (leftovers.hpp) to undo.
#pragma once

#include <sys/types.h>

#include <string>

namespace robotperf::tracing::detail {

void note_session(const std::string& name);
void forget_session();
void note_started_daemon(pid_t pid);
void forget_started_daemon();

}  // namespace robotperf::tracing::detail
