// Private to the perception category: the backend a node's config names, and what the node
// records about the device that backend runs on.
#pragma once

#include <cstdint>
#include <opencv2/core/ocl.hpp>

#include "robotperf/graph/node.hpp"
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

// The node and message a kernel function is computing for on this thread, for the grey-box events
// of its device stages: the node sets it around the call (a node's callback runs the kernel
// function on its own thread, so the function's signature need not carry it).
class DeviceStageContext {
 public:
  DeviceStageContext(const graph::Node& node, int64_t message_id)
      : node_(node.name().c_str()), message_id_(message_id), outer_(current_) {
    current_ = this;
  }
  ~DeviceStageContext() { current_ = outer_; }
  DeviceStageContext(const DeviceStageContext&) = delete;
  DeviceStageContext& operator=(const DeviceStageContext&) = delete;

  static const DeviceStageContext* current() { return current_; }
  const char* node() const { return node_; }
  int64_t message_id() const { return message_id_; }

 private:
  const char* node_;
  int64_t message_id_;
  const DeviceStageContext* outer_;
  static inline thread_local const DeviceStageContext* current_ = nullptr;
};

// One stage of a message's computation on the OpenCL device ("upload", "compute", "download"),
// from construction to destruction, as robotperf:device_begin/end while a session records. The
// device's queue runs asynchronously: a recorded stage waits for it to finish, so that each
// stage's time is its own (black-box runs do not wait).
class DeviceStage {
 public:
  DeviceStage(const char* stage, uint64_t bytes)
      : context_(plugin::device_trace_enabled() ? DeviceStageContext::current() : nullptr),
        stage_(stage),
        bytes_(bytes) {
    if (context_ != nullptr)
      plugin::trace_device_begin(context_->node(), stage_, context_->message_id(), bytes_);
  }
  ~DeviceStage() {
    if (context_ == nullptr) return;
    cv::ocl::finish();
    plugin::trace_device_end(context_->node(), stage_, context_->message_id(), bytes_);
  }
  DeviceStage(const DeviceStage&) = delete;
  DeviceStage& operator=(const DeviceStage&) = delete;

 private:
  const DeviceStageContext* context_;
  const char* stage_;
  uint64_t bytes_;
};

}  // namespace robotperf::perception
