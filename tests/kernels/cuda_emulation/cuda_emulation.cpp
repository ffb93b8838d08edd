// The host emulation of the CUDA runtime (cuda_runtime.h beside this file says what it checks).
#include <sys/mman.h>
#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "cuda_runtime.h"

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
