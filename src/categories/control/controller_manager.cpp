#include "robotperf/control/controller_manager.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/prctl.h>
#include <time.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <future>
#include <stdexcept>

namespace robotperf::control {
namespace {

int64_t monotonic_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}

void sleep_until(int64_t deadline_ns) {
  const timespec ts{static_cast<time_t>(deadline_ns / 1'000'000'000),
                    static_cast<long>(deadline_ns % 1'000'000'000)};
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

// Applies the loop thread's CPU and priority; returns what went wrong, empty when nothing did.
std::string apply_scheduling(const LoopConfig& config) {
  if (config.cpu >= 0) {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(static_cast<unsigned>(config.cpu), &set);
    if (const int e = pthread_setaffinity_np(pthread_self(), sizeof set, &set); e != 0) {
      return config.name + ": cannot pin the control loop to CPU " + std::to_string(config.cpu) +
             ": " + std::strerror(e) + " (is it online and allowed to this process? see nproc)";
    }
  }
  if (config.rt_priority != 0) {
    const sched_param param{config.rt_priority};
    if (const int e = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param); e != 0) {
      return config.name + ": cannot run the control loop at SCHED_FIFO priority " +
             std::to_string(config.rt_priority) + ": " + std::strerror(e) +
             " (needs root, CAP_SYS_NICE or an rtprio limit; or leave rt_priority at 0)";
    }
  }
  // The default 50 us timer slack would show up as period jitter.
  prctl(PR_SET_TIMERSLACK, 1UL, 0, 0, 0);
  return {};
}

}  // namespace

ControllerManager::ControllerManager(std::unique_ptr<SimulatedHardware> hardware, LoopConfig config)
    : hardware_(std::move(hardware)), config_(std::move(config)) {
  if (!(config_.update_rate_hz > 0) || !std::isfinite(config_.update_rate_hz))
    throw std::invalid_argument(config_.name + ": update_rate must be a positive number");
  if (config_.rt_priority < 0 || config_.rt_priority > 99)
    throw std::invalid_argument(config_.name + ": rt_priority must be 0 (off) to 99");
  if (config_.cpu >= CPU_SETSIZE)
    throw std::invalid_argument(config_.name + ": cpu " + std::to_string(config_.cpu) +
                                " is out of range");
  period_ns_ = std::max<int64_t>(1, std::llround(1e9 / config_.update_rate_hz));
  // Everything the loop records is allocated (and touched) now.
  records_.assign(config_.cycle_capacity, CycleRecord{});
  writes_.assign(config_.cycle_capacity, CommandWrite{});
}

ControllerManager::~ControllerManager() {
  stop();
}

void ControllerManager::add_controller(std::shared_ptr<Controller> controller) {
  if (running()) throw std::logic_error(config_.name + ": add controllers before start()");
  hardware_->claim(controller->command_interfaces());
  for (const auto& s : controller->state_interfaces()) hardware_->state_interface(s);
  controller->activate(*hardware_);
  controllers_.push_back(std::move(controller));
}

void ControllerManager::set_after_write(std::function<void(const UpdateContext&)> callback) {
  after_write_ = std::move(callback);
}

void ControllerManager::start() {
  if (running()) return;
  stop_ = false;
  std::promise<std::string> setup;
  auto result = setup.get_future();
  thread_ = std::thread([this, &setup] {
    const std::string error = apply_scheduling(config_);
    // The first deadline one period ahead: the loop starts on its own schedule.
    const int64_t start_ns = monotonic_ns() + period_ns_;
    setup.set_value(error);
    if (error.empty()) loop(start_ns);
  });
  if (std::string error = result.get(); !error.empty()) {
    thread_.join();
    throw std::runtime_error(error);
  }
}

void ControllerManager::stop() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
}

void ControllerManager::loop(int64_t start_ns) {
  // Absolute deadlines start + k * period: a late cycle does not shift the ones after it.
  int64_t deadline = start_ns;
  while (!stop_.load(std::memory_order_relaxed)) {
    sleep_until(deadline);
    const int64_t done = run_cycle(deadline, monotonic_ns());
    deadline += period_ns_;
    // A cycle that ended after the next deadline had passed, woken late or overrunning: the
    // periods already over are skipped and counted as missed, rather than run back to back with
    // a near-zero period (as ros2_control's loop does, checking the clock after the cycle); the
    // grid, and so the phase, is kept.
    if (done >= deadline) {
      const int64_t skipped = (done - deadline) / period_ns_ + 1;
      deadline += skipped * period_ns_;
      misses_ += static_cast<uint64_t>(skipped);
    }
  }
}

void ControllerManager::cycle(int64_t now_ns) {
  run_cycle(now_ns, now_ns);
}

int64_t ControllerManager::run_cycle(int64_t deadline_ns, int64_t now_ns) {
  UpdateContext ctx;
  ctx.now_ns = now_ns;
  ctx.period_s = previous_now_ns_ < 0 ? static_cast<double>(period_ns_) * 1e-9
                                      : static_cast<double>(now_ns - previous_now_ns_) * 1e-9;
  previous_now_ns_ = now_ns;
  ctx.cycle = cycles_;
  hardware_->read();
  // What was written in earlier cycles is what the state just read shows.
  ctx.observed_command = actuated_command_;
  const int64_t read_end = monotonic_ns();
  int64_t taken = kNoCommand;
  for (const auto& c : controllers_) {
    plugin::trace_controller_update_begin(config_.name.c_str(), c->name().c_str(), ctx.cycle,
                                          ctx.observed_command);
    const int64_t id = c->update(ctx);
    plugin::trace_controller_update_end(config_.name.c_str(), c->name().c_str(), ctx.cycle, id);
    if (id != kNoCommand) taken = id;
  }
  const int64_t update_end = monotonic_ns();
  hardware_->write(ctx.period_s);
  const int64_t write_end = monotonic_ns();
  if (taken != kNoCommand) {
    actuated_command_ = taken;
    if (write_count_ < writes_.size()) {
      writes_[write_count_++] = {taken, write_end};
    } else {
      ++writes_dropped_;
    }
  }
  if (after_write_) after_write_(ctx);
  // Late when the work ends after the next period has begun.
  if (write_end > deadline_ns + period_ns_) ++misses_;
  if (record_count_ < records_.size()) {
    records_[record_count_++] = {deadline_ns, now_ns, read_end, update_end, write_end};
  }
  ++cycles_;
  return write_end;
}

LoopReport ControllerManager::report() const {
  LoopReport r;
  r.name = config_.name;
  r.update_rate_hz = config_.update_rate_hz;
  r.cpu = config_.cpu;
  r.rt_priority = config_.rt_priority;
  r.cycles = cycles_;
  r.deadline_misses = misses_;
  r.records.assign(records_.begin(), records_.begin() + static_cast<std::ptrdiff_t>(record_count_));
  r.writes.assign(writes_.begin(), writes_.begin() + static_cast<std::ptrdiff_t>(write_count_));
  r.writes_dropped = writes_dropped_;
  return r;
}

}  // namespace robotperf::control
