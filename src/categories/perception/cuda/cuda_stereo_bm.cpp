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
  cv::Mat compute(cv::Size size, const MonoWriter& left, const MonoWriter& right,
                  const StereoParams& params, const std::function<void()>& meanwhile) override {
    const BlockMatchingShape s = block_matching_shape(size.height, size.width, params);
    const std::size_t pixels = size.area();
    BlockMatchingBuffers b;
    b.filtered_left = filtered_left_.reserve_for<uint8_t>(pixels);
    b.filtered_right = filtered_right_.reserve_for<uint8_t>(pixels);
    b.disparity = static_cast<int16_t*>(disparity_.reserve(s.rows, s.cols, CV_16SC1).data);
    DisparityFilterBuffers f;
    f.disparity = b.disparity;
    f.labels = labels_.reserve_for<int32_t>(pixels);
    f.region_sizes = region_sizes_.reserve_for<int32_t>(pixels);
    // The left image goes up while the host converts the right one; the stage has what is left
    // of both transfers then.
    cv::Mat left_pixels = left_.staging(size.height, size.width, CV_8UC1);
    left(left_pixels);
    b.left = static_cast<const uint8_t*>(left_.queue_upload(stream_.get()).data);
    cv::Mat right_pixels = right_.staging(size.height, size.width, CV_8UC1);
    try {
      right(right_pixels);
    } catch (...) {
      stream_.finish();  // the left image's transfer leaves no work queued behind the error
      throw;
    }
    {
      DeviceStage upload("upload", 2 * pixels, stream_);
      b.right = static_cast<const uint8_t*>(right_.queue_upload(stream_.get()).data);
    }
    {
      DeviceStage compute("compute", 0, stream_);
      block_match(s, b, stream_.get());
      filter_disparity(s, disparity_filter(params), f, stream_.get());
    }
    disparity_.queue_download(stream_.get());
    meanwhile();
    {
      DeviceStage download("download", disparity_.bytes(), stream_);
      stream_.synchronize();
    }
    return disparity_.downloaded();
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
