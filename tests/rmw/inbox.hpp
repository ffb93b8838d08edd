// Blocking helpers for tests of a Transport: wait for messages and for
// discovery with a deadline instead of sleeping.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <thread>

#include "robotperf/rmw/transport.hpp"

namespace robotperf::rmw::testing {

// Generous: the tests run in parallel on small, noisy machines.
inline constexpr std::chrono::seconds kTimeout{60};

// Counts the subscription's on_ready calls so that a taker can sleep until
// the next one. Must outlive the subscription that calls it.
class Inbox {
 public:
  std::function<void()> on_ready() {
    return [this] {
      {
        std::lock_guard lock(mutex_);
        ++notifications_;
      }
      ready_.notify_all();
    };
  }

  // The next message of `sub`, or nullptr when none arrives within `timeout`.
  MessagePtr take(SubscriptionHandle& sub, MessageInfo* info = nullptr,
                  std::chrono::milliseconds timeout = kTimeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    std::unique_lock lock(mutex_);
    while (true) {
      const uint64_t seen = notifications_;
      lock.unlock();
      if (MessagePtr msg = sub.take(info)) return msg;
      lock.lock();
      if (!ready_.wait_until(lock, deadline, [&] { return notifications_ != seen; })) {
        return nullptr;
      }
    }
  }

 private:
  std::mutex mutex_;
  std::condition_variable ready_;
  uint64_t notifications_ = 0;
};

// Polls `condition` until it holds or `timeout` passes; discovery has no
// notification in the Transport interface.
inline bool wait_until(const std::function<bool()>& condition,
                       std::chrono::milliseconds timeout = kTimeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!condition()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return true;
}

}  // namespace robotperf::rmw::testing
