// Private to the tracing library: an allocator for the trace analysis's large working vectors.
#pragma once

#include <sys/mman.h>

#include <cstddef>
#include <cstdint>
#include <iterator>
#include <new>
#include <type_traits>
#include <utility>
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

  // Elements made without a value are left as they come (default-initialised): the analysis's
  // big vectors made at their size are written whole afterwards, and zeroing them first would
  // write hundreds of megabytes twice.
  // (Constructions with values are std::allocator_traits' own.)
  template <class U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) {
    ::new (static_cast<void*>(p)) U;
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

// One kind of record from every part of a trace, part after part: each part's vector is taken
// over whole when the parts are merged, never copied into a bigger one (a copy would write the
// records' memory twice, and in a virtual machine fresh memory costs more than the copy).
template <class T>
class PartedVector {
 public:
  class const_iterator {
   public:
    using iterator_category = std::forward_iterator_tag;
    using value_type = T;
    using difference_type = std::ptrdiff_t;
    using pointer = const T*;
    using reference = const T&;

    const_iterator() = default;
    const_iterator(const std::vector<BigVector<T>>* parts, std::size_t part)
        : parts_(parts), part_(part) {
      skip_empty();
    }
    reference operator*() const { return (*parts_)[part_][index_]; }
    pointer operator->() const { return &(*parts_)[part_][index_]; }
    const_iterator& operator++() {
      if (++index_ == (*parts_)[part_].size()) {
        ++part_;
        index_ = 0;
        skip_empty();
      }
      return *this;
    }
    const_iterator operator++(int) {
      const_iterator old = *this;
      ++*this;
      return old;
    }
    bool operator==(const const_iterator& o) const {
      return part_ == o.part_ && index_ == o.index_;
    }

   private:
    void skip_empty() {
      while (part_ < parts_->size() && (*parts_)[part_].empty()) ++part_;
    }
    const std::vector<BigVector<T>>* parts_ = nullptr;
    std::size_t part_ = 0, index_ = 0;
  };

  // A new last part, to be filled, with room for `room` records.
  BigVector<T>& add_part(std::size_t room = 0) {
    BigVector<T>& part = parts_.emplace_back();
    part.reserve(room);
    return part;
  }
  // Takes over `other`'s parts, after this one's.
  void append(PartedVector&& other) {
    for (auto& p : other.parts_) parts_.push_back(std::move(p));
    other.parts_.clear();
  }
  std::vector<BigVector<T>>& parts() { return parts_; }
  const std::vector<BigVector<T>>& parts() const { return parts_; }

  std::size_t size() const {
    std::size_t n = 0;
    for (const auto& p : parts_) n += p.size();
    return n;
  }
  bool empty() const { return size() == 0; }
  const_iterator begin() const { return {&parts_, 0}; }
  const_iterator end() const { return {&parts_, parts_.size()}; }

 private:
  std::vector<BigVector<T>> parts_;
};

}  // namespace robotperf::tracing
