#include "robotperf/plugin/kernel.hpp"

#include <cctype>
#include <iostream>
#include <stdexcept>

#include "robotperf/plugin/control_loop.hpp"
#include "robotperf/tracing/tracepoints.hpp"

namespace robotperf::plugin {

const PortInfo* KernelInfo::find_port(const std::string& port) const {
  for (const auto* list : {&inputs, &outputs}) {
    for (const auto& p : *list) {
      if (p.name == port) return &p;
    }
  }
  return nullptr;
}

std::string KernelConfig::topic(const std::string& port) const {
  auto it = topics.find(port);
  if (it == topics.end()) {
    throw std::invalid_argument("node '" + node_name + "': no topic wired to port '" + port + "'");
  }
  return it->second;
}

NodeCounters::~NodeCounters() = default;

void SkippedInputs::note(const std::string& node, std::string reason) {
  if (count_++ != 0) return;
  // OpenCV's messages end in a newline.
  while (!reason.empty() && std::isspace(static_cast<unsigned char>(reason.back())))
    reason.pop_back();
  std::cerr << "robotperf node " << node << ": skipping " << what_ << ": " << reason << "\n";
}
DeviceNode::~DeviceNode() = default;
ControlLoopSource::~ControlLoopSource() = default;

bool kernel_trace_enabled() {
  return lttng_ust_tracepoint_enabled(robotperf, kernel_init) ||
         lttng_ust_tracepoint_enabled(robotperf, kernel_fini);
}

void trace_kernel_init(const char* node, const char* kernel, int64_t message_id, uint64_t bytes) {
  lttng_ust_tracepoint(robotperf, kernel_init, node, kernel, message_id, bytes);
}

void trace_kernel_fini(const char* node, const char* kernel, int64_t message_id, uint64_t bytes) {
  lttng_ust_tracepoint(robotperf, kernel_fini, node, kernel, message_id, bytes);
}

bool device_trace_enabled() {
  return lttng_ust_tracepoint_enabled(robotperf, device_begin) ||
         lttng_ust_tracepoint_enabled(robotperf, device_end);
}

void trace_device_begin(const char* node, const char* stage, int64_t message_id, uint64_t bytes) {
  lttng_ust_tracepoint(robotperf, device_begin, node, stage, message_id, bytes);
}

void trace_device_end(const char* node, const char* stage, int64_t message_id, uint64_t bytes) {
  lttng_ust_tracepoint(robotperf, device_end, node, stage, message_id, bytes);
}

void trace_controller_update_begin(const char* manager, const char* controller, uint64_t cycle,
                                   int64_t observed_command) {
  lttng_ust_tracepoint(robotperf, controller_update_begin, manager, controller, cycle,
                       observed_command);
}

void trace_controller_update_end(const char* manager, const char* controller, uint64_t cycle,
                                 int64_t taken_command) {
  lttng_ust_tracepoint(robotperf, controller_update_end, manager, controller, cycle, taken_command);
}

}  // namespace robotperf::plugin
