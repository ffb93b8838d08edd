// Private to the perception category: the backend a node's config names, and what the node
// records about the device that backend runs on.
#pragma once

#include "device_stage.hpp"
#include "robotperf/perception/image_proc.hpp"
#include "robotperf/perception/opencl_device.hpp"
#include "robotperf/plugin/kernel.hpp"

namespace robotperf::perception {

// The backend a node's config names; an OpenCL one needs its device now, not at the first frame.
inline ImageBackend backend_of(const plugin::KernelConfig& config) {
  const ImageBackend b = image_backend(config.backend);
  if (b == ImageBackend::kOpenCl) opencl_device();
  return b;
}

class ImageDeviceNode : public plugin::DeviceNode {
 public:
  explicit ImageDeviceNode(ImageBackend backend) : backend_(backend) {}
  plugin::DeviceInfo device() const override {
    return backend_ == ImageBackend::kOpenCl ? opencl_device() : plugin::DeviceInfo{};
  }

 protected:
  ImageBackend backend_;
};

}  // namespace robotperf::perception
