// Private to the cuda backend's .cu files: how a kernel over an image is laid out in threads.
#pragma once

#include <cuda_runtime.h>

namespace robotperf::perception::cuda {

// A warp along a row, eight rows a block: the threads of a warp touch neighbouring pixels.
inline dim3 image_block() {
  return dim3(32, 8);
}

// Enough blocks of image_block() to give a thread to each of width x height pixels, `planes`
// times over (gridDim.z).
inline dim3 image_grid(int width, int height, int planes = 1) {
  const dim3 block = image_block();
  return dim3((static_cast<unsigned>(width) + block.x - 1) / block.x,
              (static_cast<unsigned>(height) + block.y - 1) / block.y,
              static_cast<unsigned>(planes));
}

// Queues `kernel` on `stream` with `grid` x `block` threads. Every launch goes through here so
// that the tests' host emulation of the CUDA runtime (tests/kernels/cuda_emulation), which has no
// <<< >>>, runs the same kernels on machines without a GPU.
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

}  // namespace robotperf::perception::cuda
