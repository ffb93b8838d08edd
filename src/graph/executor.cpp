#include "robotperf/graph/executor.hpp"

#include <algorithm>
#include <stdexcept>

namespace robotperf::graph {

Executor::Executor(std::size_t threads) : threads_(threads) {
  if (threads_ == 0) throw std::invalid_argument("an executor needs at least one thread");
}

Executor::~Executor() {
  stop();
}

void Executor::add_node(std::shared_ptr<Node> node) {
  node->set_wake_signal(signal_);
  std::lock_guard lock(mutex_);
  nodes_.push_back(std::move(node));
}

void Executor::spin() {
  std::vector<std::thread> helpers;
  for (std::size_t i = 1; i < threads_; ++i) helpers.emplace_back([this] { run_worker(); });
  run_worker();
  for (auto& t : helpers) t.join();
  std::lock_guard lock(mutex_);
  if (error_) std::rethrow_exception(error_);
}

void Executor::start() {
  if (background_.joinable()) throw std::logic_error("executor already started");
  background_ = std::thread([this] {
    try {
      spin();
    } catch (...) {
      // Kept in error_ for the owner, who polls error() or gets it from stop().
    }
  });
}

void Executor::stop() {
  cancel();
  if (background_.joinable()) background_.join();
}

void Executor::cancel() {
  signal_->stop();
}

std::exception_ptr Executor::error() const {
  std::lock_guard lock(mutex_);
  return error_;
}

void Executor::run_worker() {
  while (!signal_->stopped()) {
    const uint64_t seen = signal_->generation();
    bool did_work = false;
    int64_t deadline = INT64_MAX;
    try {
      did_work = run_ready_work(deadline);
    } catch (...) {
      {
        std::lock_guard lock(mutex_);
        if (!error_) error_ = std::current_exception();
      }
      signal_->stop();
      return;
    }
    if (!did_work) signal_->wait(seen, deadline);
  }
}

// One round: for each node whose callbacks are free, run its due timers and
// one message per subscription. Returns whether any callback ran, and in
// `next_deadline` the earliest timer deadline of the nodes it visited (a node
// busy on another thread is rescanned by that thread when it is done).
bool Executor::run_ready_work(int64_t& next_deadline) {
  std::vector<std::shared_ptr<Node>> nodes;
  {
    std::lock_guard lock(mutex_);
    nodes = nodes_;
  }
  bool did_work = false;
  for (const auto& node : nodes) {
    std::unique_lock exclusive(node->callback_mutex(), std::try_to_lock);
    if (!exclusive.owns_lock()) continue;  // another thread is in this node
    for (const auto& entity : node->entities()) {
      try {
        did_work |= entity->execute();
        next_deadline = std::min(next_deadline, entity->next_deadline_ns());
      } catch (const std::exception& e) {
        throw NodeError(node->name(), e.what());
      }
    }
  }
  return did_work;
}

}  // namespace robotperf::graph
