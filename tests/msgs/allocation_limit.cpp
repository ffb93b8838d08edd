#include "allocation_limit.hpp"

#include <atomic>
#include <cstdlib>
#include <new>

namespace {

std::atomic<std::size_t> limit{0};  // 0: no limit
std::atomic<std::size_t> largest_request{0};

void* allocate(std::size_t bytes) {
  if (const std::size_t most = limit.load(std::memory_order_relaxed); most != 0) {
    std::size_t seen = largest_request.load(std::memory_order_relaxed);
    while (bytes > seen && !largest_request.compare_exchange_weak(seen, bytes)) {
    }
    if (bytes > most) throw std::bad_alloc();
  }
  if (void* p = std::malloc(bytes == 0 ? 1 : bytes)) return p;
  throw std::bad_alloc();
}

}  // namespace

// Every form that pairs with the deletes below: a sanitizer's own nothrow new (std::stable_sort's
// buffer) freed by this free() is a mismatch it reports.
void* operator new(std::size_t bytes) {
  return allocate(bytes);
}
void* operator new(std::size_t bytes, const std::nothrow_t&) noexcept {
  try {
    return allocate(bytes);
  } catch (const std::bad_alloc&) {
    return nullptr;
  }
}
void* operator new[](std::size_t bytes, const std::nothrow_t& tag) noexcept {
  return operator new(bytes, tag);
}
void operator delete(void* p, const std::nothrow_t&) noexcept {
  std::free(p);
}
void operator delete[](void* p, const std::nothrow_t&) noexcept {
  std::free(p);
}
void* operator new[](std::size_t bytes) {
  return allocate(bytes);
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete[](void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t) noexcept {
  std::free(p);
}

namespace robotperf::testing {

AllocationLimit::AllocationLimit(std::size_t bytes) {
  largest_request.store(0);
  limit.store(bytes);
}

AllocationLimit::~AllocationLimit() {
  limit.store(0);
}

std::size_t AllocationLimit::largest() const {
  return largest_request.load();
}

}  // namespace robotperf::testing
