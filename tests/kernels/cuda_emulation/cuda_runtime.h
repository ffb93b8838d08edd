// A host emulation of the part of the CUDA runtime that robotperf's cuda backend uses, so that the
// backend's own kernels and host code run in the tests of machines without a GPU (CI's). The
// kernels run on the CPU, one GPU thread after another. Most share nothing between threads (no
// shared memory or barriers), so the order does not change their answer; the speckle filter's
// union-find shares labels through atomics, and here runs in one order only: that it gives the
// same regions in every order is its algorithm's claim, which only a GPU tests. It is not a GPU:
// its times mean nothing, and nothing it computes is reported as a GPU's (its device is named as
// an emulation). It checks what a GPU would punish and a plain host run would hide:
// - a stream's work runs only when the host waits for it (cudaStreamSynchronize, or a free), so a
//   host that reads a download before waiting sees stale bytes, and one that rewrites a pinned
//   buffer before waiting uploads the rewritten bytes;
// - device memory cannot be read or written by host code (it is PROT_NONE outside the streams'
//   work), nor by a kernel past the end of its allocation (a guard page follows it);
// - a copy must go the way its kind says, within its allocations, and a kernel's pointer
//   arguments must point into device memory.
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

// The atomics: one thread runs at a time here, so a plain read-modify-write is atomic.
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

// Launches `kernel` with `grid` x `block` threads on `stream`: its arguments are copied now, as
// a GPU launch copies them, and its threads run when the stream's work runs.
template <class... Params, class... Args>
void launch(void (*kernel)(Params...), dim3 grid, dim3 block, cudaStream_t stream,
            const Args&... args) {
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
  enqueue(stream, [kernel, grid, block, arguments] {
    gridDim = grid;
    blockDim = block;
    for (blockIdx.z = 0; blockIdx.z < grid.z; ++blockIdx.z)
      for (blockIdx.y = 0; blockIdx.y < grid.y; ++blockIdx.y)
        for (blockIdx.x = 0; blockIdx.x < grid.x; ++blockIdx.x)
          for (threadIdx.z = 0; threadIdx.z < block.z; ++threadIdx.z)
            for (threadIdx.y = 0; threadIdx.y < block.y; ++threadIdx.y)
              for (threadIdx.x = 0; threadIdx.x < block.x; ++threadIdx.x)
                std::apply(kernel, arguments);
  });
}

}  // namespace robotperf::cuda_emulation
