// StereoBM's device part, the stages of robotperf's OpenCL StereoBM (stereo_bm_opencl.cpp) with
// the same integer arithmetic: the x-Sobel pre-filter, the window costs of every disparity (the
// cost volume kept on the device), the texture and uniqueness checks and the sub-pixel fit. Each
// window sum is taken whole by its own thread rather than slid along a row as the OpenCL kernels
// do: integer sums, the same values, and a thread for every cost instead of one per row.
#include <algorithm>
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

// ---------------------------------------------------------------------------------------------
// The left-right check (cv::validateDisparity)
// ---------------------------------------------------------------------------------------------

// Each right-image pixel's best match among the left pixels of its row, packed so that atomicMin
// keeps what OpenCV's scan keeps: the least cost, then the leftmost column (its scan replaces a
// match only by a strictly cheaper one); the match's disparity rides in the low bits.
constexpr unsigned long long kNoMatch = ~0ull;

__device__ unsigned long long pack_match(int cost, int x, int disparity) {
  const unsigned cost_order = static_cast<unsigned>(cost) ^ 0x80000000u;  // signed order
  return static_cast<unsigned long long>(cost_order) << 32 |
         static_cast<unsigned long long>(static_cast<unsigned>(x)) << 16 |
         static_cast<uint16_t>(disparity);
}

__device__ int matched_disparity(unsigned long long match) {
  return static_cast<int16_t>(match & 0xffff);
}

__global__ void clear_matches_kernel(unsigned long long* right_match, int rows, int cols) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x;
  const int y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x < cols && y < rows) right_match[static_cast<size_t>(y) * cols + x] = kNoMatch;
}

// The columns OpenCV checks, [max(min_disparity + disparities, 0), cols + min(min_disparity, 0)).
struct CheckedColumns {
  int first = 0, end = 0;
};

__global__ void right_match_kernel(const int16_t* disparity, const int32_t* best_cost,
                                   unsigned long long* right_match, int rows, int cols,
                                   CheckedColumns columns, int invalid) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x;
  const int y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x < columns.first || x >= columns.end || y >= rows) return;
  const size_t at = static_cast<size_t>(y) * cols + x;
  const int d = disparity[at], cost = best_cost[at];
  // A cost of INT_MAX never replaces OpenCV's initial INT_MAX.
  if (d == invalid || cost == INT_MAX) return;
  const int x2 = x - ((d + 8) >> 4);
  if (x2 < 0 || x2 >= cols) return;
  atomicMin(&right_match[static_cast<size_t>(y) * cols + x2], pack_match(cost, x, d));
}

// Invalid where the disparity rounded down and rounded up both disagree by more than max_diff
// (1/16 px) with the right pixel's best match; a right pixel without one, or whose match is not
// above the invalid value (OpenCV's test), agrees.
__global__ void left_right_check_kernel(int16_t* disparity, const unsigned long long* right_match,
                                        int rows, int cols, CheckedColumns columns, int invalid,
                                        int max_diff) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x;
  const int y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x < columns.first || x >= columns.end || y >= rows) return;
  const size_t at = static_cast<size_t>(y) * cols + x;
  const int d = disparity[at];
  if (d == invalid) return;
  const unsigned long long* row = right_match + static_cast<size_t>(y) * cols;
  const auto disagrees = [&](int x2) {
    return x2 >= 0 && x2 < cols && row[x2] != kNoMatch && matched_disparity(row[x2]) > invalid &&
           abs(matched_disparity(row[x2]) - d) > max_diff;
  };
  if (disagrees(x - (d >> 4)) && disagrees(x - ((d + 15) >> 4))) {
    disparity[at] = static_cast<int16_t>(invalid);
  }
}

// ---------------------------------------------------------------------------------------------
// The speckle filter (cv::filterSpeckles): regions of 4-neighbours whose values differ by at most
// speckle_range, found by union-find with atomicMin (Playne and Hawick's GPU labelling); a region
// of at most speckle_size pixels becomes invalid. The regions, and so the answer, are OpenCV's
// whatever the order the threads run in.
// ---------------------------------------------------------------------------------------------

__device__ int find_root(const int32_t* labels, int i) {
  while (labels[i] != i) i = labels[i];
  return i;
}

// Joins the trees of a and b, each root pointing at the smaller; a thread that loses a race to
// another's atomicMin follows the value it found and tries again.
__device__ void unite(int32_t* labels, int a, int b) {
  while (true) {
    a = find_root(labels, a);
    b = find_root(labels, b);
    if (a == b) return;
    if (a < b) {
      const int old = atomicMin(&labels[b], a);
      if (old == b) return;
      b = old;
    } else {
      const int old = atomicMin(&labels[a], b);
      if (old == a) return;
      a = old;
    }
  }
}

__global__ void init_regions_kernel(const int16_t* disparity, int32_t* labels,
                                    int32_t* region_sizes, int rows, int cols, int invalid) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x;
  const int y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= cols || y >= rows) return;
  const int at = y * cols + x;
  labels[at] = disparity[at] != invalid ? at : -1;
  region_sizes[at] = 0;
}

__global__ void join_regions_kernel(const int16_t* disparity, int32_t* labels, int rows, int cols,
                                    int max_diff) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x;
  const int y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= cols || y >= rows) return;
  const int at = y * cols + x;
  if (labels[at] < 0) return;
  const int d = disparity[at];
  // The right and lower neighbours: every 4-neighbour pair once.
  if (x + 1 < cols && labels[at + 1] >= 0 && abs(d - disparity[at + 1]) <= max_diff)
    unite(labels, at, at + 1);
  if (y + 1 < rows && labels[at + cols] >= 0 && abs(d - disparity[at + cols]) <= max_diff)
    unite(labels, at, at + cols);
}

__global__ void count_regions_kernel(int32_t* labels, int32_t* region_sizes, int rows, int cols) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x;
  const int y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= cols || y >= rows) return;
  const int at = y * cols + x;
  if (labels[at] < 0) return;
  const int root = find_root(labels, at);
  labels[at] = root;
  atomicAdd(&region_sizes[root], 1);
}

__global__ void remove_speckles_kernel(int16_t* disparity, const int32_t* labels,
                                       const int32_t* region_sizes, int rows, int cols, int invalid,
                                       int speckle_size) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x;
  const int y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= cols || y >= rows) return;
  const int at = y * cols + x;
  if (labels[at] >= 0 && region_sizes[labels[at]] <= speckle_size)
    disparity[at] = static_cast<int16_t>(invalid);
}

}  // namespace

void filter_disparity(const BlockMatchingShape& s, const DisparityFilter& f,
                      const DisparityFilterBuffers& b, cudaStream_t stream) {
  // The packed matches keep a column in 16 bits; the labels are pixel indices in an int.
  if (s.cols > 65535 || static_cast<long long>(s.rows) * s.cols > INT_MAX) {
    throw std::invalid_argument("cuda: disparity filter: " + std::to_string(s.cols) + "x" +
                                std::to_string(s.rows) + " images do not fit");
  }
  const dim3 block = image_block(), pixels = image_grid(s.cols, s.rows);
  const int invalid = (s.min_disparity - 1) * 16;
  if (f.disp12_max_diff >= 0) {
    const CheckedColumns columns{std::max(s.min_disparity + s.disparities, 0),
                                 s.cols + std::min(s.min_disparity, 0)};
    launch(clear_matches_kernel, pixels, block, stream, b.right_match, s.rows, s.cols);
    check_launch("clear_matches_kernel");
    launch(right_match_kernel, pixels, block, stream, static_cast<const int16_t*>(b.disparity),
           b.best_cost, b.right_match, s.rows, s.cols, columns, invalid);
    check_launch("right_match_kernel");
    launch(left_right_check_kernel, pixels, block, stream, b.disparity,
           static_cast<const unsigned long long*>(b.right_match), s.rows, s.cols, columns, invalid,
           f.disp12_max_diff * 16);
    check_launch("left_right_check_kernel");
  }
  if (f.speckle_size > 0 && f.speckle_range >= 0) {
    launch(init_regions_kernel, pixels, block, stream, static_cast<const int16_t*>(b.disparity),
           b.labels, b.region_sizes, s.rows, s.cols, invalid);
    check_launch("init_regions_kernel");
    launch(join_regions_kernel, pixels, block, stream, static_cast<const int16_t*>(b.disparity),
           b.labels, s.rows, s.cols, f.speckle_range);
    check_launch("join_regions_kernel");
    launch(count_regions_kernel, pixels, block, stream, b.labels, b.region_sizes, s.rows, s.cols);
    check_launch("count_regions_kernel");
    launch(remove_speckles_kernel, pixels, block, stream, b.disparity,
           static_cast<const int32_t*>(b.labels), static_cast<const int32_t*>(b.region_sizes),
           s.rows, s.cols, invalid, f.speckle_size);
    check_launch("remove_speckles_kernel");
  }
}

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
