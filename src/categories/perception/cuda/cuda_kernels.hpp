// Private to the cuda backend: its kernels, each queued on a stream, over dense images in device
// memory (rows of width x channels elements, no padding). Free of OpenCV: the .cu files include
// this and plain data only. Every launcher throws std::runtime_error when the launch fails.
#pragma once

#include <cuda_runtime.h>

#include <cstdint>

#include "../stereo_bm_shape.hpp"
#include "../xyzrgb_model.hpp"

namespace robotperf::perception::cuda {

// The element types of the images the kernels take, with 1 to 4 channels.
enum class PixelDepth { k8U, k16U, k32F };

struct DeviceImage {
  void* data = nullptr;
  int width = 0, height = 0;
};

// cv::remap(src, dst, map_xy, map_fraction, INTER_LINEAR, BORDER_CONSTANT, 0 or NaN for 32F) with
// OpenCV's fixed-point maps, one entry per dst pixel: map_xy the source pixel (x, y) of the
// top-left neighbour (CV_16SC2), map_fraction its 1/32-px fraction index (CV_16UC1, fy * 32 + fx).
void remap_linear(DeviceImage src, DeviceImage dst, PixelDepth depth, int channels,
                  const int16_t* map_xy, const uint16_t* map_fraction, cudaStream_t stream);

// One dst column's (or row's) source columns (rows) and their weights in cv::resize's
// INTER_LINEAR: the taps resize_taps() in cuda_image_ops.cpp computes as OpenCV does.
struct ResizeTap {
  int first = 0, second = 0;  // a column whose second is its first takes the first alone
  int16_t fixed[2] = {};      // 8-bit images: the weights in 1/2048 (INTER_RESIZE_COEF_BITS 11)
  float weight[2] = {};       // the other depths
};

// cv::resize(src, dst, dst size, INTER_LINEAR) with one tap per dst column and one per dst row.
void resize_linear(DeviceImage src, DeviceImage dst, PixelDepth depth, int channels,
                   const ResizeTap* columns, const ResizeTap* rows, cudaStream_t stream);

// depth_image_proc's xyz + rgb point of every pixel of `depth` (32FC1 metres or 16UC1 mm, as
// model.metres says) and `colour` (8-bit, model.colour_bytes per pixel, the depth's size) into
// `cloud`: 32 bytes a point, every byte written.
void xyzrgb(DeviceImage depth, const uint8_t* colour, const XyzrgbModel& model, uint8_t* cloud,
            cudaStream_t stream);

// StereoBM's device part on a rectified mono8 pair (shape.rows x shape.cols each): the x-Sobel
// pre-filter, the cost of every window and disparity, the texture and uniqueness checks and the
// sub-pixel fit, into `disparity` (1/16 px, filtered pixels (min_disparity - 1) * 16). Throws
// std::invalid_argument for a window and range whose tiles do not fit a block's shared memory.
struct BlockMatchingBuffers {
  const uint8_t* left = nullptr;
  const uint8_t* right = nullptr;
  uint8_t* filtered_left = nullptr;  // rows x cols each
  uint8_t* filtered_right = nullptr;
  int16_t* disparity = nullptr;  // rows x cols
};
void block_match(const BlockMatchingShape& shape, const BlockMatchingBuffers& buffers,
                 cudaStream_t stream);

// Throws std::invalid_argument, saying why, where block_match cannot take windows of `radius`
// with `disparities` disparities.
void check_block_matching(int radius, int disparities);

// StereoBM's step after block_match, in place on its `disparity`, with the answer of
// cv::filterSpeckles(disparity, (min_disparity - 1) * 16, speckle_size, speckle_range), as
// filter_on_host() runs it, where speckle_size > 0 and speckle_range >= 0.
struct DisparityFilter {
  int speckle_size = 0, speckle_range = -1;
};
struct DisparityFilterBuffers {
  int16_t* disparity = nullptr;     // rows x cols, block_match's
  int32_t* labels = nullptr;        // rows x cols
  int32_t* region_sizes = nullptr;  // rows x cols
};
void filter_disparity(const BlockMatchingShape& shape, const DisparityFilter& filter,
                      const DisparityFilterBuffers& buffers, cudaStream_t stream);

}  // namespace robotperf::perception::cuda
