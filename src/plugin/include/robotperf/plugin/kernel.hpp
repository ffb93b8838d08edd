// Kernels: what a benchmark graph's nodes run. A kernel is registered with a description of its
// ports, parameters and backends, and a factory that builds its node in a graph context.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "robotperf/graph/node.hpp"
#include "robotperf/plugin/parameters.hpp"

namespace robotperf::plugin {

// A port: the role of one topic of the node, wired to a topic name in graph.yaml.
struct PortInfo {
  std::string name{};  // "image"
  // ROS type ("sensor_msgs/msg/Image"); empty when a parameter chooses it.
  std::string type{};
  // On a backend of the kernel's device_resident_backends, this port's messages may keep their
  // data on the device: an output the node can publish without it, an input it can take so.
  bool device_resident = false;
};

// A kernel that runs a periodic control loop (ControlLoopSource): the parameter that sets its
// rate (run --update-rate overrides it) and the grey-box events one cycle emits, to size the
// trace buffers.
struct ControlLoopInfo {
  std::string rate_parameter{};  // a declared double parameter, in Hz, with a default
  double trace_events_per_cycle = 0;
};

struct KernelInfo {
  std::string name{};         // "image_proc/rectify": <package>/<kernel>
  std::string description{};  // one line
  // The backends the kernel's factory computes on. The registry adds each backend an
  // implementation is registered for (Registrar::add_kernel_backend), so that in an entry it is
  // every backend the kernel has.
  std::vector<std::string> backends{"cpu"};
  std::vector<PortInfo> inputs{};
  std::vector<PortInfo> outputs{};
  std::vector<ParameterInfo> parameters{};
  std::optional<ControlLoopInfo> control_loop{};
  // The backends on which the kernel's device_resident ports can leave data on the device for
  // the next node of its process, or take data another node left there (device-resident runs,
  // docs/design.md §6: type adaptation, as REP 2007 and NITROS do); the registry adds those of
  // the implementations registered as device-resident.
  std::vector<std::string> device_resident_backends{};

  const PortInfo* find_port(const std::string& port) const;
};

struct KernelConfig {
  std::string node_name{};
  std::string backend = "cpu";
  Parameters parameters{};                      // checked against the kernel's declarations
  std::map<std::string, std::string> topics{};  // port -> topic
  rmw::QoS qos{};
  // benchmark.yaml's `workload: seed` when the dataset is generated from one: kernels with random
  // choices of their own (planners) follow it unless a parameter of theirs says otherwise.
  std::optional<uint64_t> workload_seed{};
  // Output ports whose messages may keep their data on the device (a device-resident run): every
  // subscriber of their topics is a node of this process on the same backend that takes such
  // inputs. The node publishes those messages without downloading their data.
  std::set<std::string> device_resident_outputs{};

  // The topic wired to `port`; throws std::invalid_argument when none is.
  std::string topic(const std::string& port) const;
};

// Builds the kernel's node; throws std::invalid_argument with one line for a value it cannot
// use (the harness reports it naming the node).
using KernelFactory =
    std::function<std::shared_ptr<graph::Node>(graph::Context&, const KernelConfig&)>;

// An implementation of a kernel on one more backend, registered apart from the kernel
// (Registrar::add_kernel_backend): by the kernel's category, one implementation unit per backend,
// or by a plug-in that brings its accelerator's implementation of a kernel it did not register.
struct KernelBackendInfo {
  std::string kernel{};   // the kernel's name, registered before or in the same registration
  std::string backend{};  // a backend the kernel does not have yet
  // Its node can keep or take the data of the kernel's device_resident ports on the device.
  bool device_resident = false;
};

// Implemented by kernel nodes that count inputs they received but could not use (frames whose
// inputs never paired, inputs rejected as malformed). The harness reports the counts with the
// node; it reads them only while the node's callbacks are not running.
class NodeCounters {
 public:
  virtual ~NodeCounters();
  virtual std::map<std::string, uint64_t> counters() const = 0;
};

// Inputs a kernel node could not use (a malformed image, frames of different sizes, a map it
// cannot read): as the ROS nodes log and skip them, the node skips and counts them, the frame
// shows as lost at the Monitor and the run goes on. The first one is said on stderr, naming the
// node, so that a run that loses every frame says why.
class SkippedInputs {
 public:
  // `what` is the input's kind as the line says it ("input", "request").
  explicit SkippedInputs(std::string what = "input") : what_(std::move(what)) {}
  void note(const std::string& node, std::string reason);
  uint64_t count() const { return count_; }

 private:
  std::string what_;
  uint64_t count_ = 0;
};

// The device a kernel computes on when its backend is not the host CPU, as results record it.
struct DeviceInfo {
  std::string name{};     // "NVIDIA H100 80GB HBM3", "pthread-haswell-AMD EPYC"
  std::string vendor{};   // "NVIDIA Corporation"
  std::string driver{};   // the device driver's version
  std::string runtime{};  // the API and its version: "OpenCL 3.0 PoCL", "CUDA 13.0"
  uint64_t memory_bytes = 0;
};

// Implemented by kernel nodes whose backend runs on such a device: the harness asks it once the
// node is built and records it with the node.
class DeviceNode {
 public:
  virtual ~DeviceNode();
  virtual DeviceInfo device() const = 0;
};

// Grey-box: robotperf:kernel_init and kernel_fini around a kernel's computation, so that the
// trace analysis can split a node's time into the kernel and the rest. `message_id` is the
// input's ID (its header stamp in nanoseconds), `bytes` its or the output's CDR size.
bool kernel_trace_enabled();
void trace_kernel_init(const char* node, const char* kernel, int64_t message_id, uint64_t bytes);
void trace_kernel_fini(const char* node, const char* kernel, int64_t message_id, uint64_t bytes);

// Grey-box, for a kernel on a device: robotperf:device_begin and device_end around each stage of
// a message's computation there — "upload" (host to device), "compute", "download" (device to
// host) — so that the analysis splits the kernel's time into its transfers and its computation.
// `bytes`: what the stage moved (0 for compute).
bool device_trace_enabled();
void trace_device_begin(const char* node, const char* stage, int64_t message_id, uint64_t bytes);
void trace_device_end(const char* node, const char* stage, int64_t message_id, uint64_t bytes);

// The same with the sizes of the messages the kernel reads (summed) or writes, computed only
// while a session records; the output's ID is its header stamp.
template <class... Inputs>
void trace_kernel_init(const graph::Node& node, const char* kernel, int64_t message_id,
                       const Inputs&... inputs) {
  if (kernel_trace_enabled()) {
    const uint64_t bytes =
        (uint64_t{0} + ... + msgs::type_support<Inputs>().serialized_size(&inputs));
    trace_kernel_init(node.name().c_str(), kernel, message_id, bytes);
  }
}
template <class T>
void trace_kernel_fini(const graph::Node& node, const char* kernel, const T& output) {
  if (kernel_trace_enabled()) {
    trace_kernel_fini(node.name().c_str(), kernel, output.header.stamp.to_ns(),
                      msgs::type_support<T>().serialized_size(&output));
  }
}

}  // namespace robotperf::plugin
