// The c3 control loop (controller manager + forward position command controller + joint state
// broadcaster on the simulated RRBot multi-interface) at 1 kHz: controller update duration,
// period jitter and deadline misses, first on the normal scheduler, then at a SCHED_FIFO priority
// where the machine permits it. Targets: zero deadline misses and p99 period jitter <= 100 us
// without real-time priority. A bare clock_nanosleep loop at the same rate runs first: the floor
// this machine's scheduler and timers set, so that the loop's figures can be read against it.
//
//   bench_control [--seconds S] [--rate HZ] [--rt-priority N] [--cpu N]
#include <sys/mman.h>
#include <sys/prctl.h>
#include <time.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "robotperf/control/controller_manager.hpp"
#include "robotperf/control/forward_command_controller.hpp"
#include "robotperf/metrics/latency_stats.hpp"
#include "this_build.hpp"

namespace {

using namespace robotperf;

struct Options {
  double seconds = 60.0;
  double rate_hz = 1000.0;
  int rt_priority = 80;
  int cpu = -1;
};

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument(a + " needs a value");
      return argv[++i];
    };
    if (a == "--seconds") {
      o.seconds = std::stod(value());
    } else if (a == "--rate") {
      o.rate_hz = std::stod(value());
    } else if (a == "--rt-priority") {
      o.rt_priority = std::stoi(value());
    } else if (a == "--cpu") {
      o.cpu = std::stoi(value());
    } else {
      throw std::invalid_argument("unknown option " + a +
                                  " (use --seconds S, --rate HZ, --rt-priority N, --cpu N)");
    }
  }
  if (!(o.seconds > 0) || !(o.rate_hz > 0)) throw std::invalid_argument("values must be positive");
  return o;
}

// Sleeps to absolute deadlines with nothing else to do, as the control loop's thread would (1 ns
// timer slack); returns the wake-up minus deadline statistics in microseconds.
metrics::SampleStats bare_sleep_floor(const Options& o) {
  prctl(PR_SET_TIMERSLACK, 1UL);
  const auto period_ns = static_cast<int64_t>(1e9 / o.rate_hz);
  const auto cycles = static_cast<std::size_t>(o.seconds * o.rate_hz);
  std::vector<double> wake(cycles);
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  int64_t deadline = now.tv_sec * 1'000'000'000LL + now.tv_nsec;
  for (std::size_t k = 0; k < cycles; ++k) {
    deadline += period_ns;
    const timespec at{static_cast<time_t>(deadline / 1'000'000'000),
                      static_cast<long>(deadline % 1'000'000'000)};
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &at, nullptr) == EINTR) {
    }
    clock_gettime(CLOCK_MONOTONIC, &now);
    wake[k] = static_cast<double>(now.tv_sec * 1'000'000'000LL + now.tv_nsec - deadline) / 1e3;
  }
  return metrics::compute_stats(wake);
}

// Runs the loop; returns false (after printing why) when the OS refused the scheduling.
bool run(const Options& o, int rt_priority) {
  control::LoopConfig config{"c3_loop", o.rate_hz, o.cpu, rt_priority,
                             static_cast<std::size_t>(o.seconds * o.rate_hz * 1.1 + 100)};
  control::ControllerManager manager(control::make_hardware({"rrbot_multi_interface"}), config);
  auto fcc = std::make_shared<control::ForwardCommandController>(
      "forward_position_controller", control::ForwardCommandControllerConfig{});
  manager.add_controller(fcc);
  // The broadcaster fills its message every cycle, as in c3; publishing goes nowhere.
  uint64_t published = 0;
  manager.add_controller(std::make_shared<control::JointStateBroadcaster>(
      "joint_state_broadcaster", std::vector<std::string>{"joint1", "joint2"},
      std::make_unique<control::RealtimePublisher<msgs::JointState>>(
          [&](const msgs::JointState&) { ++published; })));
  try {
    manager.start();
  } catch (const std::runtime_error& e) {
    std::printf("%s\n", e.what());
    return false;
  }
  // Commands at 100 Hz, as the c3 Playback sends them, each with its ID.
  const auto start = std::chrono::steady_clock::now();
  int64_t id = 1;
  for (auto next = start; next - start < std::chrono::duration<double>(o.seconds);
       next += std::chrono::milliseconds(10)) {
    std::this_thread::sleep_until(next);
    auto cmd = std::make_shared<msgs::Float64MultiArray>();
    const double v = 0.5 * std::sin(static_cast<double>(id) * 0.01 * M_PI);
    cmd->data = {v, -v};
    msgs::MessageTraits<msgs::Float64MultiArray>::set_id_ns(*cmd, id++);
    fcc->command(std::move(cmd));
  }
  manager.stop();
  const control::LoopReport r = manager.report();
  std::vector<double> update, cycle, jitter, wake;
  const double period_ns = 1e9 / o.rate_hz;
  for (std::size_t k = 0; k < r.records.size(); ++k) {
    const auto& c = r.records[k];
    update.push_back(static_cast<double>(c.update_end_ns - c.read_end_ns) / 1e3);
    cycle.push_back(static_cast<double>(c.write_end_ns - c.wake_ns) / 1e3);
    // Actual wake-up minus the scheduled (absolute) deadline: never negative.
    wake.push_back(static_cast<double>(c.wake_ns - c.deadline_ns) / 1e3);
    if (k > 0) {
      jitter.push_back(
          std::abs(static_cast<double>(c.wake_ns - r.records[k - 1].wake_ns) - period_ns) / 1e3);
    }
  }
  const auto u = metrics::compute_stats(update);
  const auto cy = metrics::compute_stats(cycle);
  const auto j = metrics::compute_stats(jitter);
  const auto w = metrics::compute_stats(wake);
  std::printf("%-34s %8llu cycles, %llu commands written, %llu states published\n",
              rt_priority ? ("SCHED_FIFO " + std::to_string(rt_priority)).c_str()
                          : "normal scheduler (SCHED_OTHER)",
              static_cast<unsigned long long>(r.cycles),
              static_cast<unsigned long long>(r.writes.size()),
              static_cast<unsigned long long>(published));
  std::printf("  controller update (us)   mean %7.2f  p99 %8.2f  max %8.2f\n", u.mean, u.p99,
              u.max);
  std::printf("  cycle r-u-w (us)         mean %7.2f  p99 %8.2f  max %8.2f\n", cy.mean, cy.p99,
              cy.max);
  std::printf(
      "  wake - deadline (us)     mean %7.2f  p99 %8.2f  max %8.2f   target p99 <= 100: "
      "%.2fx of target %s\n",
      w.mean, w.p99, w.max, w.p99 / 100.0, w.p99 <= 100.0 ? "(met)" : "(MISSED)");
  std::printf(
      "  |period jitter| (us)     mean %7.2f  p99 %8.2f  max %8.2f   target p99 <= 100: "
      "%.2fx of target %s\n",
      j.mean, j.p99, j.max, j.p99 / 100.0, j.p99 <= 100.0 ? "(met)" : "(MISSED)");
  std::printf(
      "  deadline misses          %llu of %llu (%.4f %%)   target 0 %s\n",
      static_cast<unsigned long long>(r.deadline_misses), static_cast<unsigned long long>(r.cycles),
      r.cycles ? 100.0 * static_cast<double>(r.deadline_misses) / static_cast<double>(r.cycles)
               : 0.0,
      r.deadline_misses == 0 ? "(met)" : "(MISSED)");
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  robotperf::bench::warn_about_this_build();
  try {
    const Options o = parse(argc, argv);
    std::printf(
        "c3 loop: forward position command controller + joint state broadcaster, RRBot "
        "multi-interface, %.0f Hz for %.0f s per run%s\n",
        o.rate_hz, o.seconds, o.cpu >= 0 ? (", CPU " + std::to_string(o.cpu)).c_str() : "");
    const auto floor = bare_sleep_floor(o);
    std::printf(
        "machine floor: bare clock_nanosleep loop, wake - deadline (us) p50 %.2f  p99 %.2f  max "
        "%.2f (the loop cannot do better than this machine's timers and scheduler)\n",
        floor.p50, floor.p99, floor.max);
    run(o, 0);
    if (o.rt_priority > 0) {
      // The real-time variant also locks memory: no page fault may stall the loop.
      if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0) {
        std::printf("mlockall refused (%s): the real-time run has unlocked memory\n",
                    std::strerror(errno));
      }
      run(o, o.rt_priority);
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_control: %s\n", e.what());
    return 2;
  }
}
