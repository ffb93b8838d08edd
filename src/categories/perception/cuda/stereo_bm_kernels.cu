// StereoBM's device part, the stages of robotperf's OpenCL StereoBM (stereo_bm_opencl.cpp) with
// the same integer arithmetic: the x-Sobel pre-filter, the window costs of every disparity, the
// texture and uniqueness checks and the sub-pixel fit. A block matches a tile of pixels with the
// column sums of its windows in shared memory and each pixel's search in registers, so that no
// cost volume goes through device memory (a separate pass per sum and a volume of 80 MB for a3
// took 0.73 of its 0.94 ms of compute on an H100). The column sums are summed along each tile
// row, so that a window's cost is two reads, not one per window column (15 at a3's window).
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

__device__ int clamped(int v, int low, int high) {
  return min(max(v, low), high);
}

// x-Sobel of rows y-1, y, y+1 (mirrored at the top and bottom rows), clipped and offset to
// [0, 2 cap]; the first and last columns read cap, and so does the last row of an odd height
// (OpenCV filters rows in pairs and fills a row left over with cap).
__global__ void prefilter_kernel(const uint8_t* src, uint8_t* dst, int rows, int cols, int cap) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x;
  const int y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= cols || y >= rows) return;
  uint8_t* out = dst + static_cast<size_t>(y) * cols + x;
  if (x == 0 || x == cols - 1 || (rows % 2 == 1 && y == rows - 1)) {
    *out = static_cast<uint8_t>(cap);
    return;
  }
  const int up = y > 0 ? y - 1 : (rows > 1 ? 1 : 0);
  const int down = y < rows - 1 ? y + 1 : (rows > 1 ? rows - 2 : 0);
  const uint8_t* r0 = src + static_cast<size_t>(up) * cols;
  const uint8_t* r1 = src + static_cast<size_t>(y) * cols;
  const uint8_t* r2 = src + static_cast<size_t>(down) * cols;
  const int d = (r0[x + 1] - r0[x - 1]) + 2 * (r1[x + 1] - r1[x - 1]) + (r2[x + 1] - r2[x - 1]);
  *out = static_cast<uint8_t>(clamped(d, -cap, cap) + cap);
}

// The matcher's tile: the pixels of a block, a warp along each of 8 rows.
constexpr int kTileCols = 32, kTileRows = 8, kTileThreads = kTileCols * kTileRows;

#if defined(__CUDA_ARCH__) && __CUDA_ARCH__ < 800
constexpr int kMatchBlocksPerSm = 4;
#else
constexpr int kMatchBlocksPerSm = 6;
#endif

// A matcher block's shared memory: for a batch of disparity indices, each tile row's column sums
// across the halo columns, then summed along the row in place (uint32_t: a row's sum can exceed
// 16 bits), each row `line` entries apart (odd, so that the threads summing rows read different
// banks); then the pre-filtered left and right pixels the tile's windows cover (rows first),
// clamped to the image.
struct MatchTiles {
  int halo_cols = 0;   // the tile's columns and a window radius either side
  int halo_rows = 0;   // the same for rows
  int right_cols = 0;  // the right image's columns the windows reach: halo_cols + disparities - 1
  int line = 0;        // entries from one row's sums to the next: halo_cols, or one more if even
  int batch = 0;       // disparity indices a turn
};

std::size_t shared_bytes(const MatchTiles& t) {
  return sizeof(uint32_t) * static_cast<std::size_t>(t.batch) * kTileRows * t.line +
         static_cast<std::size_t>(t.halo_rows) * (t.halo_cols + t.right_cols);
}

// A pixel's search in disparity order, in registers: the least cost (the first of equals, as
// OpenCV keeps it) with the costs either side for the sub-pixel fit, and the four least costs,
// among which is the least outside the best and its two neighbours, all that the uniqueness
// check needs.
struct Search {
  int best = INT_MAX, best_k = 0, before = 0, after = 0, last = 0;
  int least[4] = {INT_MAX, INT_MAX, INT_MAX, INT_MAX};
  int least_k[4] = {-1, -1, -1, -1};

  __device__ void add(int k, int cost) {
    if (k == best_k + 1) after = cost;
    if (cost < best) {
      best = cost;
      best_k = k;
      before = last;
    }
    last = cost;
    if (cost >= least[3]) return;
    least[3] = cost;
    least_k[3] = k;
    for (int i = 3; i > 0; --i) {
      if (least[i] < least[i - 1]) {
        const int c = least[i], j = least_k[i];
        least[i] = least[i - 1];
        least_k[i] = least_k[i - 1];
        least[i - 1] = c;
        least_k[i - 1] = j;
      }
    }
  }

  // Whether a disparity other than the best and its neighbours costs within the uniqueness
  // ratio of the best.
  __device__ bool ambiguous(int ratio) const {
    const int limit = best + best * ratio / 100;
    for (int i = 0; i < 4; ++i) {
      if (least_k[i] >= 0 && (least_k[i] < best_k - 1 || least_k[i] > best_k + 1) &&
          least[i] <= limit) {
        return true;
      }
    }
    return false;
  }
};

// A block per tile of the valid region: its windows' pixels into shared memory, then, a batch of
// disparity indices at a time, the column sums of every tile row and halo column, summed along
// each row, so that a pixel's window cost is the difference of two of them; then the texture and
// uniqueness checks and the fixed-point (1/16 px) disparity with OpenCV's sub-pixel fit. Index
// `disparities` is the texture, |L - cap|. Inside the valid region no window column or row is
// clamped (min_disparity >= 0), so the clamping of the tiles only keeps the tile's part past that
// region inside the image. Registers for six blocks an SM (40 a thread; the compiler took 48, for
// five), as the matcher had before it summed along the rows; four on Turing, whose SM holds 1024
// threads.
__global__ void __launch_bounds__(kTileThreads, kMatchBlocksPerSm)
    match_kernel(const uint8_t* left, const uint8_t* right, int16_t* disparity,
                 BlockMatchingShape s, MatchTiles t) {
  const int tx = static_cast<int>(threadIdx.x), ty = static_cast<int>(threadIdx.y);
  const int id = ty * kTileCols + tx;
  const int tile_x = s.x0 + static_cast<int>(blockIdx.x) * kTileCols;
  const int tile_y = s.y0 + static_cast<int>(blockIdx.y) * kTileRows;
  const int window = 2 * s.radius + 1;
  uint32_t* sums = dynamic_shared<uint32_t>();
  uint8_t* left_tile =
      reinterpret_cast<uint8_t*>(sums + static_cast<std::size_t>(t.batch) * kTileRows * t.line);
  uint8_t* right_tile = left_tile + t.halo_rows * t.halo_cols;
  for (int i = id; i < t.halo_rows * t.halo_cols; i += kTileThreads) {
    const int y = clamped(tile_y - s.radius + i / t.halo_cols, 0, s.rows - 1);
    const int x = clamped(tile_x - s.radius + i % t.halo_cols, 0, s.cols - 1);
    left_tile[i] = left[static_cast<std::size_t>(y) * s.cols + x];
  }
  for (int i = id; i < t.halo_rows * t.right_cols; i += kTileThreads) {
    const int y = clamped(tile_y - s.radius + i / t.right_cols, 0, s.rows - 1);
    const int x = clamped(tile_x - s.radius - s.right_offset + i % t.right_cols, 0, s.cols - 1);
    right_tile[i] = right[static_cast<std::size_t>(y) * s.cols + x];
  }
  __syncthreads();
  Search search;
  int texture = 0;
  for (int k0 = 0; k0 <= s.disparities; k0 += t.batch) {
    const int count = min(t.batch, s.disparities + 1 - k0);
    // A thread per disparity index and halo column: its window's first sum whole, then slid down
    // the tile's rows.
    for (int i = id; i < count * t.halo_cols; i += kTileThreads) {
      const int c = i % t.halo_cols, b = i / t.halo_cols, k = k0 + b;
      const uint8_t* l = left_tile + c;
      const uint8_t* r = right_tile + c + k;
      // |L - R| at tile row j of this column, or the texture's |L - cap|.
      const auto cost_at = [&](int j) {
        const int lj = l[j * t.halo_cols];
        return abs(lj -
                   (k == s.disparities ? s.prefilter_cap : static_cast<int>(r[j * t.right_cols])));
      };
      int sum = 0;
      for (int j = 0; j < window; ++j) sum += cost_at(j);
      uint32_t* out = sums + b * kTileRows * t.line + c;
      out[0] = static_cast<uint32_t>(sum);
      for (int row = 1; row < kTileRows; ++row) {
        sum += cost_at(row + window - 1) - cost_at(row - 1);
        out[row * t.line] = static_cast<uint32_t>(sum);
      }
    }
    __syncthreads();
    // A thread per disparity index and tile row: the row's column sums summed along it.
    if (id < count * kTileRows) {
      uint32_t* row = sums + id * t.line;
      uint32_t total = 0;
      for (int c = 0; c < t.halo_cols; ++c) {
        total += row[c];
        row[c] = total;
      }
    }
    __syncthreads();
    for (int b = 0; b < count; ++b) {
      const uint32_t* row = sums + (b * kTileRows + ty) * t.line;
      const int cost = static_cast<int>(row[tx + window - 1] - (tx > 0 ? row[tx - 1] : 0u));
      if (k0 + b == s.disparities) {
        texture = cost;
      } else {
        search.add(k0 + b, cost);
      }
    }
    __syncthreads();
  }
  const int x = tile_x + tx, y = tile_y + ty;
  if (x >= s.x1 || y >= s.y1) return;
  const std::size_t at = static_cast<std::size_t>(y) * s.cols + x;
  const int16_t filtered = static_cast<int16_t>((s.min_disparity - 1) * 16);
  if (texture < s.texture_threshold ||
      (s.uniqueness_ratio > 0 && search.ambiguous(s.uniqueness_ratio))) {
    disparity[at] = filtered;
    return;
  }
  const int whole = s.disparities - search.best_k - 1 + s.min_disparity;
  if (search.best_k == 0 || search.best_k == s.disparities - 1) {
    disparity[at] = static_cast<int16_t>(whole * 16);
    return;
  }
  const int p = search.after, n = search.before;
  const int d = p + n - 2 * search.best + abs(p - n);
  disparity[at] = static_cast<int16_t>((whole * 256 + (d != 0 ? (p - n) * 256 / d : 0) + 15) >> 4);
}

// Every pixel outside the valid region: filtered.
__global__ void mark_unmatched_kernel(int16_t* disparity, BlockMatchingShape s) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x;
  const int y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= s.cols || y >= s.rows || (x >= s.x0 && x < s.x1 && y >= s.y0 && y < s.y1)) return;
  const std::size_t at = static_cast<std::size_t>(y) * s.cols + x;
  disparity[at] = static_cast<int16_t>((s.min_disparity - 1) * 16);
}

// ---------------------------------------------------------------------------------------------
// The speckle filter (cv::filterSpeckles): regions of 4-neighbours whose values differ by at most
// speckle_range, found by union-find with atomicMin (Playne and Hawick's GPU labelling); a region
// of at most speckle_size pixels becomes invalid. Each block first labels its own pixels in shared
// memory (the runs along each warp's row at once, then the rows joined), so that the trees in
// device memory join only blocks, not rows: a region as tall as the image made a chain of a run a
// row, walked a dependent read a step (0.1 ms of a3's 0.25 ms of compute on an H200). The regions,
// and so the answer, are OpenCV's whatever the order the threads run in.
// ---------------------------------------------------------------------------------------------

// The root of i's tree, each label passed on the way pointed at its grandparent (path halving),
// so that the threads that follow walk half as far. Safe beside concurrent unite()s: a label only
// ever points at a smaller pixel of the same region, and a root (whose label an atomicMin may be
// lowering) is never written here, as a pixel that has a parent never becomes a root again. Not
// where a thread writes a label that must stay: another thread's halving may overwrite it.
__device__ int find_root(int32_t* labels, int i) {
  while (true) {
    const int parent = labels[i];
    if (parent == i) return i;
    const int grandparent = labels[parent];
    if (grandparent == parent) return parent;
    labels[i] = grandparent;
    i = grandparent;
  }
}

// The root of i's tree, read without writing a label (see find_root).
__device__ int root_of(const int32_t* labels, int i) {
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

// Whether 4-neighbours a and b (both inside the image) join one region.
__device__ bool joined(const int16_t* disparity, int a, int b, int invalid, int max_diff) {
  const int da = disparity[a], db = disparity[b];
  return da != invalid && db != invalid && abs(da - db) <= max_diff;
}

// Whether pixel `at` and the one below it, joined, are joined already through their left
// neighbours: those two are joined to them and to each other (whose union their own thread makes).
__device__ bool joined_through_left(const int16_t* disparity, int at, int cols, int invalid,
                                    int max_diff) {
  return joined(disparity, at - 1, at, invalid, max_diff) &&
         joined(disparity, at - 1 + cols, at + cols, invalid, max_diff) &&
         joined(disparity, at - 1, at - 1 + cols, invalid, max_diff);
}

// The shared memory of init_regions_kernel: a label for each pixel of an image_block().
std::size_t block_labels_bytes() {
  const dim3 block = image_block();
  return static_cast<std::size_t>(block.x) * block.y * sizeof(int32_t);
}

// Labels each pixel with its region within its block (image_block(): a warp is a row of 32
// pixels): the runs of joined pixels along each warp's row from one ballot, each pixel pointing at
// its run's first, then the runs of the block's rows united in shared memory. Each pixel's label
// is then its block region's first pixel (in image order, so that labels still point at smaller
// pixels); invalid pixels get -1.
__global__ void init_regions_kernel(const int16_t* disparity, int32_t* labels,
                                    int32_t* region_sizes, int rows, int cols, int invalid,
                                    int max_diff) {
  int32_t* block_labels = dynamic_shared<int32_t>();
  const int x = blockIdx.x * blockDim.x + threadIdx.x;
  const int y = blockIdx.y * blockDim.y + threadIdx.y;
  const bool inside = x < cols && y < rows;
  const int at = y * cols + x;
  const bool valid = inside && disparity[at] != invalid;
  const unsigned lane = lane_id();
  const int me = static_cast<int>(threadIdx.y * blockDim.x + threadIdx.x);
  // A run starts at a valid pixel its left neighbour in the warp does not join.
  const bool starts = valid && (lane == 0 || !joined(disparity, at - 1, at, invalid, max_diff));
  const unsigned starts_here_or_before = __ballot_sync(0xffffffffu, starts) & ((2u << lane) - 1u);
  block_labels[me] =
      valid ? me - static_cast<int>(lane) + (31 - __clz(static_cast<int>(starts_here_or_before)))
            : -1;
  __syncthreads();
  if (valid && threadIdx.y + 1 < blockDim.y && y + 1 < rows &&
      joined(disparity, at, at + cols, invalid, max_diff) &&
      !(lane > 0 && joined_through_left(disparity, at, cols, invalid, max_diff)))
    unite(block_labels, me, me + static_cast<int>(blockDim.x));
  __syncthreads();
  if (!inside) return;
  if (valid) {
    const int root = find_root(block_labels, me);
    labels[at] = static_cast<int>(blockIdx.y * blockDim.y + root / blockDim.x) * cols +
                 static_cast<int>(blockIdx.x * blockDim.x + root % blockDim.x);
  } else {
    labels[at] = -1;
  }
  region_sizes[at] = 0;
}

// Joins the block regions across the blocks' edges: a block's last column with the next block's
// first, and its last row with the next block's first, but for a pair joined already through
// their left neighbours.
__global__ void join_regions_kernel(const int16_t* disparity, int32_t* labels, int rows, int cols,
                                    int invalid, int max_diff) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x;
  const int y = blockIdx.y * blockDim.y + threadIdx.y;
  const bool last_column = threadIdx.x + 1 == blockDim.x, last_row = threadIdx.y + 1 == blockDim.y;
  if (x >= cols || y >= rows || (!last_column && !last_row)) return;
  const int at = y * cols + x;
  if (labels[at] < 0) return;
  if (last_column && x + 1 < cols && joined(disparity, at, at + 1, invalid, max_diff))
    unite(labels, at, at + 1);
  if (!last_row || y + 1 >= rows || !joined(disparity, at, at + cols, invalid, max_diff)) return;
  if (!(x > 0 && joined_through_left(disparity, at, cols, invalid, max_diff)))
    unite(labels, at, at + cols);
}

// Every pixel's root, and its region's size: the lanes of a warp in one region add their count
// once (a large region fills whole warps, whose atomics on its one counter would queue). The walk
// to the root writes no label, so that each pixel's root, written here, stays for
// remove_speckles_kernel (find_root's halving in another thread could point it at a mere
// ancestor, whose region size is 0).
__global__ void count_regions_kernel(int32_t* labels, int32_t* region_sizes, int rows, int cols) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x;
  const int y = blockIdx.y * blockDim.y + threadIdx.y;
  const int at = y * cols + x;
  int root = -1;
  if (x < cols && y < rows && labels[at] >= 0) {
    root = root_of(labels, at);
    labels[at] = root;
  }
  const unsigned same = __match_any_sync(0xffffffffu, root);
  if (root >= 0 && lane_id() == static_cast<unsigned>(__ffs(static_cast<int>(same)) - 1))
    atomicAdd(&region_sizes[root], __popc(same));
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

// A block's shared memory at most: what every device gives without asking.
constexpr std::size_t kSharedLimit = 48 * 1024;

// The tiles of windows of `radius` and `disparities` indices, with the largest batch (at most 32)
// whose shared memory fits; throws where not even one disparity a turn fits.
MatchTiles match_tiles(int radius, int disparities) {
  MatchTiles t;
  t.halo_cols = kTileCols + 2 * radius;
  t.halo_rows = kTileRows + 2 * radius;
  t.right_cols = t.halo_cols + disparities - 1;
  t.line = t.halo_cols | 1;
  t.batch = 32;
  while (t.batch > 1 && shared_bytes(t) > kSharedLimit) t.batch /= 2;
  if (radius < 0 || disparities <= 0 || shared_bytes(t) > kSharedLimit) {
    throw std::invalid_argument(
        "cuda: block matching with a window of " + std::to_string(2 * radius + 1) + " px and " +
        std::to_string(disparities) + " disparities needs " + std::to_string(shared_bytes(t)) +
        " bytes of shared memory a block, more than the 48 KiB it may take; use a smaller window "
        "or range, or the opencl or cpu backend");
  }
  return t;
}

}  // namespace

void check_block_matching(int radius, int disparities) {
  match_tiles(radius, disparities);
}

void filter_disparity(const BlockMatchingShape& s, const DisparityFilter& f,
                      const DisparityFilterBuffers& b, cudaStream_t stream) {
  // The labels are pixel indices in an int.
  if (static_cast<long long>(s.rows) * s.cols > INT_MAX) {
    throw std::invalid_argument("cuda: disparity filter: " + std::to_string(s.cols) + "x" +
                                std::to_string(s.rows) + " images do not fit");
  }
  const dim3 block = image_block(), pixels = image_grid(s.cols, s.rows);
  const int invalid = (s.min_disparity - 1) * 16;
  if (f.speckle_size > 0 && f.speckle_range >= 0) {
    launch_synchronising(init_regions_kernel, pixels, block, block_labels_bytes(), stream,
                         static_cast<const int16_t*>(b.disparity), b.labels, b.region_sizes, s.rows,
                         s.cols, invalid, f.speckle_range);
    check_launch("init_regions_kernel");
    launch(join_regions_kernel, pixels, block, stream, static_cast<const int16_t*>(b.disparity),
           b.labels, s.rows, s.cols, invalid, f.speckle_range);
    check_launch("join_regions_kernel");
    launch_synchronising(count_regions_kernel, pixels, block, 0, stream, b.labels, b.region_sizes,
                         s.rows, s.cols);
    check_launch("count_regions_kernel");
    launch(remove_speckles_kernel, pixels, block, stream, b.disparity,
           static_cast<const int32_t*>(b.labels), static_cast<const int32_t*>(b.region_sizes),
           s.rows, s.cols, invalid, f.speckle_size);
    check_launch("remove_speckles_kernel");
  }
}

void block_match(const BlockMatchingShape& s, const BlockMatchingBuffers& b, cudaStream_t stream) {
  const MatchTiles t = match_tiles(s.radius, s.disparities);
  if (s.rows <= 0 || s.cols <= 0 || s.rows > 65535 * kTileRows) {  // gridDim.y <= 65535
    throw std::invalid_argument("cuda: block matching: " + std::to_string(s.cols) + "x" +
                                std::to_string(s.rows) + " images do not fit");
  }
  const dim3 block = image_block(), pixels = image_grid(s.cols, s.rows);
  launch(prefilter_kernel, pixels, block, stream, b.left, b.filtered_left, s.rows, s.cols,
         s.prefilter_cap);
  check_launch("prefilter_kernel");
  launch(prefilter_kernel, pixels, block, stream, b.right, b.filtered_right, s.rows, s.cols,
         s.prefilter_cap);
  check_launch("prefilter_kernel");
  launch(mark_unmatched_kernel, pixels, block, stream, b.disparity, s);
  check_launch("mark_unmatched_kernel");
  if (s.x1 <= s.x0 || s.y1 <= s.y0) return;
  const dim3 tiles((s.x1 - s.x0 + kTileCols - 1) / kTileCols,
                   (s.y1 - s.y0 + kTileRows - 1) / kTileRows);
  launch_synchronising(match_kernel, tiles, dim3(kTileCols, kTileRows), shared_bytes(t), stream,
                       static_cast<const uint8_t*>(b.filtered_left),
                       static_cast<const uint8_t*>(b.filtered_right), b.disparity, s, t);
  check_launch("match_kernel");
}

}  // namespace robotperf::perception::cuda
