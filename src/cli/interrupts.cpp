#include "interrupts.hpp"

#include <unistd.h>

#include "robotperf/harness/run.hpp"
#include "robotperf/tracing/leftovers.hpp"

namespace robotperf::cli {

std::atomic<int> g_interrupted{0};

namespace {

void on_interrupt(int signal_number) {
  if (g_interrupted.exchange(signal_number) != 0) {
    constexpr char kMessage[] = "\nrobotperf: interrupted again: stopping now\n";
    (void)!write(STDERR_FILENO, kMessage, sizeof kMessage - 1);
    harness::kill_node_processes();
    tracing::clean_up_at_forced_exit();
    _exit(128 + signal_number);
  }
  constexpr char kMessage[] =
      "\nrobotperf: interrupted: ending the run, keeping what it measured (again to force)\n";
  (void)!write(STDERR_FILENO, kMessage, sizeof kMessage - 1);
}

}  // namespace

InterruptHandling::InterruptHandling() {
  struct sigaction action {};
  action.sa_handler = on_interrupt;
  // While the handler runs, another of these signals waits: a forced exit's clean-up is not
  // started twice.
  sigemptyset(&action.sa_mask);
  for (const int signal_number : kHandled) sigaddset(&action.sa_mask, signal_number);
  for (std::size_t i = 0; i < kHandled.size(); ++i) sigaction(kHandled[i], &action, &previous_[i]);
}

InterruptHandling::~InterruptHandling() {
  for (std::size_t i = 0; i < kHandled.size(); ++i) sigaction(kHandled[i], &previous_[i], nullptr);
}

}  // namespace robotperf::cli
