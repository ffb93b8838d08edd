// Private to the cuda backend: what a node keeps on the device from message to message (its
// stream, its buffers), and how an image goes to the device and back through pinned memory.
#pragma once

#include <cuda_runtime.h>

#include <cstddef>
#include <functional>
#include <initializer_list>
#include <memory>
#include <mutex>
#include <opencv2/core.hpp>
#include <vector>

#include "../device_stage.hpp"
#include "cuda_check.hpp"
#include "cuda_kernels.hpp"
#include "robotperf/perception/stereo_image_proc.hpp"

namespace robotperf::perception::cuda {

// A CUDA stream of the node's own, on the device cuda_device() describes: its work runs in order,
// beside other nodes' streams.
class Stream final : public DeviceQueue {
 public:
  Stream();
  ~Stream() override;
  Stream(const Stream&) = delete;
  Stream& operator=(const Stream&) = delete;

  cudaStream_t get() const { return stream_; }
  // Waits for the stream's work; throws std::runtime_error with the error of that work, or with
  // the one a recorded stage's wait (finish()) saw first.
  void synchronize();
  void finish() const noexcept override;

 private:
  cudaStream_t stream_ = nullptr;
  mutable cudaError_t deferred_ = cudaSuccess;
};

enum class Memory { kDevice, kPinnedHost };

// Memory of one kind kept from call to call, reallocated only to grow.
class Buffer {
 public:
  explicit Buffer(Memory memory) : memory_(memory) {}
  ~Buffer();
  Buffer(const Buffer&) = delete;
  Buffer& operator=(const Buffer&) = delete;

  // At least `bytes` bytes (what it held is lost when it grows). No queued work may be using it.
  void* reserve(std::size_t bytes);
  template <class T>
  T* reserve_for(std::size_t count) {
    return static_cast<T*>(reserve(count * sizeof(T)));
  }

 private:
  void release() noexcept;
  Memory memory_;
  void* data_ = nullptr;
  std::size_t capacity_ = 0;
};

// Device memory for the images a node hands to the next one on the device (ResidentPixels): each
// message's own, back in the pool when the last message holding it goes. By then the taking
// node's stream has finished with it (a node waits for its stream before its callback returns).
class ResidentPool : public std::enable_shared_from_this<ResidentPool> {
 public:
  ResidentPool() = default;
  ~ResidentPool();
  ResidentPool(const ResidentPool&) = delete;
  ResidentPool& operator=(const ResidentPool&) = delete;

  // At least `bytes` bytes of device memory, held by the returned pointer and its copies.
  std::shared_ptr<void> take(std::size_t bytes);

 private:
  struct Block {
    void* data;
    std::size_t bytes;
  };
  std::mutex mutex_;
  std::vector<Block> free_;
};

// An image with a dense copy on the device and one in pinned host memory for its transfers (a
// cudaMemcpyAsync from pinned memory is one DMA, from pageable memory a staged copy).
class StagedImage {
 public:
  // Copies `image` into pinned memory and queues its upload on `stream`; returns the device's
  // copy.
  DeviceImage upload(const cv::Mat& image, cudaStream_t stream);
  // The pinned memory of a dense rows x cols image of `type`, for the host to write the image
  // into (in place) before queue_upload(): no copy of it on the host then.
  cv::Mat staging(int rows, int cols, int type);
  // Queues the upload of what the pinned memory holds on `stream`; returns the device's copy.
  DeviceImage queue_upload(cudaStream_t stream);
  // A dense rows x cols image of `type` on the device, for a kernel's output.
  DeviceImage reserve(int rows, int cols, int type);
  // Queues the download of the image last uploaded or reserved into pinned memory.
  void queue_download(cudaStream_t stream);
  // Once the stream has finished the download: copies it into `out`, which has its size and type
  // already (written in place).
  void copy_to(cv::Mat& out) const;
  // Once the stream has finished the download: the image in pinned memory, valid until this
  // object's next upload, reservation or download.
  cv::Mat downloaded() const;
  std::size_t bytes() const;

 private:
  Buffer pinned_{Memory::kPinnedHost}, device_{Memory::kDevice};
  int rows_ = 0, cols_ = 0, type_ = 0;
  void* pinned_data_ = nullptr;
  void* device_data_ = nullptr;
};

// A staged image's way back into an output of its size and type.
struct Download {
  StagedImage& from;
  cv::Mat& to;
};

// A message's "download" stage: queues each download on `stream`, waits for it, and copies each
// into its output.
void download(Stream& stream, std::initializer_list<Download> downloads);

// download() of one image into an output the host makes while the device works: queues the
// download, calls `make_output` (a message's buffer, allocated and zeroed meanwhile), then, in
// the "download" stage, waits and copies into the image it returned (of `from`'s size and type,
// else std::logic_error). Where stages are recorded, the earlier stages have waited for their
// work; the DMA may overlap `make_output`, and the stage has what is left of it.
void download_overlapped(Stream& stream, StagedImage& from,
                         const std::function<cv::Mat()>& make_output);

// The StereoBM parameters of the steps after the block matching (filter_disparity).
DisparityFilter disparity_filter(const StereoParams& params);

// The kernels' depth for an OpenCV type: 8U, 16U or 32F with 1 to 4 channels; otherwise throws
// std::invalid_argument naming `what`.
PixelDepth pixel_depth(int type, const char* what);

}  // namespace robotperf::perception::cuda
