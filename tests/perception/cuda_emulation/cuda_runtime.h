// A host emulation of the part of the CUDA runtime that robotperf's cuda backend uses, so that the
// backend's own kernels and host code run in the tests of machines without a GPU (CI's). The
// kernels run on the CPU. A kernel launched with launch() runs one GPU thread after another: its
// threads share nothing but atomics, so the order does not change its answer. A kernel launched
// with launch_synchronising() has threads that wait for each other (__syncthreads, the warp
// collectives) and share a block's memory: each thread of a block runs as a fiber until it waits,
// the block's fibers taking turns in an order that reverses every turn, so that a thread reading
// what another writes without a barrier between them reads the wrong bytes in one of the orders;
// a block's dynamic shared memory starts full of 0xa5 bytes, never the last block's. The speckle
// filter's union-find shares labels through atomics, and here runs in a few orders only: that it
// gives the same regions in every order is its algorithm's claim, which only a GPU tests. It is
// not a GPU: its times mean nothing, and nothing it computes is reported as a GPU's (its device is
// named as an emulation). It checks what a GPU would punish and a plain host run would hide:
// - a stream's work runs only when the host waits for it (cudaStreamSynchronize, or a free), so a
//   host that reads a download before waiting sees stale bytes, and one that rewrites a pinned
//   buffer before waiting uploads the rewritten bytes;
// - device memory cannot be read or written by host code (it is PROT_NONE outside the streams'
//   work), nor by a kernel past the end of its allocation (a guard page follows it);
// - a copy must go the way its kind says, within its allocations, and a kernel's pointer
//   arguments must point into device memory;
// - the threads of a block that wait must all reach the same barrier, and the lanes a warp
//   collective names must all reach it (a deadlock on a GPU ends the test here, saying which).
// Found on the include path before any CUDA toolkit's, by the emulated test build only.
#pragma once

#define ROBOTPERF_CUDA_EMULATION 1

#include <bit>
#include <climits>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <functional>
#include <tuple>
#include <type_traits>
#include <utility>

struct dim3 {
  unsigned x = 1, y = 1, z = 1;
  constexpr dim3(unsigned x_ = 1, unsigned y_ = 1, unsigned z_ = 1) : x(x_), y(y_), z(z_) {}
};
struct uint3 {
  unsigned x = 0, y = 0, z = 0;
};
struct alignas(16) float4 {
  float x, y, z, w;
};
struct alignas(16) uint4 {
  unsigned x, y, z, w;
};
inline float4 make_float4(float x, float y, float z, float w) {
  return {x, y, z, w};
}
inline uint4 make_uint4(unsigned x, unsigned y, unsigned z, unsigned w) {
  return {x, y, z, w};
}

#define __global__
#define __device__
#define __host__
#define __launch_bounds__(...)

// The running GPU thread's coordinates.
extern constinit thread_local uint3 threadIdx, blockIdx;
extern constinit thread_local dim3 blockDim, gridDim;

// The device functions the kernels call.
inline int min(int a, int b) {
  return a < b ? a : b;
}
inline int max(int a, int b) {
  return a > b ? a : b;
}
using std::isfinite;
inline float __int_as_float(int bits) {
  return std::bit_cast<float>(bits);
}
// Round to nearest, ties to even; NaN gives 0 and the out-of-range saturate, as the GPU's cvt.
inline int __float2int_rn(float v) {
  if (std::isnan(v)) return 0;
  if (v >= 2147483648.f) return INT_MAX;
  if (v <= -2147483648.f) return INT_MIN;
  return static_cast<int>(std::nearbyint(v));
}

// The atomics: one thread runs at a time here (a fiber runs until it waits), so a plain
// read-modify-write is atomic.
inline int atomicMin(int* address, int value) {
  const int old = *address;
  if (value < old) *address = value;
  return old;
}
inline unsigned long long atomicMin(unsigned long long* address, unsigned long long value) {
  const unsigned long long old = *address;
  if (value < old) *address = value;
  return old;
}
inline int atomicAdd(int* address, int value) {
  const int old = *address;
  *address = old + value;
  return old;
}

inline int __popc(unsigned bits) {
  return std::popcount(bits);
}
// The zero bits above the most significant bit set, 32 for none.
inline int __clz(int bits) {
  return std::countl_zero(static_cast<unsigned>(bits));
}
// 1 + the index of the least significant bit set, 0 for none.
inline int __ffs(int bits) {
  return bits == 0 ? 0 : std::countr_zero(static_cast<unsigned>(bits)) + 1;
}

// Block and warp synchronisation, for kernels launched with launch_synchronising() only (a kernel
// launched with launch() that calls one ends the test, saying so).
void __syncthreads();
// The lanes of the caller's warp in `mask` (all of which must call it) whose predicate is non-zero.
unsigned __ballot_sync(unsigned mask, int predicate);
// The lanes of the caller's warp in `mask` (all of which must call it) whose value is the caller's.
unsigned __match_any_sync(unsigned mask, int value);

enum cudaError_t {
  cudaSuccess = 0,
  cudaErrorInvalidValue = 1,
  cudaErrorMemoryAllocation = 2,
  cudaErrorInvalidDevicePointer = 17,
  cudaErrorNoDevice = 100,
  cudaErrorInvalidResourceHandle = 400,
  cudaErrorIllegalAddress = 700,
};
using cudaError = cudaError_t;
enum cudaMemcpyKind {
  cudaMemcpyHostToHost = 0,
  cudaMemcpyHostToDevice = 1,
  cudaMemcpyDeviceToHost = 2,
  cudaMemcpyDeviceToDevice = 3,
};
using cudaStream_t = struct CUstream_st*;
constexpr unsigned cudaStreamNonBlocking = 1;
constexpr unsigned cudaHostAllocDefault = 0;

struct cudaDeviceProp {
  char name[256];
  std::size_t totalGlobalMem;
};

const char* cudaGetErrorString(cudaError_t error);
cudaError_t cudaGetLastError();
cudaError_t cudaGetDeviceCount(int* count);
cudaError_t cudaGetDeviceProperties(cudaDeviceProp* properties, int device);
cudaError_t cudaDriverGetVersion(int* version);
cudaError_t cudaRuntimeGetVersion(int* version);
cudaError_t cudaStreamCreateWithFlags(cudaStream_t* stream, unsigned flags);
cudaError_t cudaStreamDestroy(cudaStream_t stream);
cudaError_t cudaStreamSynchronize(cudaStream_t stream);
cudaError_t cudaMalloc(void** pointer, std::size_t bytes);
cudaError_t cudaFree(void* pointer);
cudaError_t cudaHostAlloc(void** pointer, std::size_t bytes, unsigned flags);
cudaError_t cudaFreeHost(void* pointer);
cudaError_t cudaMemcpyAsync(void* to, const void* from, std::size_t bytes, cudaMemcpyKind kind,
                            cudaStream_t stream);

namespace robotperf::cuda_emulation {

// Queues `work` on `stream` (run when the host waits for the stream); an error for an unknown
// stream.
cudaError_t enqueue(cudaStream_t stream, std::function<void()> work);

// Whether a kernel may take `pointer`: null, or inside a device allocation. Records the launch
// error (cudaGetLastError) and says why on stderr when not.
bool device_argument(const void* pointer, const char* kernel_name);

// Runs `thread` (one GPU thread of a kernel) for every thread of `grid` x `block`, threadIdx and
// blockIdx set: one after another, or, `synchronising`, each block's threads as fibers with
// `shared_bytes` of dynamic shared memory (see the top of this file).
void run_grid(dim3 grid, dim3 block, bool synchronising, std::size_t shared_bytes,
              const std::function<void()>& thread);

// The running block's dynamic shared memory (launch_synchronising's `shared_bytes`).
void* dynamic_shared_memory();

template <class... Params, class... Args>
void launch_on(bool synchronising, std::size_t shared_bytes, void (*kernel)(Params...), dim3 grid,
               dim3 block, cudaStream_t stream, const Args&... args) {
  std::tuple<std::decay_t<Params>...> arguments(args...);
  bool pointers_ok = true;
  std::apply(
      [&](const auto&... a) {
        const auto check = [&](const auto& argument) {
          if constexpr (std::is_pointer_v<std::decay_t<decltype(argument)>>)
            pointers_ok = device_argument(argument, "a kernel") && pointers_ok;
        };
        (check(a), ...);
      },
      arguments);
  if (!pointers_ok) return;
  enqueue(stream, [kernel, grid, block, synchronising, shared_bytes, arguments] {
    run_grid(grid, block, synchronising, shared_bytes, [&] { std::apply(kernel, arguments); });
  });
}

// Launches `kernel` with `grid` x `block` threads on `stream`: its arguments are copied now, as
// a GPU launch copies them, and its threads run when the stream's work runs.
template <class... Params, class... Args>
void launch(void (*kernel)(Params...), dim3 grid, dim3 block, cudaStream_t stream,
            const Args&... args) {
  launch_on(false, 0, kernel, grid, block, stream, args...);
}

// As launch(), for a kernel whose threads wait for each other or share `shared_bytes` of dynamic
// shared memory a block.
template <class... Params, class... Args>
void launch_synchronising(void (*kernel)(Params...), dim3 grid, dim3 block,
                          std::size_t shared_bytes, cudaStream_t stream, const Args&... args) {
  launch_on(true, shared_bytes, kernel, grid, block, stream, args...);
}

}  // namespace robotperf::cuda_emulation
