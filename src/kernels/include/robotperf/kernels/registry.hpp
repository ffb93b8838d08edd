// The kernels a benchmark graph can name, and how to build their nodes.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "robotperf/control/controller_manager.hpp"
#include "robotperf/graph/node.hpp"

namespace robotperf::kernels {

// A node's parameters as written in graph.yaml. Values are kept as text and
// converted on read, so a wrong type or an unknown name can be reported by name.
class Parameters {
 public:
  void set(const std::string& name, std::string value) { values_[name] = std::move(value); }
  bool has(const std::string& name) const { return values_.contains(name); }

  // Each getter returns `fallback` when the parameter is absent and throws
  // std::invalid_argument naming the parameter when its text does not convert.
  double get_double(const std::string& name, double fallback) const;
  int64_t get_int(const std::string& name, int64_t fallback) const;
  bool get_bool(const std::string& name, bool fallback) const;
  std::string get_string(const std::string& name, const std::string& fallback) const;

  // Names that were set but never read: almost always a typo in graph.yaml.
  std::vector<std::string> unused() const;
  const std::map<std::string, std::string>& values() const { return values_; }

 private:
  const std::string* find(const std::string& name) const;
  std::map<std::string, std::string> values_;
  mutable std::set<std::string> read_;
};

struct KernelConfig {
  std::string node_name;
  std::string backend = "cpu";
  Parameters parameters;
  std::map<std::string, std::string> topics;  // the kernel's port -> topic
  rmw::QoS qos;
  // benchmark.yaml's `workload: seed` when the dataset is generated from one: kernels with random
  // choices of their own (planners) follow it unless their `seed` parameter says otherwise.
  std::optional<uint64_t> workload_seed;

  // The topic wired to `port`; throws std::invalid_argument when none is.
  std::string topic(const std::string& port) const;
};

struct KernelInfo {
  std::string name;         // "image_proc/rectify"
  std::string description;  // one line
  std::vector<std::string> backends;
  std::vector<std::string> input_ports;
  std::vector<std::string> output_ports;
};

// Implemented by kernel nodes that count inputs they received but could not use (frames whose
// inputs never paired, inputs rejected as malformed). The harness reports the counts with the
// node; read them only while the node's callbacks are not running.
class NodeCounters {
 public:
  virtual ~NodeCounters() = default;
  virtual std::map<std::string, uint64_t> counters() const = 0;
};

// Implemented by kernel nodes that run a control loop (src/control): stops the loop and returns
// what it recorded (per-cycle timestamps, deadline misses, commands written). The harness calls
// it once, after the run, to report the loop metrics.
class ControlLoopSource {
 public:
  virtual ~ControlLoopSource() = default;
  virtual control::LoopReport stop_and_report() = 0;
};

using KernelFactory =
    std::function<std::shared_ptr<graph::Node>(graph::Context&, const KernelConfig&)>;

// Every kernel compiled into robotperf, by name.
const std::vector<KernelInfo>& kernel_infos();
const KernelInfo* find_kernel(const std::string& name);

// Builds the node; throws std::invalid_argument for an unknown kernel or
// backend, a missing port or an unusable parameter.
std::shared_ptr<graph::Node> make_kernel_node(const std::string& kernel, graph::Context& context,
                                              const KernelConfig& config);

}  // namespace robotperf::kernels
