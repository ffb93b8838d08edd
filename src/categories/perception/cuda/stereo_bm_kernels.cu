// StereoBM's device part, the stages of robotperf's OpenCL StereoBM (stereo_bm_opencl.cpp) with
// the same integer arithmetic: the x-Sobel pre-filter, the window costs of every disparity (the
// cost volume kept on the device), the texture and uniqueness checks and the sub-pixel fit. Each
// window sum is taken whole by its own thread rather than slid along a row as the OpenCL kernels
// do: integer sums, the same values, and a thread for every cost instead of one per row.
#include <climits>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "cuda_check.hpp"
#include "cuda_kernels.hpp"
#include "grid.hpp"

namespace robotperf::perception::cuda {
namespace {

// x-Sobel of rows y-1, y, y+1 (mirrored at the top and bottom rows), clipped and offset to
// [0, 2 cap]; the first and last columns read cap.
__global__ void prefilter_kernel(const uint8_t* src, uint8_t* dst, int rows, int cols, int cap) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x;
  const int y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= cols || y >= rows) return;
  uint8_t* out = dst + static_cast<size_t>(y) * cols + x;
  if (x == 0 || x == cols - 1) {
    *out = static_cast<uint8_t>(cap);
    return;
  }
  const int up = y > 0 ? y - 1 : (rows > 1 ? 1 : 0);
  const int down = y < rows - 1 ? y + 1 : (rows > 1 ? rows - 2 : 0);
  const uint8_t* r0 = src + static_cast<size_t>(up) * cols;
  const uint8_t* r1 = src + static_cast<size_t>(y) * cols;
  const uint8_t* r2 = src + static_cast<size_t>(down) * cols;
  const int d = (r0[x + 1] - r0[x - 1]) + 2 * (r1[x + 1] - r1[x - 1]) + (r2[x + 1] - r2[x - 1]);
  *out = static_cast<uint8_t>(min(max(d, -cap), cap) + cap);
}

// The cost of pixel column c for disparity index k (disparity = right_offset - k), the columns
// clamped as OpenCV clamps them; index `disparities` is the texture, |L - cap|.
__device__ int column_cost(const uint8_t* l, const uint8_t* r, int c, int k,
                           const BlockMatchingShape& s) {
  const int lc = min(max(c, 0), s.cols - 1);
  if (k == s.disparities) return abs(static_cast<int>(l[lc]) - s.prefilter_cap);
  return abs(static_cast<int>(l[lc]) -
             static_cast<int>(r[min(max(c - s.right_offset, 0) + k, s.cols - 1)]));
}

// Per pixel and disparity index (blockIdx.z): the window's sum along the row.
__global__ void row_costs_kernel(const uint8_t* left, const uint8_t* right, int32_t* row_costs,
                                 BlockMatchingShape s) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x;
  const int y = blockIdx.y * blockDim.y + threadIdx.y;
  const int k = blockIdx.z;
  if (x >= s.cols || y >= s.rows || k > s.disparities) return;
  const uint8_t* l = left + static_cast<size_t>(y) * s.cols;
  const uint8_t* r = right + static_cast<size_t>(y) * s.cols;
  int sum = 0;
  for (int c = x - s.radius; c <= x + s.radius; ++c) sum += column_cost(l, r, c, k, s);
  row_costs[(static_cast<size_t>(k) * s.rows + y) * s.cols + x] = sum;
}

// Per pixel and disparity index: the window's sum of the row sums down the column, the rows
// clamped at the top and bottom.
__global__ void window_costs_kernel(const int32_t* row_costs, int32_t* costs,
                                    BlockMatchingShape s) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x;
  const int y = blockIdx.y * blockDim.y + threadIdx.y;
  const int k = blockIdx.z;
  if (x >= s.cols || y >= s.rows || k > s.disparities) return;
  const int32_t* in = row_costs + static_cast<size_t>(k) * s.rows * s.cols + x;
  int sum = 0;
  for (int j = y - s.radius; j <= y + s.radius; ++j)
    sum += in[static_cast<size_t>(min(max(j, 0), s.rows - 1)) * s.cols];
  costs[(static_cast<size_t>(k) * s.rows + y) * s.cols + x] = sum;
}

// Per pixel: inside the valid region, the best disparity, the texture and uniqueness checks, and
// the fixed-point (1/16 px) disparity with OpenCV's sub-pixel fit of the costs on either side;
// the best cost for the left-right check (0 where filtered).
__global__ void choose_kernel(const int32_t* costs, int16_t* disparity, int32_t* best_cost,
                              BlockMatchingShape s) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x;
  const int y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= s.cols || y >= s.rows) return;
  const size_t plane = static_cast<size_t>(s.rows) * s.cols,
               at = static_cast<size_t>(y) * s.cols + x;
  const int16_t filtered = static_cast<int16_t>((s.min_disparity - 1) * 16);
  disparity[at] = filtered;
  best_cost[at] = 0;
  if (x < s.x0 || x >= s.x1 || y < s.y0 || y >= s.y1 ||
      costs[s.disparities * plane + at] < s.texture_threshold) {
    return;
  }
  int best = INT_MAX, best_k = 0;
  for (int k = 0; k < s.disparities; ++k) {
    const int c = costs[k * plane + at];
    if (c < best) {
      best = c;
      best_k = k;
    }
  }
  if (s.uniqueness_ratio > 0) {
    const int limit = best + best * s.uniqueness_ratio / 100;
    for (int k = 0; k < s.disparities; ++k) {
      if ((k < best_k - 1 || k > best_k + 1) && costs[k * plane + at] <= limit) return;
    }
  }
  best_cost[at] = best;
  const int whole = s.disparities - best_k - 1 + s.min_disparity;
  if (best_k == 0 || best_k == s.disparities - 1) {
    disparity[at] = static_cast<int16_t>(whole * 16);
    return;
  }
  const int p = costs[(best_k + 1) * plane + at];
  const int n = costs[(best_k - 1) * plane + at];
  const int d = p + n - 2 * best + abs(p - n);
  disparity[at] = static_cast<int16_t>((whole * 256 + (d != 0 ? (p - n) * 256 / d : 0) + 15) >> 4);
}

}  // namespace

void block_match(const BlockMatchingShape& s, const BlockMatchingBuffers& b, cudaStream_t stream) {
  // gridDim.y and gridDim.z are at most 65535.
  if (s.rows <= 0 || s.cols <= 0 || s.disparities <= 0 || s.disparities >= 65535 ||
      s.rows > 65535 * 8) {
    throw std::invalid_argument("cuda: block matching: " + std::to_string(s.cols) + "x" +
                                std::to_string(s.rows) + " images with " +
                                std::to_string(s.disparities) + " disparities do not fit");
  }
  const dim3 block = image_block(), pixels = image_grid(s.cols, s.rows);
  launch(prefilter_kernel, pixels, block, stream, b.left, b.filtered_left, s.rows, s.cols,
         s.prefilter_cap);
  check_launch("prefilter_kernel");
  launch(prefilter_kernel, pixels, block, stream, b.right, b.filtered_right, s.rows, s.cols,
         s.prefilter_cap);
  check_launch("prefilter_kernel");
  const dim3 volume = image_grid(s.cols, s.rows, s.disparities + 1);
  launch(row_costs_kernel, volume, block, stream, b.filtered_left, b.filtered_right, b.row_costs,
         s);
  check_launch("row_costs_kernel");
  launch(window_costs_kernel, volume, block, stream, b.row_costs, b.costs, s);
  check_launch("window_costs_kernel");
  launch(choose_kernel, pixels, block, stream, b.costs, b.disparity, b.best_cost, s);
  check_launch("choose_kernel");
}

}  // namespace robotperf::perception::cuda
