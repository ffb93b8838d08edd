#pragma once

// Pairing the inputs of one frame (left + right image, depth + colour + CameraInfo) by their
// header stamps, as ROS nodes do with message_filters. Inputs that cannot be paired are dropped
// and counted, never mixed into another frame's set.

#include <algorithm>
#include <array>
#include <cstdint>
#include <deque>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <stdexcept>

namespace robotperf::plugin {

enum class SyncPolicy {
  // Only messages with identical stamps form a set (message_filters ExactTime).
  kExact,
  // Messages with nearby stamps form a set (in the spirit of message_filters ApproximateTime).
  kApproximate,
};

struct SyncOptions {
  SyncPolicy policy = SyncPolicy::kExact;
  // Exact: incomplete stamps kept; approximate: messages kept per input.
  std::size_t queue_size = 10;
  // Approximate: the largest spread of stamps within one set.
  int64_t max_interval_ns = std::numeric_limits<int64_t>::max();
};

// N inputs, each stamped; calls back with one message of every input per set.
//
// Exact: a set is emitted as soon as every input has a message with the same stamp; stamps older
// than an emitted set are dropped (they can no longer complete in order); beyond queue_size
// incomplete stamps the oldest is dropped.
//
// Approximate: the pivot is the latest of the oldest queued message of each input. Once every
// input holds a message stamped at or after the pivot (later arrivals cannot come closer), the
// message of each input closest to the pivot forms the set, unless the set spans more than
// max_interval_ns, in which case the oldest queued message is dropped instead. Messages older than
// the chosen ones are dropped. With identical stamps a set is emitted on its last message's
// arrival, without waiting for the next frame.
//
// Not thread-safe: a node's callbacks never run concurrently.
template <std::size_t N>
class MessageSync {
 public:
  using Ptr = std::shared_ptr<const void>;
  using Set = std::array<Ptr, N>;
  using Callback = std::function<void(const Set&)>;

  MessageSync(SyncOptions options, Callback callback)
      : options_(options), callback_(std::move(callback)) {
    if (options_.queue_size == 0) throw std::invalid_argument("sync queue_size must be >= 1");
    if (options_.max_interval_ns < 0) throw std::invalid_argument("sync max_interval must be >= 0");
  }

  void add(std::size_t input, Ptr msg, int64_t stamp_ns) {
    if (input >= N) throw std::out_of_range("sync input index out of range");
    if (options_.policy == SyncPolicy::kExact) {
      add_exact(input, std::move(msg), stamp_ns);
    } else {
      add_approximate(input, std::move(msg), stamp_ns);
    }
  }

  // Messages of each input discarded without being part of an emitted set.
  const std::array<uint64_t, N>& dropped() const { return dropped_; }
  uint64_t dropped_total() const {
    uint64_t sum = 0;
    for (uint64_t d : dropped_) sum += d;
    return sum;
  }
  uint64_t emitted() const { return emitted_; }

 private:
  struct Pending {
    Set set;
    std::size_t present = 0;
  };
  struct Stamped {
    int64_t stamp_ns;
    Ptr msg;
  };

  void drop_pending(const Pending& p) {
    for (std::size_t i = 0; i < N; ++i) dropped_[i] += p.set[i] ? 1 : 0;
  }

  void add_exact(std::size_t input, Ptr msg, int64_t stamp_ns) {
    if (emitted_ > 0 && stamp_ns <= last_emitted_ns_) {
      ++dropped_[input];  // too late: its stamp was emitted or passed over already
      return;
    }
    Pending& p = pending_[stamp_ns];
    if (p.set[input]) {
      ++dropped_[input];  // a second message with the same stamp replaces the first
    } else {
      ++p.present;
    }
    p.set[input] = std::move(msg);
    if (p.present == N) {
      const Set set = std::move(p.set);
      auto last = pending_.upper_bound(stamp_ns);
      for (auto it = pending_.begin(); it != last; ++it) {
        if (it->first != stamp_ns) drop_pending(it->second);
      }
      pending_.erase(pending_.begin(), last);
      emit(set, stamp_ns);
      return;
    }
    if (pending_.size() > options_.queue_size) {
      drop_pending(pending_.begin()->second);
      pending_.erase(pending_.begin());
    }
  }

  void add_approximate(std::size_t input, Ptr msg, int64_t stamp_ns) {
    auto& queue = queues_[input];
    if ((!queue.empty() && stamp_ns < queue.back().stamp_ns) ||
        (emitted_ > 0 && stamp_ns < chosen_ns_[input])) {
      ++dropped_[input];  // out of order: it could only pair with frames already gone
      return;
    }
    queue.push_back({stamp_ns, std::move(msg)});
    if (queue.size() > options_.queue_size) {
      queue.pop_front();
      ++dropped_[input];
    }
    while (try_emit_approximate()) {
    }
  }

  bool try_emit_approximate() {
    int64_t pivot = std::numeric_limits<int64_t>::min();
    for (const auto& q : queues_) {
      if (q.empty()) return false;
      pivot = std::max(pivot, q.front().stamp_ns);
    }
    std::array<std::size_t, N> chosen{};
    int64_t lo = std::numeric_limits<int64_t>::max();
    int64_t hi = std::numeric_limits<int64_t>::min();
    for (std::size_t i = 0; i < N; ++i) {
      const auto& q = queues_[i];
      if (q.back().stamp_ns < pivot) return false;  // a closer one may still come
      std::size_t best = 0;
      for (std::size_t j = 1; j < q.size(); ++j) {
        if (distance(q[j].stamp_ns, pivot) < distance(q[best].stamp_ns, pivot)) best = j;
      }
      chosen[i] = best;
      lo = std::min(lo, q[best].stamp_ns);
      hi = std::max(hi, q[best].stamp_ns);
    }
    if (static_cast<uint64_t>(hi) - static_cast<uint64_t>(lo) >
        static_cast<uint64_t>(options_.max_interval_ns)) {
      // No acceptable set contains the oldest message: give it up.
      std::size_t oldest = 0;
      for (std::size_t i = 1; i < N; ++i) {
        if (queues_[i].front().stamp_ns < queues_[oldest].front().stamp_ns) oldest = i;
      }
      queues_[oldest].pop_front();
      ++dropped_[oldest];
      return true;
    }
    Set set;
    for (std::size_t i = 0; i < N; ++i) {
      auto& q = queues_[i];
      dropped_[i] += chosen[i];
      set[i] = std::move(q[chosen[i]].msg);
      chosen_ns_[i] = q[chosen[i]].stamp_ns;
      q.erase(q.begin(), q.begin() + static_cast<std::ptrdiff_t>(chosen[i]) + 1);
    }
    emit(set, hi);
    return true;
  }

  static uint64_t distance(int64_t a, int64_t b) {
    return a > b ? static_cast<uint64_t>(a) - static_cast<uint64_t>(b)
                 : static_cast<uint64_t>(b) - static_cast<uint64_t>(a);
  }

  void emit(const Set& set, int64_t stamp_ns) {
    ++emitted_;
    last_emitted_ns_ = stamp_ns;
    callback_(set);
  }

  SyncOptions options_;
  Callback callback_;
  std::map<int64_t, Pending> pending_;         // exact
  std::array<std::deque<Stamped>, N> queues_;  // approximate
  std::array<int64_t, N> chosen_ns_{};         // approximate: stamp last used per input
  std::array<uint64_t, N> dropped_{};
  uint64_t emitted_ = 0;
  int64_t last_emitted_ns_ = 0;
};

}  // namespace robotperf::plugin
