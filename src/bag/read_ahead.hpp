// Private to the bag piece: the work a reader does on each of its units in order (decompressing
// an MCAP chunk and checking its CRC), done ahead of the reading thread by a pool of workers.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <span>
#include <thread>
#include <vector>

namespace robotperf::bag {

// The threads that read_ahead_threads = 0 stands for: one per online CPU, at least 1.
std::size_t online_cpus();

class ReadAhead {
 public:
  using Buffer = std::shared_ptr<std::vector<uint8_t>>;
  // Prepares unit `unit`: returns its bytes, which lie in `buffer` (filled here) or elsewhere
  // for as long as the ReadAhead. Called from any thread, several units at once.
  using Prepare = std::function<std::span<const uint8_t>(std::size_t unit, std::vector<uint8_t>&)>;

  struct Prepared {
    Buffer buffer;  // holds `bytes` when they were written into it; give it back when done
    std::span<const uint8_t> bytes;
  };

  // Units 0 .. units-1 are prepared by `workers` threads (none: each on the thread that takes
  // it), at most `ahead` of them at a time beyond those taken: memory stays at `ahead` buffers
  // in flight, and `ahead` + 1 kept for reuse, whatever the number of units.
  ReadAhead(std::size_t units, std::size_t workers, std::size_t ahead, Prepare prepare);
  // Stops the workers and waits for them: each finishes at most the unit it is on.
  ~ReadAhead();
  ReadAhead(const ReadAhead&) = delete;
  ReadAhead& operator=(const ReadAhead&) = delete;

  // The next unit, in order, waiting for it (or preparing it here if no worker has started it).
  // Rethrows what preparing it threw, after which the unit after it is next.
  Prepared take();
  // A buffer no longer referred to, for a later unit to reuse: a large buffer allocated afresh
  // costs a page fault per 4 KiB.
  void give_back(Buffer buffer);

  std::size_t workers() const { return threads_.size(); }
  // The most units that were ever prepared (or being prepared) and not yet taken.
  std::size_t most_in_flight() const;

 private:
  struct Slot {
    Buffer buffer;
    std::span<const uint8_t> bytes;
    std::exception_ptr error;
    bool done = false;
  };

  void work();
  // Claims the next unit if the read-ahead allows; call with the lock held.
  bool claim(std::size_t& unit);
  // Prepares `unit` into its slot, the lock released meanwhile; call with the lock held.
  void prepare(std::size_t unit, std::unique_lock<std::mutex>& lock);
  Buffer spare_buffer();

  const std::size_t units_;
  const std::size_t ahead_;
  const Prepare prepare_;
  mutable std::mutex mutex_;
  std::condition_variable can_claim_;  // workers wait for a unit to claim, or for the end
  std::condition_variable done_;       // the taker waits for its unit
  std::vector<Slot> slots_;            // unit u in slots_[u % ahead_]
  std::size_t next_taken_ = 0;
  std::size_t next_claimed_ = 0;
  std::size_t most_in_flight_ = 0;
  std::vector<Buffer> spare_;  // at most ahead_ + 1
  bool stopping_ = false;
  std::vector<std::thread> threads_;  // last: started once everything above is ready
};

}  // namespace robotperf::bag
