// Private to the perception category: the output message a node writes its next frame into.
#pragma once

#include <atomic>
#include <memory>

namespace robotperf::perception {

// Output messages of megabytes: the last one published is reused once every subscriber has let
// go of it (like a ROS 2 loaned message), so the kernel writes into memory already allocated and
// sized, instead of a fresh buffer that is page-faulted and zero-filled (resize()) on every frame
// before the kernel overwrites it. A message still held anywhere is never written again: the
// node gets a new one.
template <class T>
class OutputPool {
 public:
  std::shared_ptr<T> acquire() {
    // use_count 1: only we hold it, and nobody can take a new reference from us.
    if (last_ && last_.use_count() == 1) {
      // The last holder's reads happened before it let go (a release decrement): seen here.
      std::atomic_thread_fence(std::memory_order_acquire);
      return last_;
    }
    last_ = std::make_shared<T>();
    return last_;
  }

 private:
  std::shared_ptr<T> last_;
};

}  // namespace robotperf::perception
