#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "robotperf/graph/node.hpp"

namespace robotperf::graph {

// Runs the callbacks of its nodes. With one thread it is rclcpp's
// single-threaded executor; with more, callbacks of different nodes run in
// parallel while each node's own callbacks stay mutually exclusive.
// A callback of a node threw: the node's name, and what it threw.
class NodeError : public std::runtime_error {
 public:
  NodeError(std::string node, const std::string& what)
      : std::runtime_error("node '" + node + "': " + what), node_(std::move(node)) {}
  const std::string& node() const { return node_; }

 private:
  std::string node_;
};

// A callback that has been running for a while: the node it belongs to, and for how long.
struct RunningCallback {
  std::string node;
  int64_t running_ns = 0;
};

class Executor {
 public:
  // `wait`: how its threads wait when no callback is ready (WaitMode).
  explicit Executor(std::size_t threads = 1, WaitMode wait = WaitMode::kSleep);
  ~Executor();
  Executor(const Executor&) = delete;
  Executor& operator=(const Executor&) = delete;

  void add_node(std::shared_ptr<Node> node);

  // Runs callbacks on the calling thread (and threads-1 more) until cancel()
  // or until a callback throws. Rethrows the first callback exception, prefixed
  // with the node's name.
  void spin();
  // Runs spin() on background threads; stop() cancels and joins them.
  void start();
  void stop();
  void cancel();
  // Cancels and waits at most `timeout` for a background spin to end. False when a callback does
  // not return in time: its threads are detached and go on using this executor, its nodes and
  // their context, which the caller must then never destroy.
  bool stop_within(std::chrono::nanoseconds timeout);
  // The error that stopped a background spin, if any.
  std::exception_ptr error() const;
  // The longest-running callback at `now_ns` (steady clock), when one has run for longer than
  // `limit_ns`: what a watchdog looks at.
  std::optional<RunningCallback> running_longer_than(int64_t limit_ns, int64_t now_ns) const;

  std::size_t threads() const { return threads_; }

 private:
  // What one worker thread is running: the node, and since when (0: nothing).
  struct Busy {
    std::atomic<const Node*> node{nullptr};
    std::atomic<int64_t> since_ns{0};
  };

  void run_worker(Busy& busy);
  bool run_ready_work(int64_t& next_deadline, Busy& busy);

  std::size_t threads_;
  WaitMode wait_;
  std::unique_ptr<Busy[]> busy_;
  std::condition_variable finished_cv_;
  bool finished_ = false;  // the background spin ended
  std::shared_ptr<WakeSignal> signal_ = std::make_shared<WakeSignal>();
  mutable std::mutex mutex_;
  std::vector<std::shared_ptr<Node>> nodes_;
  std::exception_ptr error_;
  std::thread background_;
};

}  // namespace robotperf::graph
