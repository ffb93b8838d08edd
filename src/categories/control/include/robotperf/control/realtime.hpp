// Handing data between the real-time control loop and ordinary threads without blocking the loop
// (the roles of realtime_tools' RealtimeBuffer and RealtimePublisher in ROS 2).
#pragma once

#include <pthread.h>
#include <sched.h>

#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>

namespace robotperf::control {

// One slot for the newest command: written by a subscription thread, taken by the loop. The loop
// only try-locks (a writer holding the lock delays the command by one cycle, never the loop), and
// takes by swapping, so the command it replaces is released by the next writer, not in the loop.
template <class T>
class CommandBuffer {
 public:
  void write(std::shared_ptr<const T> command) {
    std::lock_guard lock(mutex_);
    pending_ = std::move(command);
    fresh_ = true;
  }
  // Replaces `current` with the newest command when one arrived since the last take; returns
  // whether it did.
  bool take(std::shared_ptr<const T>& current) {
    std::unique_lock lock(mutex_, std::try_to_lock);
    if (!lock.owns_lock() || !fresh_) return false;
    current.swap(pending_);
    fresh_ = false;
    return true;
  }

 private:
  std::mutex mutex_;
  std::shared_ptr<const T> pending_;
  bool fresh_ = false;
};

// A message filled by the loop and published by a thread of its own. The loop fills msg() only
// after try_lock() succeeded and then calls unlock_and_publish(); while the previous message is
// still being published try_lock() fails and the loop skips this publication.
template <class T>
class RealtimePublisher {
 public:
  explicit RealtimePublisher(std::function<void(const T&)> publish)
      : publish_(std::move(publish)), thread_([this] { run(); }) {}
  ~RealtimePublisher() {
    {
      std::lock_guard lock(mutex_);
      stop_ = true;
    }
    cv_.notify_one();
    thread_.join();
  }
  RealtimePublisher(const RealtimePublisher&) = delete;
  RealtimePublisher& operator=(const RealtimePublisher&) = delete;

  // Non-real-time setup (sizes, names) before the loop starts.
  T& msg() { return msg_; }
  bool try_lock() {
    if (!mutex_.try_lock()) return false;
    if (ready_) {  // the publisher thread has not taken the previous one yet
      mutex_.unlock();
      return false;
    }
    return true;
  }
  void unlock_and_publish() {
    ready_ = true;
    mutex_.unlock();
    cv_.notify_one();
  }

 private:
  void run() {
    // On the normal scheduler, SCHED_BATCH: this thread, woken by the loop every publication,
    // must not preempt the loop on wake-up (CFS wake-up preemption) and delay the rest of its
    // cycle. Real-time configurations are left as they are.
    int policy = 0;
    sched_param param{};
    if (pthread_getschedparam(pthread_self(), &policy, &param) == 0 && policy == SCHED_OTHER) {
      param.sched_priority = 0;
      pthread_setschedparam(pthread_self(), SCHED_BATCH, &param);
    }
    std::unique_lock lock(mutex_);
    while (true) {
      cv_.wait(lock, [this] { return ready_ || stop_; });
      if (ready_) {
        publish_(msg_);  // copies msg_: allocation happens here, outside the loop
        ready_ = false;
      }
      if (stop_) return;
    }
  }

  std::function<void(const T&)> publish_;
  std::mutex mutex_;
  std::condition_variable cv_;
  T msg_{};
  bool ready_ = false;
  bool stop_ = false;
  std::thread thread_;
};

}  // namespace robotperf::control
