#include "robotperf/graph/executor.hpp"

#include <algorithm>
#include <stdexcept>

namespace robotperf::graph {

Executor::Executor(std::size_t threads, WaitMode wait) : threads_(threads), wait_(wait) {
  if (threads_ == 0) throw std::invalid_argument("an executor needs at least one thread");
  busy_ = std::make_unique<Busy[]>(threads_);
}

Executor::~Executor() {
  stop();
}

void Executor::add_node(std::shared_ptr<Node> node) {
  {
    std::lock_guard lock(mutex_);
    nodes_.push_back(node);
  }
  // Only then the wake-up: a worker woken before would scan without the node, then sleep.
  node->set_wake_signal(signal_);
}

void Executor::spin() {
  std::vector<std::thread> helpers;
  for (std::size_t i = 1; i < threads_; ++i)
    helpers.emplace_back([this, i] { run_worker(busy_[i]); });
  run_worker(busy_[0]);
  for (auto& t : helpers) t.join();
  std::lock_guard lock(mutex_);
  if (error_) std::rethrow_exception(error_);
}

void Executor::start() {
  if (background_.joinable()) throw std::logic_error("executor already started");
  finished_ = false;
  background_ = std::thread([this] {
    try {
      spin();
    } catch (...) {
      // Kept in error_ for the owner, who polls error() or gets it from stop().
    }
    std::lock_guard lock(mutex_);
    finished_ = true;
    finished_cv_.notify_all();
  });
}

void Executor::stop() {
  cancel();
  if (background_.joinable()) background_.join();
}

void Executor::cancel() {
  signal_->stop();
}

bool Executor::stop_within(std::chrono::nanoseconds timeout) {
  cancel();
  if (!background_.joinable()) return true;
  {
    std::unique_lock lock(mutex_);
    if (!finished_cv_.wait_for(lock, timeout, [&] { return finished_; })) {
      background_.detach();
      return false;
    }
  }
  background_.join();
  return true;
}

std::optional<RunningCallback> Executor::running_longer_than(int64_t limit_ns,
                                                             int64_t now_ns) const {
  std::optional<RunningCallback> longest;
  for (std::size_t i = 0; i < threads_; ++i) {
    const int64_t since = busy_[i].since_ns.load(std::memory_order_acquire);
    const Node* node = busy_[i].node.load(std::memory_order_acquire);
    if (since == 0 || node == nullptr || now_ns - since <= limit_ns) continue;
    if (!longest || now_ns - since > longest->running_ns)
      longest = RunningCallback{node->name(), now_ns - since};
  }
  return longest;
}

std::exception_ptr Executor::error() const {
  std::lock_guard lock(mutex_);
  return error_;
}

void Executor::run_worker(Busy& busy) {
  while (!signal_->stopped()) {
    const uint64_t seen = signal_->generation();
    bool did_work = false;
    int64_t deadline = INT64_MAX;
    try {
      did_work = run_ready_work(deadline, busy);
    } catch (...) {
      {
        std::lock_guard lock(mutex_);
        if (!error_) error_ = std::current_exception();
      }
      signal_->stop();
      return;
    }
    if (did_work) continue;
    if (wait_ == WaitMode::kSpin) {
      signal_->spin_wait(seen, deadline);
    } else {
      signal_->wait(seen, deadline);
    }
  }
}

// One round: for each node whose callbacks are free, run its due timers and
// one message per subscription. Returns whether any callback ran, and in
// `next_deadline` the earliest timer deadline of the nodes it visited (a node
// busy on another thread is rescanned by that thread when it is done).
bool Executor::run_ready_work(int64_t& next_deadline, Busy& busy) {
  std::vector<std::shared_ptr<Node>> nodes;
  {
    std::lock_guard lock(mutex_);
    nodes = nodes_;
  }
  bool did_work = false;
  for (const auto& node : nodes) {
    std::unique_lock exclusive(node->callback_mutex(), std::try_to_lock);
    if (!exclusive.owns_lock()) continue;  // another thread is in this node
    // Nodes stay alive while the executor holds them: a watchdog may read the name.
    busy.node.store(node.get(), std::memory_order_release);
    for (const auto& entity : node->entities()) {
      busy.since_ns.store(rmw::steady_now_ns(), std::memory_order_release);
      try {
        did_work |= entity->execute();
        next_deadline = std::min(next_deadline, entity->next_deadline_ns());
      } catch (const std::exception& e) {
        busy.since_ns.store(0, std::memory_order_release);
        throw NodeError(node->name(), e.what());
      }
      busy.since_ns.store(0, std::memory_order_release);
    }
  }
  return did_work;
}

}  // namespace robotperf::graph
