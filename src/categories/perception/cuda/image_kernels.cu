// cv::remap and cv::resize with INTER_LINEAR on the device, in the arithmetic of OpenCV's CPU
// code (imgwarp.cpp's remapBilinear, resize.cpp's HResizeLinear and VResizeLinear): integer
// weights for 8-bit images, float weights for 16-bit and float ones, the same operations in the
// same order (built with --fmad=false), so that the cuda backend gives the cpu backend's pixels.
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

constexpr int kTabBits = 5;  // INTER_BITS: remap's fractions are in 1/32 px
constexpr int kTabSize = 1 << kTabBits;
constexpr int kRemapCoefBits = 15;  // INTER_REMAP_COEF_BITS
constexpr int kMaxChannels = 4;

__device__ uint8_t saturate_u8(int v) {
  return static_cast<uint8_t>(v < 0 ? 0 : (v > 255 ? 255 : v));
}

// saturate_cast<ushort>(float): cvRound (to nearest, ties to even; NaN gives 0), then clamped.
__device__ uint16_t saturate_u16(float v) {
  const int rounded = __float2int_rn(v);
  return static_cast<uint16_t>(rounded < 0 ? 0 : (rounded > 65535 ? 65535 : rounded));
}

// ---------------------------------------------------------------------------------------------
// remap
// ---------------------------------------------------------------------------------------------

// Per element type: remap's border value, its four weights for a fraction (fx, fy) in 1/32 px
// (top-left, top-right, bottom-left, bottom-right) and the value they make.
template <class T>
struct Remap;

template <>
struct Remap<uint8_t> {
  using Weight = int;
  __device__ static uint8_t border() { return 0; }
  // OpenCV's fixed-point table: the product of the 1-D weights in 1/32768, saturated to a short
  // (the whole pixel's 32768 becomes 32767, which rounds to the same 8-bit value).
  __device__ static void weights(int fx, int fy, int w[4]) {
    const int wx[2] = {kTabSize - fx, fx};
    const int wy[2] = {kTabSize - fy, fy};
    constexpr int kScale = (1 << kRemapCoefBits) / (kTabSize * kTabSize);
    for (int k = 0; k < 4; ++k) w[k] = min(wy[k / 2] * wx[k % 2] * kScale, 32767);
  }
  __device__ static uint8_t combine(uint8_t v0, uint8_t v1, uint8_t v2, uint8_t v3,
                                    const int w[4]) {
    const int sum = v0 * w[0] + v1 * w[1] + v2 * w[2] + v3 * w[3];
    return saturate_u8((sum + (1 << (kRemapCoefBits - 1))) >> kRemapCoefBits);
  }
};

// The float table: 1-D weights 1 - t and t, t = i / 32, multiplied (all exact in float).
__device__ void float_remap_weights(int fx, int fy, float w[4]) {
  const float tx = fx * (1.f / kTabSize), ty = fy * (1.f / kTabSize);
  const float wx[2] = {1.f - tx, tx};
  const float wy[2] = {1.f - ty, ty};
  for (int k = 0; k < 4; ++k) w[k] = wy[k / 2] * wx[k % 2];
}

template <>
struct Remap<uint16_t> {
  using Weight = float;
  __device__ static uint16_t border() { return 0; }
  __device__ static void weights(int fx, int fy, float w[4]) { float_remap_weights(fx, fy, w); }
  __device__ static uint16_t combine(uint16_t v0, uint16_t v1, uint16_t v2, uint16_t v3,
                                     const float w[4]) {
    return saturate_u16(v0 * w[0] + v1 * w[1] + v2 * w[2] + v3 * w[3]);
  }
};

template <>
struct Remap<float> {
  using Weight = float;
  // No data outside the field of view, as image_geometry gives float images.
  __device__ static float border() { return __int_as_float(0x7fc00000); }
  __device__ static void weights(int fx, int fy, float w[4]) { float_remap_weights(fx, fy, w); }
  __device__ static float combine(float v0, float v1, float v2, float v3, const float w[4]) {
    return v0 * w[0] + v1 * w[1] + v2 * w[2] + v3 * w[3];
  }
};

// One thread per dst pixel. A neighbour outside the source is the border value; a pixel whose
// neighbours are all outside is the border value itself, as remapBilinear's BORDER_CONSTANT.
template <class T>
__global__ void remap_linear_kernel(DeviceImage src, DeviceImage dst, int channels,
                                    const int16_t* map_xy, const uint16_t* map_fraction) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x;
  const int y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= dst.width || y >= dst.height) return;
  using Op = Remap<T>;
  const size_t at = static_cast<size_t>(y) * dst.width + x;
  T* out = static_cast<T*>(dst.data) + at * channels;
  const int sx = map_xy[2 * at], sy = map_xy[2 * at + 1];
  if (sx >= src.width || sx + 1 < 0 || sy >= src.height || sy + 1 < 0) {
    for (int c = 0; c < channels; ++c) out[c] = Op::border();
    return;
  }
  const int fraction = map_fraction[at] & (kTabSize * kTabSize - 1);
  typename Op::Weight w[4];
  Op::weights(fraction & (kTabSize - 1), fraction >> kTabBits, w);
  const T* in = static_cast<const T*>(src.data);
  const bool left = sx >= 0, right = sx + 1 < src.width;
  const bool top = sy >= 0, bottom = sy + 1 < src.height;
  // Signed: the top-left neighbour may lie one pixel outside (then it is not read).
  const ptrdiff_t top_left = (static_cast<ptrdiff_t>(sy) * src.width + sx) * channels;
  const ptrdiff_t below = static_cast<ptrdiff_t>(src.width) * channels;
  for (int c = 0; c < channels; ++c) {
    const T v0 = top && left ? in[top_left + c] : Op::border();
    const T v1 = top && right ? in[top_left + channels + c] : Op::border();
    const T v2 = bottom && left ? in[top_left + below + c] : Op::border();
    const T v3 = bottom && right ? in[top_left + below + channels + c] : Op::border();
    out[c] = Op::combine(v0, v1, v2, v3, w);
  }
}

// ---------------------------------------------------------------------------------------------
// resize
// ---------------------------------------------------------------------------------------------

// Per element type: a source row's value at a dst column (HResizeLinear) and the dst value of two
// of them (VResizeLinear).
template <class T>
struct Resize;

template <>
struct Resize<uint8_t> {
  using Row = int;  // in 1/2048
  __device__ static int along_row(const uint8_t* row, const ResizeTap& t, int channels, int c) {
    const int first = row[t.first * channels + c] * t.fixed[0];
    return t.second == t.first ? first : first + row[t.second * channels + c] * t.fixed[1];
  }
  // OpenCV's own order of shifts and rounding for the 2^22 scale of the two weights.
  __device__ static uint8_t across_rows(int a, int b, const ResizeTap& t) {
    return saturate_u8((((t.fixed[0] * (a >> 4)) >> 16) + ((t.fixed[1] * (b >> 4)) >> 16) + 2) >>
                       2);
  }
};

template <class T>
struct FloatResize {
  using Row = float;
  __device__ static float along_row(const T* row, const ResizeTap& t, int channels, int c) {
    const float first = row[t.first * channels + c] * t.weight[0];
    return t.second == t.first ? first : first + row[t.second * channels + c] * t.weight[1];
  }
};

template <>
struct Resize<uint16_t> : FloatResize<uint16_t> {
  __device__ static uint16_t across_rows(float a, float b, const ResizeTap& t) {
    return saturate_u16(a * t.weight[0] + b * t.weight[1]);
  }
};

template <>
struct Resize<float> : FloatResize<float> {
  __device__ static float across_rows(float a, float b, const ResizeTap& t) {
    return a * t.weight[0] + b * t.weight[1];
  }
};

// One thread per dst pixel; both source rows are read whatever the row's weights.
template <class T>
__global__ void resize_linear_kernel(DeviceImage src, DeviceImage dst, int channels,
                                     const ResizeTap* columns, const ResizeTap* rows) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x;
  const int y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= dst.width || y >= dst.height) return;
  using Op = Resize<T>;
  const ResizeTap column = columns[x], row = rows[y];
  const size_t row_elements = static_cast<size_t>(src.width) * channels;
  const T* in = static_cast<const T*>(src.data);
  const T* first = in + row.first * row_elements;
  const T* second = in + row.second * row_elements;
  T* out = static_cast<T*>(dst.data) + (static_cast<size_t>(y) * dst.width + x) * channels;
  for (int c = 0; c < channels; ++c) {
    out[c] = Op::across_rows(Op::along_row(first, column, channels, c),
                             Op::along_row(second, column, channels, c), row);
  }
}

// ---------------------------------------------------------------------------------------------
// Launching
// ---------------------------------------------------------------------------------------------

// Checks the images, then has `launch(element, grid, block)` queue a kernel with a thread per
// pixel of `dst` (`element`: a null pointer to the element type of `depth`), and checks the
// launch.
template <class Launch>
void launch_per_pixel(const char* kernel, DeviceImage src, DeviceImage dst, PixelDepth depth,
                      int channels, const Launch& launch) {
  for (const DeviceImage& image : {src, dst}) {
    if (image.data == nullptr || image.width <= 0 || image.height <= 0 || channels < 1 ||
        channels > kMaxChannels) {
      throw std::invalid_argument(std::string("cuda: ") + kernel + ": empty image or " +
                                  std::to_string(channels) + " channels (1 to 4)");
    }
  }
  const dim3 grid = image_grid(dst.width, dst.height), block = image_block();
  switch (depth) {
    case PixelDepth::k8U:
      launch(static_cast<uint8_t*>(nullptr), grid, block);
      break;
    case PixelDepth::k16U:
      launch(static_cast<uint16_t*>(nullptr), grid, block);
      break;
    case PixelDepth::k32F:
      launch(static_cast<float*>(nullptr), grid, block);
      break;
  }
  check_launch(kernel);
}

template <class Pointer>
using Element = std::remove_pointer_t<Pointer>;

}  // namespace

void remap_linear(DeviceImage src, DeviceImage dst, PixelDepth depth, int channels,
                  const int16_t* map_xy, const uint16_t* map_fraction, cudaStream_t stream) {
  launch_per_pixel("remap_linear_kernel", src, dst, depth, channels,
                   [&](auto* element, dim3 grid, dim3 block) {
                     launch(remap_linear_kernel<Element<decltype(element)>>, grid, block, stream,
                            src, dst, channels, map_xy, map_fraction);
                   });
}

void resize_linear(DeviceImage src, DeviceImage dst, PixelDepth depth, int channels,
                   const ResizeTap* columns, const ResizeTap* rows, cudaStream_t stream) {
  launch_per_pixel("resize_linear_kernel", src, dst, depth, channels,
                   [&](auto* element, dim3 grid, dim3 block) {
                     launch(resize_linear_kernel<Element<decltype(element)>>, grid, block, stream,
                            src, dst, channels, columns, rows);
                   });
}

}  // namespace robotperf::perception::cuda
