// SIGINT, SIGTERM, SIGHUP (a dropped ssh session) and SIGQUIT during a run: the first ends the
// run cleanly (the harness polls g_interrupted), a second one ends the process at once.
#pragma once

#include <signal.h>

#include <array>
#include <atomic>

namespace robotperf::cli {

// The signal that interrupted the run, 0 while none has.
extern std::atomic<int> g_interrupted;

// The exit status of a run the signal in g_interrupted ended.
inline int interrupted_exit_code() {
  return 128 + g_interrupted.load();
}

// Handles those signals while it lives: the first sets g_interrupted, a second ends the process
// with 128 + its signal.
class InterruptHandling {
 public:
  InterruptHandling();
  ~InterruptHandling();
  InterruptHandling(const InterruptHandling&) = delete;
  InterruptHandling& operator=(const InterruptHandling&) = delete;

 private:
  static constexpr std::array kHandled = {SIGINT, SIGTERM, SIGHUP, SIGQUIT};
  std::array<struct sigaction, kHandled.size()> previous_{};
};

}  // namespace robotperf::cli
