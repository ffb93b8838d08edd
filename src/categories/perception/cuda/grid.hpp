// Private to the cuda backend's .cu files: how a kernel over an image is laid out in threads.
#pragma once

#include <cuda_runtime.h>

#include <cstddef>

namespace robotperf::perception::cuda {

// A warp along a row, eight rows a block: the threads of a warp touch neighbouring pixels.
inline dim3 image_block() {
  return dim3(32, 8);
}

// Enough blocks of image_block() to give a thread to each of width x height pixels.
inline dim3 image_grid(int width, int height) {
  const dim3 block = image_block();
  return dim3((static_cast<unsigned>(width) + block.x - 1) / block.x,
              (static_cast<unsigned>(height) + block.y - 1) / block.y);
}

// Queues `kernel` on `stream` with `grid` x `block` threads. Every launch goes through here so
// that the tests' host emulation of the CUDA runtime (tests/perception/cuda_emulation), which has
// no <<< >>>, runs the same kernels on machines without a GPU.
template <class... Params, class... Args>
void launch(void (*kernel)(Params...), dim3 grid, dim3 block, cudaStream_t stream,
            const Args&... args) {
#ifdef ROBOTPERF_CUDA_EMULATION
  cuda_emulation::launch(kernel, grid, block, stream, args...);
#else
  // clang-format takes a .hpp for C++, which has no <<< >>>.
  // clang-format off
  kernel<<<grid, block, 0, stream>>>(args...);
  // clang-format on
#endif
}

// As launch(), for a kernel whose threads wait for each other (__syncthreads, warp collectives)
// or share `shared_bytes` of dynamic shared memory a block (dynamic_shared()): the emulation runs
// its threads as fibers that take turns at each wait.
template <class... Params, class... Args>
void launch_synchronising(void (*kernel)(Params...), dim3 grid, dim3 block,
                          std::size_t shared_bytes, cudaStream_t stream, const Args&... args) {
#ifdef ROBOTPERF_CUDA_EMULATION
  cuda_emulation::launch_synchronising(kernel, grid, block, shared_bytes, stream, args...);
#else
  // clang-format off
  kernel<<<grid, block, shared_bytes, stream>>>(args...);
  // clang-format on
#endif
}

// The block's dynamic shared memory, as T.
template <class T>
__device__ T* dynamic_shared() {
#ifdef ROBOTPERF_CUDA_EMULATION
  return static_cast<T*>(cuda_emulation::dynamic_shared_memory());
#else
  extern __shared__ __align__(16) unsigned char shared_bytes[];
  return reinterpret_cast<T*>(shared_bytes);
#endif
}

// The calling thread's lane in its warp: warps are runs of 32 threads in x, then y, then z order.
__device__ inline unsigned lane_id() {
  return (threadIdx.x + blockDim.x * (threadIdx.y + blockDim.y * threadIdx.z)) % 32u;
}

}  // namespace robotperf::perception::cuda
