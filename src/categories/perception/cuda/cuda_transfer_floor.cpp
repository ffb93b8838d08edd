// The floor under the cuda backend's upload and download stages (cuda_device.hpp says what each
// way is): a reader of a cuda latency can then tell the machine's PCIe and memory from the
// backend's own work.
#include <algorithm>
#include <chrono>
#include <climits>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "cuda_support.hpp"
#include "robotperf/perception/cuda_device.hpp"

namespace robotperf::perception {
namespace {

// Of an even count, the mean of the middle two (bench_backends takes 100 samples a way).
double median(std::vector<double> samples) {
  const auto middle = samples.begin() + static_cast<std::ptrdiff_t>(samples.size() / 2);
  std::nth_element(samples.begin(), middle, samples.end());
  if (samples.size() % 2 != 0) return *middle;
  return (*std::max_element(samples.begin(), middle) + *middle) / 2.0;
}

template <class Work>
double microseconds(Work&& work) {
  const auto start = std::chrono::steady_clock::now();
  work();
  return std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start)
      .count();
}

void expect_returned(const cv::Mat& sent, const void* back, const char* way) {
  if (std::memcmp(sent.data, back, sent.total()) != 0) {
    throw std::runtime_error(std::string("cuda transfer floor: the bytes came back changed (") +
                             way + " way)");
  }
}

}  // namespace

CudaTransferFloor cuda_transfer_floor(std::size_t bytes, int repetitions) {
  cuda_device();
  if (bytes == 0 || bytes > static_cast<std::size_t>(INT_MAX) || repetitions < 1) {
    throw std::invalid_argument(
        "cuda transfer floor: needs 1 to 2^31 - 1 bytes and at least one repetition");
  }
  using namespace cuda;
  Stream stream;
  // One row: the staged way copies an image row by row, and a dense image is one row to it.
  cv::Mat sent(1, static_cast<int>(bytes), CV_8UC1), back(1, static_cast<int>(bytes), CV_8UC1);
  for (std::size_t i = 0; i < bytes; ++i) sent.data[i] = static_cast<uint8_t>(i * 131 + 7);
  // Each way has device memory of its own, so that a way that moved nothing cannot pass on
  // another's bytes.
  Buffer pinned{Memory::kPinnedHost}, pinned_device{Memory::kDevice},
      pageable_device{Memory::kDevice};
  void* const pinned_host = pinned.reserve(bytes);
  void* const pinned_on_device = pinned_device.reserve(bytes);
  void* const pageable_on_device = pageable_device.reserve(bytes);
  StagedImage staged;
  const auto copy = [&](void* to, const void* from, cudaMemcpyKind kind, const char* what) {
    check(cudaMemcpyAsync(to, from, bytes, kind, stream.get()), what);
    stream.synchronize();
  };
  std::vector<double> pinned_up, pinned_down, staged_up, staged_down, pageable_up, pageable_down;
  for (int r = 0; r < repetitions; ++r) {
    // Other bytes every time: one repetition's cannot pass for the next one's.
    cv::bitwise_not(sent, sent);
    std::memcpy(pinned_host, sent.data, bytes);
    pinned_up.push_back(microseconds([&] {
      copy(pinned_on_device, pinned_host, cudaMemcpyHostToDevice, "cudaMemcpyAsync (pinned up)");
    }));
    std::memset(pinned_host, 0, bytes);
    pinned_down.push_back(microseconds([&] {
      copy(pinned_host, pinned_on_device, cudaMemcpyDeviceToHost, "cudaMemcpyAsync (pinned down)");
    }));
    expect_returned(sent, pinned_host, "pinned");

    staged_up.push_back(microseconds([&] {
      staged.upload(sent, stream.get());
      stream.synchronize();
    }));
    back.setTo(0);
    staged_down.push_back(microseconds([&] { download(stream, {{staged, back}}); }));
    expect_returned(sent, back.data, "staged");

    pageable_up.push_back(microseconds([&] {
      copy(pageable_on_device, sent.data, cudaMemcpyHostToDevice, "cudaMemcpyAsync (pageable up)");
    }));
    back.setTo(0);
    pageable_down.push_back(microseconds([&] {
      copy(back.data, pageable_on_device, cudaMemcpyDeviceToHost,
           "cudaMemcpyAsync (pageable down)");
    }));
    expect_returned(sent, back.data, "pageable");
  }
  CudaTransferFloor floor;
  floor.bytes = bytes;
  floor.repetitions = repetitions;
  floor.pinned_upload_us = median(std::move(pinned_up));
  floor.pinned_download_us = median(std::move(pinned_down));
  floor.staged_upload_us = median(std::move(staged_up));
  floor.staged_download_us = median(std::move(staged_down));
  floor.pageable_upload_us = median(std::move(pageable_up));
  floor.pageable_download_us = median(std::move(pageable_down));
  return floor;
}

}  // namespace robotperf::perception
