#include "robotperf/perception/opencl_device.hpp"

#include <cstdlib>
#include <mutex>
#include <opencv2/core/ocl.hpp>
#include <stdexcept>
#include <string>

#include "device_stage.hpp"

namespace robotperf::perception {
namespace {

class OpenClQueue final : public DeviceQueue {
 public:
  void finish() const noexcept override { cv::ocl::finish(); }
};

plugin::DeviceInfo describe(const cv::ocl::Device& d) {
  return {d.name(), d.vendorName(), d.driverVersion(), d.version(),
          static_cast<uint64_t>(d.globalMemSize())};
}

constexpr const char* kMissing =
    "the opencl backend has no OpenCL device: install an OpenCL driver (Debian: "
    "pocl-opencl-icd for the CPU, or the GPU vendor's ICD) and check that clinfo lists it";

// Why there is no device: none installed, or, where the user chose one with OPENCV_OPENCL_DEVICE
// (`user_choice`, null when unset), none that the choice matches.
std::string missing_device(const char* user_choice) {
  if (user_choice == nullptr) return kMissing;
  return std::string("the opencl backend has no OpenCL device: OPENCV_OPENCL_DEVICE='") +
         user_choice +
         "' matches none (its form is <platform>:<CPU|GPU|ACCELERATOR>:<device name>; robotperf "
         "sysinfo lists the devices as opencl_devices); unset it to take a GPU, else a CPU or "
         "accelerator device";
}

// Calls `f` for every device of every platform; creates no OpenCL context of OpenCV's.
template <class F>
void for_each_device(const F& f) {
  std::vector<cv::ocl::PlatformInfo> platforms;
  cv::ocl::getPlatfomsInfo(platforms);
  for (const auto& p : platforms) {
    for (int i = 0; i < p.deviceNumber(); ++i) {
      cv::ocl::Device d;
      p.getDevice(d, i);
      f(d);
    }
  }
}

}  // namespace

std::vector<plugin::DeviceInfo> opencl_devices() {
  std::vector<plugin::DeviceInfo> out;
  for_each_device([&](const cv::ocl::Device& d) { out.push_back(describe(d)); });
  return out;
}

const DeviceQueue& opencl_queue() {
  static const OpenClQueue queue;
  return queue;
}

const plugin::DeviceInfo& opencl_device() {
  static std::once_flag once;
  static plugin::DeviceInfo chosen;
  static std::string error;
  std::call_once(once, [] {
    const char* user_choice = std::getenv("OPENCV_OPENCL_DEVICE");
    // OpenCV takes only GPUs by default; which type is read when it first creates its context.
    if (user_choice == nullptr) {
      int types = 0;
      for_each_device([&](const cv::ocl::Device& d) { types |= d.type(); });
      if (!(types & cv::ocl::Device::TYPE_GPU) && (types & cv::ocl::Device::TYPE_CPU)) {
        setenv("OPENCV_OPENCL_DEVICE", ":CPU:", 0);
      } else if (!(types & cv::ocl::Device::TYPE_GPU) && types != 0) {
        setenv("OPENCV_OPENCL_DEVICE", ":ACCELERATOR:", 0);
      }
    }
    cv::ocl::setUseOpenCL(true);
    const cv::ocl::Device& d = cv::ocl::Device::getDefault();
    if (!cv::ocl::useOpenCL() || !d.available()) {
      error = missing_device(user_choice);
      return;
    }
    chosen = describe(d);
  });
  if (!error.empty()) throw std::invalid_argument(error);
  return chosen;
}

}  // namespace robotperf::perception
