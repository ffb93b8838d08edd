// Private to the perception category: the backend a node's config names, and what the node
// records about the device that backend runs on.
#pragma once

#include <string>
#include <vector>

#include "device_stage.hpp"
#include "robotperf/perception/cuda_device.hpp"
#include "robotperf/perception/image_proc.hpp"
#include "robotperf/perception/opencl_device.hpp"
#include "robotperf/plugin/kernel.hpp"

namespace robotperf::perception {

// The backends of the perception kernels that have device code: cuda only in a build with the
// CUDA toolkit, so that a run asking for it elsewhere is refused before any node is built.
inline std::vector<std::string> perception_backends() {
  std::vector<std::string> names{"cpu", "opencl"};
  if (cuda_backend_built()) names.push_back("cuda");
  return names;
}

// The backends on which rectify and resize hand images to each other on the device (a
// device-resident run): cuda, in a build that has it.
inline std::vector<std::string> image_resident_backends() {
  if (cuda_backend_built()) return {"cuda"};
  return {};
}

// The backend a node's config names. Its device is asked for when the node builds its kernel (a
// device backend needs it then, not at the first frame).
inline ImageBackend backend_of(const plugin::KernelConfig& config) {
  return image_backend(config.backend);
}

class ImageDeviceNode : public plugin::DeviceNode {
 public:
  explicit ImageDeviceNode(ImageBackend backend) : backend_(backend) {}
  plugin::DeviceInfo device() const override {
    switch (backend_) {
      case ImageBackend::kOpenCl:
        return opencl_device();
      case ImageBackend::kCuda:
        return cuda_device();
      case ImageBackend::kCpu:
        break;
    }
    return {};
  }

 protected:
  ImageBackend backend_;
};

}  // namespace robotperf::perception
