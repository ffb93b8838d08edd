#pragma once

#include <cstddef>
#include <cstdint>
#include <exception>
#include <memory>
#include <mutex>
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

class Executor {
 public:
  explicit Executor(std::size_t threads = 1);
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
  // The error that stopped a background spin, if any.
  std::exception_ptr error() const;

  std::size_t threads() const { return threads_; }

 private:
  void run_worker();
  bool run_ready_work(int64_t& next_deadline);

  std::size_t threads_;
  std::shared_ptr<WakeSignal> signal_ = std::make_shared<WakeSignal>();
  mutable std::mutex mutex_;
  std::vector<std::shared_ptr<Node>> nodes_;
  std::exception_ptr error_;
  std::thread background_;
};

}  // namespace robotperf::graph
