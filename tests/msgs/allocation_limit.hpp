// Refuses large allocations while alive, so that a test sees code that would allocate what a
// forged size claims get std::bad_alloc (and fail its EXPECT_THROW) instead of the memory. Linked
// into a test binary with allocation_limit.cpp, which replaces the global operator new.
#pragma once

#include <cstddef>

namespace robotperf::testing {

class AllocationLimit {
 public:
  // While this lives, operator new throws std::bad_alloc for any one request over `bytes`.
  explicit AllocationLimit(std::size_t bytes);
  ~AllocationLimit();
  AllocationLimit(const AllocationLimit&) = delete;
  AllocationLimit& operator=(const AllocationLimit&) = delete;

  // The largest single request made while it lived, refused or not.
  std::size_t largest() const;
};

}  // namespace robotperf::testing
