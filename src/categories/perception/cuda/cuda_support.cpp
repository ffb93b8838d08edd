#include "cuda_support.hpp"

#include <algorithm>
#include <cstring>
#include <opencv2/core/utility.hpp>
#include <stdexcept>
#include <string>

namespace robotperf::perception::cuda {
namespace {

// Copies `from` into `to` (same size and type) between a message and pinned memory. One core
// copies a few GB/s on a data-centre CPU, several times slower than the DMA: a megabyte image's
// host copy would cost more than its transfer. Dense images are copied in slices of the bytes on
// OpenCV's threads, the pool the cpu backend's kernels run on.
void host_copy(const cv::Mat& from, cv::Mat& to) {
  if (!from.isContinuous() || !to.isContinuous()) {
    from.copyTo(to);
    return;
  }
  constexpr std::size_t kSliceBytes = 256 * 1024;  // small enough to spread, large per thread
  const std::size_t bytes = from.total() * from.elemSize();
  if (bytes == 0) return;
  const auto* source = from.ptr<const uint8_t>();
  auto* target = to.ptr<uint8_t>();
  const int slices = static_cast<int>((bytes + kSliceBytes - 1) / kSliceBytes);
  if (slices <= 1) {
    std::memcpy(target, source, bytes);
    return;
  }
  cv::parallel_for_(cv::Range(0, slices), [&](const cv::Range& range) {
    const std::size_t begin = static_cast<std::size_t>(range.start) * kSliceBytes;
    const std::size_t end = std::min(bytes, static_cast<std::size_t>(range.end) * kSliceBytes);
    std::memcpy(target + begin, source + begin, end - begin);
  });
}

}  // namespace

Stream::Stream() {
  // Non-blocking: no implicit ordering with other streams' work (other nodes, OpenCV's).
  check(cudaStreamCreateWithFlags(&stream_, cudaStreamNonBlocking), "cudaStreamCreateWithFlags");
}

Stream::~Stream() {
  // Every call waited for its work; a destructor has nobody to report an error to.
  static_cast<void>(cudaStreamDestroy(stream_));
}

void Stream::synchronize() {
  const cudaError_t seen = deferred_;
  deferred_ = cudaSuccess;
  check(seen, "cudaStreamSynchronize (a recorded stage's wait)");
  check(cudaStreamSynchronize(stream_), "cudaStreamSynchronize");
}

void Stream::finish() const noexcept {
  const cudaError_t error = cudaStreamSynchronize(stream_);
  if (deferred_ == cudaSuccess) deferred_ = error;
}

Buffer::~Buffer() {
  release();
}

void* Buffer::reserve(std::size_t bytes) {
  if (bytes <= capacity_) return data_;
  release();
  if (memory_ == Memory::kDevice) {
    check(cudaMalloc(&data_, bytes), "cudaMalloc");
  } else {
    check(cudaHostAlloc(&data_, bytes, cudaHostAllocDefault), "cudaHostAlloc");
  }
  capacity_ = bytes;
  return data_;
}

void Buffer::release() noexcept {
  if (data_ == nullptr) return;
  // Freeing fails only for a pointer CUDA did not give or a device already lost: nothing to do.
  static_cast<void>(memory_ == Memory::kDevice ? cudaFree(data_) : cudaFreeHost(data_));
  data_ = nullptr;
  capacity_ = 0;
}

ResidentPool::~ResidentPool() {
  // Every message holding a block has gone (each holds the pool): nothing uses them.
  for (const Block& block : free_) static_cast<void>(cudaFree(block.data));
}

std::shared_ptr<void> ResidentPool::take(std::size_t bytes) {
  Block block{nullptr, bytes};
  {
    const std::lock_guard lock(mutex_);
    const auto fits = std::find_if(free_.begin(), free_.end(),
                                   [bytes](const Block& b) { return b.bytes >= bytes; });
    if (fits != free_.end()) {
      block = *fits;
      free_.erase(fits);
    }
  }
  if (block.data == nullptr) check(cudaMalloc(&block.data, bytes), "cudaMalloc (resident image)");
  return {block.data, [pool = shared_from_this(), block](void*) {
            try {
              const std::lock_guard lock(pool->mutex_);
              pool->free_.push_back(block);
            } catch (...) {
              static_cast<void>(cudaFree(block.data));  // no room to keep it: given back to CUDA
            }
          }};
}

std::size_t StagedImage::bytes() const {
  return static_cast<std::size_t>(rows_) * cols_ * CV_ELEM_SIZE(type_);
}

DeviceImage StagedImage::upload(const cv::Mat& image, cudaStream_t stream) {
  cv::Mat pinned = staging(image.rows, image.cols, image.type());
  host_copy(image, pinned);
  return queue_upload(stream);
}

cv::Mat StagedImage::staging(int rows, int cols, int type) {
  reserve(rows, cols, type);
  pinned_data_ = pinned_.reserve(bytes());
  return {rows_, cols_, type_, pinned_data_};
}

DeviceImage StagedImage::queue_upload(cudaStream_t stream) {
  check(cudaMemcpyAsync(device_data_, pinned_data_, bytes(), cudaMemcpyHostToDevice, stream),
        "cudaMemcpyAsync (upload)");
  return {device_data_, cols_, rows_};
}

DeviceImage StagedImage::reserve(int rows, int cols, int type) {
  rows_ = rows;
  cols_ = cols;
  type_ = type;
  device_data_ = device_.reserve(bytes());
  return {device_data_, cols, rows};
}

void StagedImage::queue_download(cudaStream_t stream) {
  pinned_data_ = pinned_.reserve(bytes());
  check(cudaMemcpyAsync(pinned_data_, device_data_, bytes(), cudaMemcpyDeviceToHost, stream),
        "cudaMemcpyAsync (download)");
}

void StagedImage::copy_to(cv::Mat& out) const {
  if (out.rows != rows_ || out.cols != cols_ || out.type() != type_) {
    throw std::logic_error("cuda: the device's output has another size or type");
  }
  host_copy(downloaded(), out);
}

cv::Mat StagedImage::downloaded() const {
  return {rows_, cols_, type_, pinned_data_};
}

void download_overlapped(Stream& stream, StagedImage& from,
                         const std::function<cv::Mat()>& make_output) {
  from.queue_download(stream.get());
  cv::Mat out = make_output();
  DeviceStage stage("download", from.bytes(), stream);
  stream.synchronize();
  from.copy_to(out);
}

void download(Stream& stream, std::initializer_list<Download> downloads) {
  uint64_t bytes = 0;
  for (const Download& d : downloads) bytes += d.from.bytes();
  DeviceStage stage("download", bytes, stream);
  for (const Download& d : downloads) d.from.queue_download(stream.get());
  stream.synchronize();
  for (const Download& d : downloads) d.from.copy_to(d.to);
}

PixelDepth pixel_depth(int type, const char* what) {
  const int channels = CV_MAT_CN(type);
  if (channels >= 1 && channels <= 4) {
    switch (CV_MAT_DEPTH(type)) {
      case CV_8U:
        return PixelDepth::k8U;
      case CV_16U:
        return PixelDepth::k16U;
      case CV_32F:
        return PixelDepth::k32F;
      default:
        break;
    }
  }
  throw std::invalid_argument(std::string(what) +
                              ": the cuda backend takes 8-bit, 16-bit unsigned and 32-bit float "
                              "images of 1 to 4 channels");
}

}  // namespace robotperf::perception::cuda
