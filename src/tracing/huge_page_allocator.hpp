// Private to the tracing library: an allocator for the trace analysis's large working vectors.
#pragma once

#include <sys/mman.h>

#include <cstddef>
#include <cstdint>
#include <new>
#include <vector>

namespace robotperf::tracing {

constexpr std::size_t kHugePageBytes = std::size_t{2} << 20;

// Marks the whole 2 MiB pages inside [p, p + bytes) for transparent huge pages, before they are
// written; without transparent huge pages (or with them off) the pages stay ordinary ones.
inline void advise_huge_pages(void* p, std::size_t bytes) {
  constexpr uintptr_t kHuge = kHugePageBytes;
  const auto begin = (reinterpret_cast<uintptr_t>(p) + kHuge - 1) & ~(kHuge - 1);
  const auto end = (reinterpret_cast<uintptr_t>(p) + bytes) & ~(kHuge - 1);
  if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
}

// Blocks of 2 MiB and more are mapped on their own, aligned to 2 MiB and marked for transparent
// huge pages, so that filling hundreds of megabytes takes one page fault per 2 MiB instead of one
// per 4 KiB: in a virtual machine a fault costs microseconds, and with 4 KiB pages the faults took
// 40 % of the analysis of a 10 million-event trace. Smaller blocks come from operator new.
template <class T>
struct HugePageAllocator {
  using value_type = T;
  static constexpr std::size_t kHugePage = kHugePageBytes;

  HugePageAllocator() = default;
  template <class U>
  HugePageAllocator(const HugePageAllocator<U>&) {}  // NOLINT: allocators convert implicitly

  T* allocate(std::size_t n) {
    const std::size_t bytes = n * sizeof(T);
    if (bytes < kHugePage) return static_cast<T*>(::operator new(bytes));
    const std::size_t size = rounded(bytes);
    // Mapped one huge page larger, then trimmed to a 2 MiB boundary at both ends.
    void* mapped = mmap(nullptr, size + kHugePage, PROT_READ | PROT_WRITE,
                        MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
    if (mapped == MAP_FAILED) throw std::bad_alloc();
    const auto start = reinterpret_cast<uintptr_t>(mapped);
    const uintptr_t aligned = (start + kHugePage - 1) & ~(uintptr_t{kHugePage} - 1);
    if (aligned > start) munmap(mapped, aligned - start);
    const uintptr_t end = start + size + kHugePage;
    if (end > aligned + size) munmap(reinterpret_cast<void*>(aligned + size), end - aligned - size);
    advise_huge_pages(reinterpret_cast<void*>(aligned), size);
    return reinterpret_cast<T*>(aligned);
  }

  void deallocate(T* p, std::size_t n) {
    const std::size_t bytes = n * sizeof(T);
    if (bytes < kHugePage) {
      ::operator delete(p);
    } else {
      munmap(p, rounded(bytes));
    }
  }

  template <class U>
  bool operator==(const HugePageAllocator<U>&) const {
    return true;
  }

 private:
  static std::size_t rounded(std::size_t bytes) {
    return (bytes + kHugePage - 1) & ~(kHugePage - 1);
  }
};

template <class T>
using BigVector = std::vector<T, HugePageAllocator<T>>;

}  // namespace robotperf::tracing
