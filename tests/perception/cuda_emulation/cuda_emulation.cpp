// The host emulation of the CUDA runtime (cuda_runtime.h beside this file says what it checks).
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <boost/context/fiber.hpp>
#include <cstdio>
#include <cstring>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "cuda_runtime.h"

#if defined(__SANITIZE_ADDRESS__)
#include <sanitizer/asan_interface.h>
#include <sanitizer/common_interface_defs.h>
#endif

struct CUstream_st {
  std::deque<std::function<void()>> work;
};

constinit thread_local uint3 threadIdx, blockIdx;
constinit thread_local dim3 blockDim, gridDim;

namespace robotperf::cuda_emulation {
namespace {

std::size_t page_bytes() {
  static const auto bytes = static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
  return bytes;
}

std::size_t round_up(std::size_t n, std::size_t to) {
  return (n + to - 1) / to * to;
}

// A device allocation: pages of its own, PROT_NONE but while streams' work runs, with its data
// ending at a guard page that is never readable.
struct DeviceAllocation {
  std::byte* mapping = nullptr;
  std::size_t readable_bytes = 0;  // the mapping less its guard page
  std::size_t bytes = 0;           // as asked for
};

struct State {
  std::mutex mutex;  // guards the maps, the streams' queues and the running of their work
  std::map<const std::byte*, DeviceAllocation> device;  // by the data's address
  std::map<const std::byte*, std::size_t> pinned;       // by address: bytes
  std::vector<CUstream_st*> streams;
  CUstream_st default_stream;
};

State& state() {
  static State s;
  return s;
}

thread_local cudaError_t last_error = cudaSuccess;

cudaError_t refuse(cudaError_t error, const std::string& why) {
  std::fprintf(stderr, "cuda emulation: %s\n", why.c_str());
  return error;
}

// The allocation in `allocations` (keyed by address) holding [p, p + bytes), if any.
template <class Map>
auto holding(const Map& allocations, const void* p, std::size_t bytes) {
  const auto* at = static_cast<const std::byte*>(p);
  auto it = allocations.upper_bound(at);
  if (it == allocations.begin()) return allocations.end();
  --it;
  const std::size_t size = [&] {
    if constexpr (std::is_same_v<typename Map::mapped_type, DeviceAllocation>) {
      return it->second.bytes;
    } else {
      return it->second;
    }
  }();
  return at >= it->first && at + bytes <= it->first + size ? it : allocations.end();
}

bool overlaps_device(const State& s, const void* p, std::size_t bytes) {
  const auto* at = static_cast<const std::byte*>(p);
  for (const auto& [start, a] : s.device)
    if (at < start + a.bytes && start < at + bytes) return true;
  return false;
}

void set_device_access(State& s, int protection) {
  for (auto& [start, a] : s.device) mprotect(a.mapping, a.readable_bytes, protection);
}

CUstream_st* find_stream(State& s, cudaStream_t stream) {
  if (stream == nullptr) return &s.default_stream;
  for (CUstream_st* known : s.streams)
    if (known == stream) return known;
  return nullptr;
}

// Runs a stream's queued work, device memory readable meanwhile. Called with the mutex held.
void run(State& s, CUstream_st& stream) {
  if (stream.work.empty()) return;
  set_device_access(s, PROT_READ | PROT_WRITE);
  while (!stream.work.empty()) {
    const std::function<void()> work = std::move(stream.work.front());
    stream.work.pop_front();
    work();
  }
  set_device_access(s, PROT_NONE);
}

// A free waits for all the device's work, as CUDA's does.
void run_all(State& s) {
  run(s, s.default_stream);
  for (CUstream_st* stream : s.streams) run(s, *stream);
}

// What a waiting thread waits for.
enum class Wait { kNone, kBlock, kBallot, kMatchAny, kDone };

// One GPU thread of a block running as a fiber.
struct Fiber {
  boost::context::fiber context;    // the thread's, while it waits
  boost::context::fiber scheduler;  // the scheduler's, while the thread runs
  std::byte* stack = nullptr;
  uint3 thread;
  unsigned lane = 0;
  Wait wait = Wait::kNone;
  unsigned mask = 0;           // of a warp collective
  int value = 0;               // its argument
  unsigned result = 0;         // its answer
  void* fake_stack = nullptr;  // AddressSanitizer's, while switched out
};

// Hands a fiber the stack its grid keeps for its thread.
struct ThreadStack {
  std::byte* bottom = nullptr;
  std::size_t bytes = 0;
  boost::context::stack_context allocate() const {
    boost::context::stack_context stack;
    stack.size = bytes;
    stack.sp = bottom + bytes;
    return stack;
  }
  void deallocate(boost::context::stack_context& /*stack*/) const noexcept {}
};

[[noreturn]] void deadlock(const std::string& why) {
  std::fprintf(stderr, "cuda emulation: block (%u, %u, %u): %s\n", blockIdx.x, blockIdx.y,
               blockIdx.z, why.c_str());
  std::abort();
}

// Runs blocks of a kernel launched with launch_synchronising(): every thread of a block as a
// fiber of its own stack, taking turns until each waits or ends, in an order reversed every turn.
class SynchronisingGrid {
 public:
  static constexpr std::size_t kStackBytes = 256 * 1024;

  SynchronisingGrid(dim3 block, std::size_t shared_bytes, const std::function<void()>& thread)
      : thread_(thread), shared_(shared_bytes) {
    const std::size_t n = std::size_t{block.x} * block.y * block.z;
    stacks_bytes_ = n * kStackBytes;
    void* stacks = mmap(nullptr, stacks_bytes_, PROT_READ | PROT_WRITE,
                        MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
    if (stacks == MAP_FAILED) deadlock("no memory for the stacks of its threads' fibers");
    stacks_ = static_cast<std::byte*>(stacks);
    fibers_.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      Fiber& f = fibers_[i];
      f.stack = stacks_ + i * kStackBytes;
      f.thread = {static_cast<unsigned>(i % block.x), static_cast<unsigned>(i / block.x % block.y),
                  static_cast<unsigned>(i / (std::size_t{block.x} * block.y))};
      f.lane = static_cast<unsigned>(i % 32);
    }
  }
  ~SynchronisingGrid() {
    unpoison_stacks();
    munmap(stacks_, stacks_bytes_);
  }
  SynchronisingGrid(const SynchronisingGrid&) = delete;
  SynchronisingGrid& operator=(const SynchronisingGrid&) = delete;

  void run_block() {
    std::fill(shared_.begin(), shared_.end(), std::byte{0xa5});
    unpoison_stacks();
    for (Fiber& f : fibers_) {
      f.wait = Wait::kNone;
      f.context = boost::context::fiber(std::allocator_arg, ThreadStack{f.stack, kStackBytes},
                                        [this, &f](boost::context::fiber&& scheduler) {
                                          return run_thread(f, std::move(scheduler));
                                        });
    }
    bool forward = true;
    while (true) {
      for (std::size_t i = 0; i < fibers_.size(); ++i) {
        Fiber& f = fibers_[forward ? i : fibers_.size() - 1 - i];
        if (f.wait == Wait::kNone) resume(f);
      }
      forward = !forward;
      if (release_warps()) continue;
      std::size_t done = 0, at_barrier = 0;
      for (const Fiber& f : fibers_) {
        done += f.wait == Wait::kDone ? 1 : 0;
        at_barrier += f.wait == Wait::kBlock ? 1 : 0;
      }
      if (done == fibers_.size()) return;
      if (done + at_barrier < fibers_.size())
        deadlock("threads wait at a warp collective that lanes it names never reach");
      for (Fiber& f : fibers_)
        if (f.wait == Wait::kBlock) f.wait = Wait::kNone;
    }
  }

  // The running fiber waits for `wait` (the scheduler resumes it when its wait is over).
  unsigned wait(Wait wait, unsigned mask = 0, int value = 0) {
    Fiber& f = *running_;
    f.wait = wait;
    f.mask = mask;
    f.value = value;
    switch_to_scheduler(f);
    return f.result;
  }

  void* shared_memory() { return shared_.data(); }

  static SynchronisingGrid* current() { return current_; }
  static void set_current(SynchronisingGrid* grid) { current_ = grid; }

 private:
  // AddressSanitizer marks the frames of a fiber's stack as it marks any stack's; the marks
  // outlive the fiber, and would fault a new fiber there or memory mapped there after the munmap.
  void unpoison_stacks() {
#if defined(__SANITIZE_ADDRESS__)
    ASAN_UNPOISON_MEMORY_REGION(stacks_, stacks_bytes_);
#endif
  }

  boost::context::fiber run_thread(Fiber& f, boost::context::fiber&& scheduler) {
    f.scheduler = std::move(scheduler);
#if defined(__SANITIZE_ADDRESS__)
    __sanitizer_finish_switch_fiber(nullptr, &scheduler_stack_, &scheduler_stack_bytes_);
#endif
    thread_();
    f.wait = Wait::kDone;
#if defined(__SANITIZE_ADDRESS__)
    __sanitizer_start_switch_fiber(nullptr, scheduler_stack_, scheduler_stack_bytes_);
#endif
    return std::move(f.scheduler);
  }

  void resume(Fiber& f) {
    running_ = &f;
    threadIdx = f.thread;
#if defined(__SANITIZE_ADDRESS__)
    void* fake_stack = nullptr;
    __sanitizer_start_switch_fiber(&fake_stack, f.stack, kStackBytes);
#endif
    f.context = std::move(f.context).resume();
#if defined(__SANITIZE_ADDRESS__)
    __sanitizer_finish_switch_fiber(fake_stack, nullptr, nullptr);
#endif
    running_ = nullptr;
  }

  void switch_to_scheduler(Fiber& f) {
#if defined(__SANITIZE_ADDRESS__)
    __sanitizer_start_switch_fiber(&f.fake_stack, scheduler_stack_, scheduler_stack_bytes_);
#endif
    f.scheduler = std::move(f.scheduler).resume();
#if defined(__SANITIZE_ADDRESS__)
    __sanitizer_finish_switch_fiber(f.fake_stack, nullptr, nullptr);
#endif
  }

  // Answers every warp collective whose lanes have all reached it; whether any was.
  bool release_warps() {
    bool released = false;
    for (std::size_t first = 0; first < fibers_.size(); first += 32) {
      const std::size_t end = std::min(first + 32, fibers_.size());
      const Fiber* caller = nullptr;
      for (std::size_t i = first; i < end && caller == nullptr; ++i) {
        const Wait w = fibers_[i].wait;
        if (w == Wait::kBallot || w == Wait::kMatchAny) caller = &fibers_[i];
      }
      if (caller == nullptr) continue;
      const unsigned mask = caller->mask;
      const Wait kind = caller->wait;
      bool all_there = true;
      for (std::size_t i = first; i < end; ++i) {
        const Fiber& f = fibers_[i];
        if ((mask >> f.lane & 1u) == 0) continue;
        if (f.wait == Wait::kDone) deadlock("a lane a warp collective names has ended");
        if (f.wait == kind && f.mask != mask)
          deadlock("the lanes of a warp collective disagree on its mask");
        all_there = all_there && f.wait == kind;
      }
      if (end - first < 32 && mask >> (end - first) != 0)
        deadlock("a warp collective names lanes past the block's last thread");
      if (!all_there) continue;
      for (std::size_t i = first; i < end; ++i) {
        Fiber& f = fibers_[i];
        if ((mask >> f.lane & 1u) == 0 || f.wait != kind) continue;
        unsigned answer = 0;
        for (std::size_t j = first; j < end; ++j) {
          const Fiber& g = fibers_[j];
          if ((mask >> g.lane & 1u) == 0) continue;
          const bool counted = kind == Wait::kBallot ? g.value != 0 : g.value == f.value;
          answer |= counted ? 1u << g.lane : 0u;
        }
        f.result = answer;
      }
      for (std::size_t i = first; i < end; ++i)
        if ((mask >> fibers_[i].lane & 1u) != 0) fibers_[i].wait = Wait::kNone;
      released = true;
    }
    return released;
  }

  static thread_local SynchronisingGrid* current_;
  const std::function<void()>& thread_;
  std::vector<std::byte> shared_;
  std::byte* stacks_ = nullptr;
  std::size_t stacks_bytes_ = 0;
  std::vector<Fiber> fibers_;
  Fiber* running_ = nullptr;
  const void* scheduler_stack_ = nullptr;
  std::size_t scheduler_stack_bytes_ = 0;
};

thread_local SynchronisingGrid* SynchronisingGrid::current_ = nullptr;

SynchronisingGrid& synchronising_grid(const char* what) {
  SynchronisingGrid* grid = SynchronisingGrid::current();
  if (grid == nullptr) {
    std::fprintf(stderr,
                 "cuda emulation: %s in a kernel launched with launch(): launch it with "
                 "launch_synchronising()\n",
                 what);
    std::abort();
  }
  return *grid;
}

}  // namespace

cudaError_t enqueue(cudaStream_t stream, std::function<void()> work) {
  State& s = state();
  const std::lock_guard lock(s.mutex);
  CUstream_st* queue = find_stream(s, stream);
  if (queue == nullptr) return refuse(cudaErrorInvalidResourceHandle, "work for an unknown stream");
  queue->work.push_back(std::move(work));
  return cudaSuccess;
}

bool device_argument(const void* pointer, const char* kernel_name) {
  if (pointer == nullptr) return true;
  State& s = state();
  const std::lock_guard lock(s.mutex);
  if (holding(s.device, pointer, 0) != s.device.end()) return true;
  last_error = refuse(cudaErrorIllegalAddress,
                      std::string(kernel_name) + " was given a pointer outside device memory");
  return false;
}

void run_grid(dim3 grid, dim3 block, bool synchronising, std::size_t shared_bytes,
              const std::function<void()>& thread) {
  gridDim = grid;
  blockDim = block;
  if (!synchronising) {
    for (blockIdx.z = 0; blockIdx.z < grid.z; ++blockIdx.z)
      for (blockIdx.y = 0; blockIdx.y < grid.y; ++blockIdx.y)
        for (blockIdx.x = 0; blockIdx.x < grid.x; ++blockIdx.x)
          for (threadIdx.z = 0; threadIdx.z < block.z; ++threadIdx.z)
            for (threadIdx.y = 0; threadIdx.y < block.y; ++threadIdx.y)
              for (threadIdx.x = 0; threadIdx.x < block.x; ++threadIdx.x) thread();
    return;
  }
  SynchronisingGrid blocks(block, shared_bytes, thread);
  SynchronisingGrid::set_current(&blocks);
  for (blockIdx.z = 0; blockIdx.z < grid.z; ++blockIdx.z)
    for (blockIdx.y = 0; blockIdx.y < grid.y; ++blockIdx.y)
      for (blockIdx.x = 0; blockIdx.x < grid.x; ++blockIdx.x) blocks.run_block();
  SynchronisingGrid::set_current(nullptr);
}

void* dynamic_shared_memory() {
  return synchronising_grid("dynamic shared memory").shared_memory();
}

}  // namespace robotperf::cuda_emulation

using namespace robotperf::cuda_emulation;

const char* cudaGetErrorString(cudaError_t error) {
  switch (error) {
    case cudaSuccess:
      return "no error";
    case cudaErrorInvalidValue:
      return "invalid argument";
    case cudaErrorMemoryAllocation:
      return "out of memory";
    case cudaErrorInvalidDevicePointer:
      return "invalid device pointer";
    case cudaErrorNoDevice:
      return "no CUDA-capable device is detected";
    case cudaErrorInvalidResourceHandle:
      return "invalid resource handle";
    case cudaErrorIllegalAddress:
      return "an illegal memory access was encountered";
  }
  return "unknown error";
}

cudaError_t cudaGetLastError() {
  return std::exchange(last_error, cudaSuccess);
}

cudaError_t cudaGetDeviceCount(int* count) {
  // CUDA_VISIBLE_DEVICES=-1 hides every device, as it does from the real runtime.
  if (const char* visible = std::getenv("CUDA_VISIBLE_DEVICES");
      visible != nullptr && (*visible == '\0' || *visible == '-')) {
    *count = 0;
    return cudaErrorNoDevice;
  }
  *count = 1;
  return cudaSuccess;
}

cudaError_t cudaGetDeviceProperties(cudaDeviceProp* properties, int device) {
  if (device != 0) return cudaErrorInvalidValue;
  *properties = {};
  std::snprintf(properties->name, sizeof properties->name,
                "robotperf's CUDA emulation on the host (tests only)");
  properties->totalGlobalMem = std::size_t{1} << 30;
  return cudaSuccess;
}

cudaError_t cudaDriverGetVersion(int* version) {
  *version = 13000;
  return cudaSuccess;
}

cudaError_t cudaRuntimeGetVersion(int* version) {
  *version = 13000;
  return cudaSuccess;
}

cudaError_t cudaStreamCreateWithFlags(cudaStream_t* stream, unsigned /*flags*/) {
  State& s = state();
  const std::lock_guard lock(s.mutex);
  s.streams.push_back(new CUstream_st);
  *stream = s.streams.back();
  return cudaSuccess;
}

cudaError_t cudaStreamDestroy(cudaStream_t stream) {
  State& s = state();
  const std::lock_guard lock(s.mutex);
  CUstream_st* queue = find_stream(s, stream);
  if (queue == nullptr || stream == nullptr)
    return refuse(cudaErrorInvalidResourceHandle, "destroying an unknown stream");
  run(s, *queue);  // its queued work still completes
  std::erase(s.streams, queue);
  delete queue;
  return cudaSuccess;
}

cudaError_t cudaStreamSynchronize(cudaStream_t stream) {
  State& s = state();
  const std::lock_guard lock(s.mutex);
  CUstream_st* queue = find_stream(s, stream);
  if (queue == nullptr)
    return refuse(cudaErrorInvalidResourceHandle, "synchronizing an unknown stream");
  run(s, *queue);
  return cudaSuccess;
}

cudaError_t cudaMalloc(void** pointer, std::size_t bytes) {
  *pointer = nullptr;
  if (bytes == 0) return cudaSuccess;
  const std::size_t page = page_bytes(), data_bytes = round_up(bytes, 256),
                    readable = round_up(data_bytes, page);
  void* mapping = mmap(nullptr, readable + page, PROT_NONE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (mapping == MAP_FAILED) return cudaErrorMemoryAllocation;
  auto* base = static_cast<std::byte*>(mapping);
  std::byte* data = base + (readable - data_bytes);
  State& s = state();
  const std::lock_guard lock(s.mutex);
  s.device[data] = {base, readable, bytes};
  *pointer = data;
  return cudaSuccess;
}

cudaError_t cudaFree(void* pointer) {
  if (pointer == nullptr) return cudaSuccess;
  State& s = state();
  const std::lock_guard lock(s.mutex);
  const auto it = s.device.find(static_cast<const std::byte*>(pointer));
  if (it == s.device.end())
    return refuse(cudaErrorInvalidDevicePointer, "cudaFree of a pointer cudaMalloc did not give");
  run_all(s);
  munmap(it->second.mapping, it->second.readable_bytes + page_bytes());
  s.device.erase(it);
  return cudaSuccess;
}

cudaError_t cudaHostAlloc(void** pointer, std::size_t bytes, unsigned /*flags*/) {
  *pointer = std::aligned_alloc(page_bytes(), round_up(bytes == 0 ? 1 : bytes, page_bytes()));
  if (*pointer == nullptr) return cudaErrorMemoryAllocation;
  State& s = state();
  const std::lock_guard lock(s.mutex);
  s.pinned[static_cast<const std::byte*>(*pointer)] = bytes;
  return cudaSuccess;
}

cudaError_t cudaFreeHost(void* pointer) {
  if (pointer == nullptr) return cudaSuccess;
  State& s = state();
  const std::lock_guard lock(s.mutex);
  const auto it = s.pinned.find(static_cast<const std::byte*>(pointer));
  if (it == s.pinned.end())
    return refuse(cudaErrorInvalidValue, "cudaFreeHost of a pointer cudaHostAlloc did not give");
  run_all(s);
  s.pinned.erase(it);
  std::free(pointer);
  return cudaSuccess;
}

cudaError_t cudaMemcpyAsync(void* to, const void* from, std::size_t bytes, cudaMemcpyKind kind,
                            cudaStream_t stream) {
  State& s = state();
  std::unique_lock lock(s.mutex);
  CUstream_st* queue = find_stream(s, stream);
  if (queue == nullptr)
    return refuse(cudaErrorInvalidResourceHandle, "a copy on an unknown stream");
  if (bytes == 0) return cudaSuccess;
  const bool to_device = kind == cudaMemcpyHostToDevice || kind == cudaMemcpyDeviceToDevice;
  const bool from_device = kind == cudaMemcpyDeviceToHost || kind == cudaMemcpyDeviceToDevice;
  const auto side_ok = [&](const void* p, bool device) {
    return device ? holding(s.device, p, bytes) != s.device.end() : !overlaps_device(s, p, bytes);
  };
  if (!side_ok(to, to_device) || !side_ok(from, from_device)) {
    return refuse(cudaErrorInvalidValue,
                  "cudaMemcpyAsync of " + std::to_string(bytes) + " bytes of kind " +
                      std::to_string(kind) +
                      ": a pointer is not on the side its kind says, or the bytes run past "
                      "its allocation");
  }
  // Pageable host memory: CUDA reads the source before returning, and writes the destination
  // before returning (the copy is synchronous then).
  const bool pageable_from = !from_device && holding(s.pinned, from, bytes) == s.pinned.end();
  const bool pageable_to = !to_device && holding(s.pinned, to, bytes) == s.pinned.end();
  if (pageable_from) {
    auto copy = std::make_shared<std::vector<std::byte>>(
        static_cast<const std::byte*>(from), static_cast<const std::byte*>(from) + bytes);
    queue->work.push_back([to, copy] { std::memcpy(to, copy->data(), copy->size()); });
  } else {
    queue->work.push_back([to, from, bytes] { std::memcpy(to, from, bytes); });
  }
  if (pageable_to) run(s, *queue);
  return cudaSuccess;
}

void __syncthreads() {
  synchronising_grid("__syncthreads").wait(Wait::kBlock);
}

unsigned __ballot_sync(unsigned mask, int predicate) {
  return synchronising_grid("__ballot_sync").wait(Wait::kBallot, mask, predicate);
}

unsigned __match_any_sync(unsigned mask, int value) {
  return synchronising_grid("__match_any_sync").wait(Wait::kMatchAny, mask, value);
}
