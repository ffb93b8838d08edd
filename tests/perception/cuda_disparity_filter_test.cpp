// The cuda backend's speckle filter against filter_on_host (OpenCV's cv::filterSpeckles) on the
// same disparity: the same answer, pixel for pixel. Built against the host emulation of the CUDA
// runtime on every machine, and against CUDA where the toolkit is (there it needs a device, and
// shows the union-find's answer under a GPU's real concurrency).
#include <gtest/gtest.h>

#include <cstdint>
#include <opencv2/core.hpp>
#include <random>
#include <string>
#include <vector>

#include "cuda/cuda_support.hpp"
#include "cuda_test_support.hpp"
#include "stereo_bm_device.hpp"

namespace robotperf::perception {
namespace {

// A fixed-point disparity of sloping surfaces, with blobs of other values (speckles of many
// sizes), holes of invalid pixels and noise.
void make_disparity(uint32_t seed, cv::Mat& disparity, int invalid) {
  std::mt19937 random(seed);
  const int rows = disparity.rows, cols = disparity.cols;
  for (int y = 0; y < rows; ++y)
    for (int x = 0; x < cols; ++x)
      disparity.at<int16_t>(y, x) = static_cast<int16_t>(16 * (8 + x / 24 + y / 40) + (x + y) % 3);
  std::uniform_int_distribution<int> row(0, rows - 1), col(0, cols - 1), size(1, 14),
      value(0, 63 * 16);
  for (int blob = 0; blob < 120; ++blob) {
    const int y0 = row(random), x0 = col(random), h = size(random), w = size(random);
    const int v = blob % 5 == 0 ? invalid : value(random);
    for (int y = y0; y < std::min(rows, y0 + h); ++y)
      for (int x = x0; x < std::min(cols, x0 + w); ++x)
        disparity.at<int16_t>(y, x) = static_cast<int16_t>(v == invalid ? v : v + (x % 2));
  }
}

// The filter's parameters, with a3's range of disparities.
StereoParams speckle_params(int min_disparity, int speckle_size, int speckle_range) {
  StereoParams params;
  params.min_disparity = min_disparity;
  params.disparity_range = 64;
  params.speckle_size = speckle_size;
  params.speckle_range = speckle_range;
  return params;
}

cv::Mat on_device(const cv::Mat& disparity, const BlockMatchingShape& shape,
                  const StereoParams& params) {
  using cuda::Buffer;
  using cuda::Memory;
  const std::size_t pixels = disparity.total();
  cuda::Stream stream;
  Buffer d{Memory::kDevice}, labels{Memory::kDevice}, sizes{Memory::kDevice};
  cuda::DisparityFilterBuffers b;
  b.disparity = d.reserve_for<int16_t>(pixels);
  b.labels = labels.reserve_for<int32_t>(pixels);
  b.region_sizes = sizes.reserve_for<int32_t>(pixels);
  cuda::check(cudaMemcpyAsync(b.disparity, disparity.data, pixels * 2, cudaMemcpyHostToDevice,
                              stream.get()),
              "upload");
  cuda::filter_disparity(shape, cuda::disparity_filter(params), b, stream.get());
  cv::Mat out(disparity.size(), CV_16SC1);
  cuda::check(
      cudaMemcpyAsync(out.data, b.disparity, pixels * 2, cudaMemcpyDeviceToHost, stream.get()),
      "download");
  stream.synchronize();
  return out;
}

TEST(DisparityFilterCuda, GivesOpenCvsSpeckleFilter) {
  if (const std::string why = without_cuda(); !why.empty()) GTEST_SKIP() << why;
  struct Case {
    int speckle_size, speckle_range;
  };
  for (const Case k : {Case{100, 4}, Case{20, 16}, Case{400, 0}, Case{50, 2}}) {
    for (const uint32_t seed : {1u, 2u, 3u}) {
      const StereoParams params =
          speckle_params(seed == 3 ? 4 : 0, k.speckle_size, k.speckle_range);
      const int invalid = (params.min_disparity - 1) * 16;
      // Whole blocks of the kernels' 32 x 8 threads, and blocks cut at the right and the bottom.
      cv::Mat disparity = seed == 2 ? cv::Mat(117, 203, CV_16SC1) : cv::Mat(120, 200, CV_16SC1);
      make_disparity(seed, disparity, invalid);
      cv::Mat expected = disparity.clone();
      filter_on_host(expected, params);
      const cv::Mat got = on_device(
          disparity, block_matching_shape(disparity.rows, disparity.cols, params), params);
      const std::string what = "speckles " + std::to_string(k.speckle_size) + "/" +
                               std::to_string(k.speckle_range) + ", seed " + std::to_string(seed);
      EXPECT_EQ(cv::countNonZero(got != expected), 0) << what;
      // The case changed something, so that agreeing means something.
      EXPECT_GT(cv::countNonZero(expected != disparity), 0) << what;
    }
  }
}

// One region winding through every block, a column at a time (down one, up the next, joined at
// alternate ends): kept, though what each block holds of it alone is a speckle. Its union-find
// trees are the deepest an image of this size gives, and one join missed across a block's edge
// cuts it into speckles. Beside it, columns on their own, which go.
TEST(DisparityFilterCuda, KeepsARegionWindingThroughEveryBlock) {
  if (const std::string why = without_cuda(); !why.empty()) GTEST_SKIP() << why;
  const StereoParams params = speckle_params(0, 3000, 1);
  const int invalid = (params.min_disparity - 1) * 16;
  const int rows = 133, cols = 150, winding_cols = 96;
  cv::Mat disparity(rows, cols, CV_16SC1, cv::Scalar(invalid));
  for (int x = 0; x < cols; x += 2) {
    for (int y = 0; y < rows; ++y) disparity.at<int16_t>(y, x) = static_cast<int16_t>(300 + y % 2);
    if (x + 2 < winding_cols) disparity.at<int16_t>(x % 4 == 0 ? rows - 1 : 0, x + 1) = 300;
  }
  cv::Mat expected = disparity.clone();
  filter_on_host(expected, params);
  ASSERT_EQ(expected.at<int16_t>(rows / 2, 0), 300) << "the winding region is kept";
  ASSERT_EQ(expected.at<int16_t>(rows / 2, cols - 2), invalid) << "a column alone goes";
  const cv::Mat got = on_device(disparity, block_matching_shape(rows, cols, params), params);
  EXPECT_EQ(cv::countNonZero(got != expected), 0);
}

}  // namespace
}  // namespace robotperf::perception
