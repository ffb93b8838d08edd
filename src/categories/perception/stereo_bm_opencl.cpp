// StereoBM on an OpenCL device: OpenCV's block matcher as its documentation and source define it
// (x-Sobel pre-filter clipped to [-cap, cap], sum of absolute differences over the window,
// texture and uniqueness checks, sub-pixel fit of the three costs around the best, the valid
// region), which OpenCV's own OpenCL StereoBM does only without the texture check. The speckle
// filter (connected components, sequential) runs on the host after the download, with OpenCV's
// own function, as part of the kernel's time.
#include "stereo_bm_opencl.hpp"

#include <algorithm>
#include <cstdint>
#include <limits>
#include <opencv2/core/ocl.hpp>
#include <stdexcept>
#include <string>

#include "device_stage.hpp"
#include "stereo_bm_device.hpp"

namespace robotperf::perception {
namespace {

// The cost volume is kept whole on the device, an int per pixel and disparity (and one plane for
// the texture): sliding sums along the rows, then along the columns.
const char* const kStereoBmSource = R"CL(
// x-Sobel of rows y-1, y, y+1 (mirrored at the top and bottom rows), clipped and offset to
// [0, 2 cap]; the first and last columns read cap, and so does the last row of an odd height
// (OpenCV filters rows in pairs and fills a row left over with cap).
__kernel void prefilter(__global const uchar* src, int src_step, int src_offset,
                        __global uchar* dst, int dst_step, int dst_offset, int rows, int cols,
                        int cap) {
  const int x = get_global_id(0), y = get_global_id(1);
  if (x >= cols || y >= rows) return;
  __global uchar* out = dst + dst_offset + y * dst_step + x;
  if (x == 0 || x == cols - 1 || (rows % 2 == 1 && y == rows - 1)) {
    *out = (uchar)cap;
    return;
  }
  const int up = y > 0 ? y - 1 : (rows > 1 ? 1 : 0);
  const int down = y < rows - 1 ? y + 1 : (rows > 1 ? rows - 2 : 0);
  __global const uchar* r0 = src + src_offset + up * src_step;
  __global const uchar* r1 = src + src_offset + y * src_step;
  __global const uchar* r2 = src + src_offset + down * src_step;
  const int d = (r0[x + 1] - r0[x - 1]) + 2 * (r1[x + 1] - r1[x - 1]) + (r2[x + 1] - r2[x - 1]);
  *out = (uchar)(clamp(d, -cap, cap) + cap);
}

// The cost of pixel column c for disparity index k (disparity = lofs - k), the columns clamped as
// OpenCV clamps them; index ndisp is the texture, |L - cap|.
int column_cost(__global const uchar* l, __global const uchar* r, int c, int k, int cols, int ndisp,
                int lofs, int cap) {
  const int lc = clamp(c, 0, cols - 1);
  if (k == ndisp) return abs((int)l[lc] - cap);
  return abs((int)l[lc] - (int)r[min(max(c - lofs, 0) + k, cols - 1)]);
}

// Per row and disparity index: the window's horizontal sums along the row, sliding.
__kernel void row_costs(__global const uchar* left, int left_step, int left_offset,
                        __global const uchar* right, int right_step, int right_offset,
                        __global int* rows_cost, int rows, int cols, int ndisp, int lofs,
                        int radius, int cap) {
  const int y = get_global_id(0), k = get_global_id(1);
  if (y >= rows || k > ndisp) return;
  __global const uchar* l = left + left_offset + y * left_step;
  __global const uchar* r = right + right_offset + y * right_step;
  __global int* out = rows_cost + ((size_t)k * rows + y) * cols;
  int sum = 0;
  for (int i = -radius; i <= radius; ++i) sum += column_cost(l, r, i, k, cols, ndisp, lofs, cap);
  out[0] = sum;
  for (int x = 1; x < cols; ++x) {
    sum += column_cost(l, r, x + radius, k, cols, ndisp, lofs, cap) -
           column_cost(l, r, x - radius - 1, k, cols, ndisp, lofs, cap);
    out[x] = sum;
  }
}

// Per column and disparity index: the window's vertical sums of the row sums, sliding, the rows
// clamped at the top and bottom.
__kernel void window_costs(__global const int* rows_cost, __global int* costs, int rows, int cols,
                           int ndisp, int radius) {
  const int x = get_global_id(0), k = get_global_id(1);
  if (x >= cols || k > ndisp) return;
  __global const int* in = rows_cost + (size_t)k * rows * cols + x;
  __global int* out = costs + (size_t)k * rows * cols + x;
  int sum = 0;
  for (int j = -radius; j <= radius; ++j) sum += in[(size_t)clamp(j, 0, rows - 1) * cols];
  out[0] = sum;
  for (int y = 1; y < rows; ++y) {
    sum += in[(size_t)min(y + radius, rows - 1) * cols] - in[(size_t)max(y - radius - 1, 0) * cols];
    out[(size_t)y * cols] = sum;
  }
}

// Per pixel of the region where the window and the search range fit ([x0, x1) x [y0, y1), as
// OpenCV's valid disparity ROI): the best disparity, the texture and uniqueness checks, and the
// fixed-point (1/16 px) disparity with OpenCV's sub-pixel fit of the costs on either side.
__kernel void choose(__global const int* costs, __global short* disp, int disp_step,
                     int disp_offset, int rows, int cols, int ndisp, int lofs, int mindisp,
                     int texture_threshold, int uniqueness, int x0, int x1, int y0, int y1) {
  const int x = get_global_id(0), y = get_global_id(1);
  if (x >= cols || y >= rows) return;
  __global short* out = (__global short*)((__global uchar*)disp + disp_offset + y * disp_step) + x;
  const short filtered = (short)((mindisp - 1) * 16);
  const size_t plane = (size_t)rows * cols, at = (size_t)y * cols + x;
  if (x < x0 || x >= x1 || y < y0 || y >= y1 || costs[ndisp * plane + at] < texture_threshold) {
    *out = filtered;
    return;
  }
  int best = INT_MAX, best_k = 0;
  for (int k = 0; k < ndisp; ++k) {
    const int c = costs[k * plane + at];
    if (c < best) {
      best = c;
      best_k = k;
    }
  }
  if (uniqueness > 0) {
    const int limit = best + best * uniqueness / 100;
    for (int k = 0; k < ndisp; ++k) {
      if ((k < best_k - 1 || k > best_k + 1) && costs[k * plane + at] <= limit) {
        *out = filtered;
        return;
      }
    }
  }
  if (best_k == 0 || best_k == ndisp - 1) {
    *out = (short)((ndisp - best_k - 1 + mindisp) * 16);
    return;
  }
  const int p = costs[(best_k + 1) * plane + at];
  const int n = costs[(best_k - 1) * plane + at];
  const int d = p + n - 2 * best + abs(p - n);
  *out = (short)(((ndisp - best_k - 1 + mindisp) * 256 + (d != 0 ? (p - n) * 256 / d : 0) + 15) >>
                 4);
}
)CL";

cv::ocl::Kernel build(const char* name) {
  static const cv::ocl::ProgramSource source(kStereoBmSource);
  cv::ocl::Kernel kernel(name, source);
  if (kernel.empty())
    throw std::runtime_error(std::string("disparity: the OpenCL kernel ") + name +
                             " did not build");
  return kernel;
}

void run(cv::ocl::Kernel& kernel, std::size_t x, std::size_t y) {
  std::size_t global[2] = {x, y};
  if (!kernel.run(2, global, nullptr, true))
    throw std::runtime_error("disparity: an OpenCL kernel did not run");
}

}  // namespace

void OpenClBlockMatcher::compute(const cv::Mat& left, const cv::Mat& right, const StereoParams& p,
                                 cv::Mat& disparity16) {
  if (p.algorithm != StereoAlgorithm::kBlockMatching)
    throw std::invalid_argument("disparity: the opencl backend has StereoBM only");
  if (p.min_disparity < 0)
    throw std::invalid_argument("disparity: the opencl backend needs min_disparity >= 0");
  const BlockMatchingShape s = block_matching_shape(left.rows, left.cols, p);
  const int rows = s.rows, cols = s.cols;
  // The cost volumes, an int per pixel and disparity and one plane for the texture, each one
  // buffer on the device: no larger than the device allocates at once.
  const std::size_t planes = static_cast<std::size_t>(s.disparities) + 1;
  const std::size_t volume_bytes =
      planes * static_cast<std::size_t>(rows) * static_cast<std::size_t>(cols) * sizeof(int32_t);
  const std::size_t max_alloc = cv::ocl::Device::getDefault().maxMemAllocSize();
  if (volume_bytes > max_alloc ||
      planes * rows > static_cast<std::size_t>(std::numeric_limits<int>::max())) {
    throw std::invalid_argument(
        "disparity: the opencl backend's two cost volumes for " + std::to_string(cols) + "x" +
        std::to_string(rows) + " images and disparity_range " + std::to_string(s.disparities) +
        " are " + std::to_string(volume_bytes) + " bytes each, more than the device allocates at " +
        "once (" + std::to_string(max_alloc) +
        " bytes, CL_DEVICE_MAX_MEM_ALLOC_SIZE); reduce disparity_range or use the cpu or cuda "
        "backend");
  }
  const int volume_rows = static_cast<int>(planes * rows);
  {
    DeviceStage upload("upload", left.total() + right.total(), opencl_queue());
    left.copyTo(left_);
    right.copyTo(right_);
  }
  filtered_left_.create(rows, cols, CV_8UC1);
  filtered_right_.create(rows, cols, CV_8UC1);
  row_costs_.create(volume_rows, cols, CV_32SC1);
  costs_.create(volume_rows, cols, CV_32SC1);
  disparity_.create(rows, cols, CV_16SC1);
  if (choose_.empty()) {
    prefilter_ = build("prefilter");
    row_kernel_ = build("row_costs");
    window_kernel_ = build("window_costs");
    choose_ = build("choose");
  }
  {
    DeviceStage stage("compute", 0, opencl_queue());
    for (auto [in, out] : {std::pair{&left_, &filtered_left_}, {&right_, &filtered_right_}}) {
      prefilter_.args(cv::ocl::KernelArg::ReadOnlyNoSize(*in),
                      cv::ocl::KernelArg::WriteOnlyNoSize(*out), rows, cols, s.prefilter_cap);
      run(prefilter_, static_cast<std::size_t>(cols), static_cast<std::size_t>(rows));
    }
    row_kernel_.args(cv::ocl::KernelArg::ReadOnlyNoSize(filtered_left_),
                     cv::ocl::KernelArg::ReadOnlyNoSize(filtered_right_),
                     cv::ocl::KernelArg::PtrWriteOnly(row_costs_), rows, cols, s.disparities,
                     s.right_offset, s.radius, s.prefilter_cap);
    run(row_kernel_, static_cast<std::size_t>(rows), static_cast<std::size_t>(s.disparities + 1));
    window_kernel_.args(cv::ocl::KernelArg::PtrReadOnly(row_costs_),
                        cv::ocl::KernelArg::PtrWriteOnly(costs_), rows, cols, s.disparities,
                        s.radius);
    run(window_kernel_, static_cast<std::size_t>(cols),
        static_cast<std::size_t>(s.disparities + 1));
    choose_.args(cv::ocl::KernelArg::PtrReadOnly(costs_),
                 cv::ocl::KernelArg::WriteOnlyNoSize(disparity_), rows, cols, s.disparities,
                 s.right_offset, s.min_disparity, s.texture_threshold, s.uniqueness_ratio, s.x0,
                 s.x1, s.y0, s.y1);
    run(choose_, static_cast<std::size_t>(cols), static_cast<std::size_t>(rows));
  }
  {
    DeviceStage download("download", static_cast<uint64_t>(rows) * cols * 2, opencl_queue());
    disparity_.copyTo(disparity16);
  }
  filter_on_host(disparity16, p);
}

}  // namespace robotperf::perception
