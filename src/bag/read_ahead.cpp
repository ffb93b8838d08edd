#include "read_ahead.hpp"

#include <unistd.h>

#include <algorithm>
#include <system_error>

namespace robotperf::bag {

std::size_t online_cpus() {
  const long n = ::sysconf(_SC_NPROCESSORS_ONLN);
  return n > 0 ? static_cast<std::size_t>(n) : 1;
}

ReadAhead::ReadAhead(std::size_t units, std::size_t workers, std::size_t ahead, Prepare prepare)
    : units_(units),
      ahead_(std::max<std::size_t>(ahead, 1)),
      prepare_(std::move(prepare)),
      slots_(ahead_) {
  workers = std::min(workers, units);
  threads_.reserve(workers);
  for (std::size_t i = 0; i < workers; ++i) {
    try {
      threads_.emplace_back([this] { work(); });
    } catch (const std::system_error&) {
      break;  // no more threads to be had: the taker prepares what the others do not
    }
  }
}

ReadAhead::~ReadAhead() {
  {
    const std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  can_claim_.notify_all();
  for (std::thread& t : threads_) t.join();
}

bool ReadAhead::claim(std::size_t& unit) {
  if (next_claimed_ >= units_ || next_claimed_ >= next_taken_ + ahead_) return false;
  unit = next_claimed_++;
  most_in_flight_ = std::max(most_in_flight_, next_claimed_ - next_taken_);
  return true;
}

void ReadAhead::prepare(std::size_t unit, std::unique_lock<std::mutex>& lock) {
  Buffer buffer = spare_buffer();
  lock.unlock();
  Slot result;
  try {
    result.bytes = prepare_(unit, *buffer);
  } catch (...) {
    result.error = std::current_exception();
  }
  result.done = true;
  lock.lock();
  if (!buffer->empty() && result.bytes.data() == buffer->data()) {
    result.buffer = std::move(buffer);
  } else if (spare_.size() <= ahead_) {
    spare_.push_back(std::move(buffer));
  }
  slots_[unit % ahead_] = std::move(result);
  done_.notify_one();
}

void ReadAhead::work() {
  std::unique_lock lock(mutex_);
  for (;;) {
    std::size_t unit = 0;
    while (!stopping_ && !claim(unit)) can_claim_.wait(lock);
    if (stopping_) return;
    prepare(unit, lock);
  }
}

ReadAhead::Prepared ReadAhead::take() {
  std::unique_lock lock(mutex_);
  Slot& slot = slots_[next_taken_ % ahead_];
  // No worker has started this unit (there are none, or they are still waking up): waiting
  // for one would only delay it.
  if (std::size_t unit = 0; next_claimed_ == next_taken_ && claim(unit)) prepare(unit, lock);
  done_.wait(lock, [&] { return slot.done; });
  Slot taken = std::move(slot);
  slot = Slot{};
  ++next_taken_;
  lock.unlock();
  can_claim_.notify_one();
  if (taken.error) std::rethrow_exception(taken.error);
  return {std::move(taken.buffer), taken.bytes};
}

void ReadAhead::give_back(Buffer buffer) {
  const std::lock_guard lock(mutex_);
  if (spare_.size() <= ahead_) spare_.push_back(std::move(buffer));
}

std::size_t ReadAhead::most_in_flight() const {
  const std::lock_guard lock(mutex_);
  return most_in_flight_;
}

ReadAhead::Buffer ReadAhead::spare_buffer() {
  if (spare_.empty()) return std::make_shared<std::vector<uint8_t>>();
  Buffer buffer = std::move(spare_.back());
  spare_.pop_back();
  return buffer;
}

}  // namespace robotperf::bag
