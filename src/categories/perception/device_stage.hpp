// Private to the perception category: the grey-box events of a kernel's stages on a device
// (robotperf:device_begin/end), for the opencl and cuda backends alike.
#pragma once

#include <cstdint>

#include "robotperf/graph/node.hpp"
#include "robotperf/plugin/kernel.hpp"

namespace robotperf::perception {

// The queue a device's work runs on, asynchronously to the host: what a recorded stage waits
// for before it ends.
class DeviceQueue {
 public:
  virtual ~DeviceQueue() = default;
  // Returns once the work queued so far has finished. Never throws: an error of that work is
  // left for the queue's next checked wait, which every message makes before its answer is used.
  virtual void finish() const noexcept = 0;
};

// OpenCV's OpenCL queue of the calling thread (opencl_device.cpp).
const DeviceQueue& opencl_queue();

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

// One stage of a message's computation on a device ("upload", "compute", "download"), from
// construction to destruction, as robotperf:device_begin/end while a session records. The
// device's queue runs asynchronously: a recorded stage waits for `queue` to finish, so that each
// stage's time is its own (black-box runs do not wait).
class DeviceStage {
 public:
  DeviceStage(const char* stage, uint64_t bytes, const DeviceQueue& queue)
      : context_(plugin::device_trace_enabled() ? DeviceStageContext::current() : nullptr),
        stage_(stage),
        bytes_(bytes),
        queue_(queue) {
    if (context_ != nullptr)
      plugin::trace_device_begin(context_->node(), stage_, context_->message_id(), bytes_);
  }
  ~DeviceStage() {
    if (context_ == nullptr) return;
    queue_.finish();
    plugin::trace_device_end(context_->node(), stage_, context_->message_id(), bytes_);
  }
  DeviceStage(const DeviceStage&) = delete;
  DeviceStage& operator=(const DeviceStage&) = delete;

 private:
  const DeviceStageContext* context_;
  const char* stage_;
  uint64_t bytes_;
  const DeviceQueue& queue_;
};

}  // namespace robotperf::perception
