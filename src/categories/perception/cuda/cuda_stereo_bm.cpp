// The cuda backend's StereoBM on a node's own stream: the pair up, the block matching and the
// speckle filter after it on the device (stereo_bm_kernels.cu), the disparity down. The opencl
// backend runs that filter on the host (filter_on_host); this gives its answer.
#include <cstdint>
#include <stdexcept>

#include "../stereo_bm_device.hpp"
#include "cuda_backend.hpp"
#include "cuda_support.hpp"
#include "robotperf/perception/cuda_device.hpp"

namespace robotperf::perception::cuda {
namespace {

class CudaBlockMatcher final : public BlockMatcher {
 public:
  void compute(const cv::Mat& left, const cv::Mat& right, const StereoParams& params,
               cv::Mat& disparity16, const std::function<void()>& meanwhile) override {
    if (left.type() != CV_8UC1 || right.type() != CV_8UC1 || left.size() != right.size())
      throw std::logic_error("cuda: block matching takes a mono8 pair of one size");
    const BlockMatchingShape s = block_matching_shape(left.rows, left.cols, params);
    const std::size_t pixels = left.total();
    BlockMatchingBuffers b;
    b.filtered_left = filtered_left_.reserve_for<uint8_t>(pixels);
    b.filtered_right = filtered_right_.reserve_for<uint8_t>(pixels);
    b.disparity = static_cast<int16_t*>(disparity_.reserve(s.rows, s.cols, CV_16SC1).data);
    DisparityFilterBuffers f;
    f.disparity = b.disparity;
    f.labels = labels_.reserve_for<int32_t>(pixels);
    f.region_sizes = region_sizes_.reserve_for<int32_t>(pixels);
    {
      DeviceStage upload("upload", left.total() + right.total(), stream_);
      b.left = static_cast<const uint8_t*>(left_.upload(left, stream_.get()).data);
      b.right = static_cast<const uint8_t*>(right_.upload(right, stream_.get()).data);
    }
    {
      DeviceStage compute("compute", 0, stream_);
      block_match(s, b, stream_.get());
      filter_disparity(s, disparity_filter(params), f, stream_.get());
    }
    download_overlapped(stream_, disparity_, [&] {
      meanwhile();
      disparity16.create(s.rows, s.cols, CV_16SC1);
      return disparity16;
    });
  }

 private:
  Stream stream_;
  StagedImage left_, right_, disparity_;
  Buffer filtered_left_{Memory::kDevice}, filtered_right_{Memory::kDevice};
  Buffer labels_{Memory::kDevice}, region_sizes_{Memory::kDevice};
};

}  // namespace

DisparityFilter disparity_filter(const StereoParams& params) {
  DisparityFilter f;
  f.speckle_size = params.speckle_size;
  f.speckle_range = params.speckle_range;
  return f;
}

std::unique_ptr<BlockMatcher> make_block_matcher(const StereoParams& params) {
  check_block_matching(params.correlation_window_size / 2, params.disparity_range);
  cuda_device();
  return std::make_unique<CudaBlockMatcher>();
}

}  // namespace robotperf::perception::cuda
