// depth_image_proc's point_cloud_xyzrgb on the device: one thread per point, the cpu's float
// operations in its order (built with --fmad=false: no multiply-add is fused), so that every
// coordinate has the cpu's bits, NaN included.
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <type_traits>

#include "cuda_check.hpp"
#include "cuda_kernels.hpp"
#include "grid.hpp"

namespace robotperf::perception::cuda {
namespace {

constexpr int kPointBytes = 32;  // kXyzrgbPointStep

template <class Depth>
__global__ void xyzrgb_kernel(DeviceImage depth, const uint8_t* colour, XyzrgbModel m,
                              uint8_t* cloud) {
  const int u = blockIdx.x * blockDim.x + threadIdx.x;
  const int v = blockIdx.y * blockDim.y + threadIdx.y;
  if (u >= depth.width || v >= depth.height) return;
  const size_t at = static_cast<size_t>(v) * depth.width + u;
  const Depth raw = static_cast<const Depth*>(depth.data)[at];
  float d = raw;
  bool valid;
  if constexpr (std::is_same_v<Depth, float>) {
    valid = isfinite(raw);
  } else {
    valid = raw != 0;
  }
  float x, y, z;
  if (!valid && !m.fill_invalid) {
    // std::numeric_limits<float>::quiet_NaN()'s bits, as the cpu writes them.
    x = y = z = __int_as_float(0x7fc00000);
  } else {
    if (!valid) d = m.fill;
    x = (static_cast<float>(u) - m.cx) * d * m.constant_x;
    y = (static_cast<float>(v) - m.cy) * d * m.constant_y;
    z = m.metres ? d : d * 0.001f;
  }
  // x, y, z, padding; then b, g, r, 0 (PointCloud2Iterator's "rgb" bytes) and padding.
  uint8_t* point = cloud + at * kPointBytes;
  const uint8_t* px = colour + at * m.colour_bytes;
  reinterpret_cast<float4*>(point)[0] = make_float4(x, y, z, 0.f);
  const unsigned rgb = px[m.blue] | px[m.green] << 8 | px[m.red] << 16;
  reinterpret_cast<uint4*>(point)[1] = make_uint4(rgb, 0, 0, 0);
}

}  // namespace

void xyzrgb(DeviceImage depth, const uint8_t* colour, const XyzrgbModel& model, uint8_t* cloud,
            cudaStream_t stream) {
  if (depth.data == nullptr || colour == nullptr || cloud == nullptr || depth.width <= 0 ||
      depth.height <= 0 || model.colour_bytes < 1 || model.colour_bytes > 4) {
    throw std::invalid_argument("cuda: xyzrgb: empty image or a colour pixel of " +
                                std::to_string(model.colour_bytes) + " bytes");
  }
  const dim3 grid = image_grid(depth.width, depth.height);
  if (model.metres) {
    launch(xyzrgb_kernel<float>, grid, image_block(), stream, depth, colour, model, cloud);
  } else {
    launch(xyzrgb_kernel<uint16_t>, grid, image_block(), stream, depth, colour, model, cloud);
  }
  check_launch("xyzrgb_kernel");
}

}  // namespace robotperf::perception::cuda
