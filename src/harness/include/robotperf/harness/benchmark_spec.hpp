// A benchmark package: benchmark.yaml (RobotPerf fields) + graph.yaml (what to run).
#pragma once

#include <cstddef>
#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "robotperf/harness/functional.hpp"
#include "robotperf/harness/network_link.hpp"
#include "robotperf/plugin/kernel.hpp"
#include "robotperf/plugin/registry.hpp"
#include "robotperf/rmw/transport.hpp"

namespace robotperf::harness {

// A benchmark package that cannot be used; the message names the file and what is wrong.
class BenchmarkError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A topic at the boundary of the graph under test.
struct BoundaryTopic {
  std::string topic;
  std::string type;    // ROS type, e.g. sensor_msgs/msg/Image
  std::string stream;  // inputs: the dataset stream published on it
  rmw::QoS qos;
  // Outputs only: a state stream (control benchmarks). Each message carries the ID of the newest
  // command it reflects and several messages may carry one ID: the first reception is the
  // latency, later ones are counted as repeats (not duplicates), the functional check keeps the
  // last, and the Monitor waits the whole drain time.
  bool state = false;
};

struct NodeSpec {
  std::string name;
  std::string kernel;
  std::string backend = "cpu";
  // The host it runs on (graph.yaml `host:`, a name the run maps to a launcher); empty: the
  // runner's. A node on a host runs in a process of its own there.
  std::string host;
  std::map<std::string, std::string> parameters;
  std::map<std::string, std::string> topics;  // port -> topic
  rmw::QoS qos;
  // Output ports whose images stay on the device in a device-resident run (keep_on_device); empty
  // otherwise.
  std::set<std::string> device_resident_outputs;
};

// A process of an external graph (graph.yaml `launch:`): robotperf starts it before timing and
// stops it after. ${domain}, ${rmw} and ${package} in its command and environment are replaced.
struct LaunchSpec {
  std::string name;
  std::vector<std::string> command;  // argv; the program is looked up on PATH
  std::filesystem::path cwd = ".";   // relative to the package folder
  std::map<std::string, std::string> env;
};

struct BenchmarkSpec {
  std::filesystem::path dir;
  // graph.yaml `plugins:`, resolved against the package folder; loaded with the package.
  std::vector<std::filesystem::path> plugins;
  // From benchmark.yaml.
  std::string id;    // "a1"
  std::string name;  // "a1_perception_2nodes"
  std::string short_description;
  std::string description;
  std::string category;  // the folder above the package: perception, control, ...
  // benchmark.yaml `workload:` — parameters of a generated dataset (seed, requests, ...).
  std::map<std::string, std::string> workload;
  // From graph.yaml.
  std::string dataset;  // built-in dataset name
  double rate_hz = 30.0;
  std::size_t count = 0;  // messages to send; 0: as many as the dataset has frames
  std::size_t warmup = 0;
  double drain_s = 2.0;
  // graph.yaml `sample:` what one measured message is, for a benchmark whose nature keeps a run
  // to fewer than a p99 interval needs (one goal every 6 s): the summary says it beside the count.
  std::string sample;
  // The process layout the benchmark is defined with ("single" or "per-node"); --processes
  // overrides it (e.g. n2, a ping-pong between two processes, says per-node).
  std::string processes = "single";
  // graph.yaml `security: required`: runs only with DDS Security (--security), e.g. n4.
  bool security_required = false;
  // graph.yaml `network:` the path --netns makes to the other host: a router between two subnets
  // (topology: routed) and a VPN over it (vpn: wireguard), e.g. n5 to n8.
  NetworkLayout network;
  std::size_t executor_threads = 1;
  std::size_t min_samples = 30;
  double max_loss_percent = 0.0;
  std::vector<BoundaryTopic> inputs;
  // graph.yaml `output:`, or the first of `outputs:`: the output the run's latency and validity
  // are first of all about.
  BoundaryTopic output;
  // The rest of `outputs:`, each monitored and reported as the first is (a graph that fans out).
  std::vector<BoundaryTopic> more_outputs;
  std::vector<NodeSpec> nodes;
  // An external graph: processes robotperf starts (launch:), or one already running (attach:
  // true). Either may go with nodes of robotperf's own.
  std::vector<LaunchSpec> launch;
  bool attach = false;
  bool external() const { return attach || !launch.empty(); }
  // graph.yaml `functional:` with benchmark.yaml's thresholds; absent when the benchmark does not
  // check accuracy.
  std::optional<FunctionalSpec> functional;

  const NodeSpec* find_node(const std::string& name) const;
  // The hosts the nodes are placed on (graph.yaml `host:`), sorted, without the runner's.
  std::vector<std::string> hosts() const;
};

// A name graph.yaml's `host:` and --host accept: letters, digits, '.', '-' and '_'.
bool valid_host_name(const std::string& name);

// A benchmark's id and name, and its nodes' names, become parts of file names (results, reports,
// logs): letters, digits, '.', '-' and '_', starting with a letter, a digit or '_', at most 128
// characters. No such name can leave the folder it is written in.
bool valid_file_name_part(const std::string& name);

// Reads and checks <dir>/benchmark.yaml and <dir>/graph.yaml, loading the plug-ins graph.yaml
// names first; throws BenchmarkError.
BenchmarkSpec load_benchmark(const std::filesystem::path& dir);

// Every package under <root>/<category>/<package>/ with a graph.yaml, of every root, sorted by id.
// Packages that fail to load are returned in `broken` as one line each. Two packages with one id
// are a BenchmarkError naming both.
std::vector<BenchmarkSpec> discover_benchmarks(const std::vector<std::filesystem::path>& roots,
                                               std::vector<std::string>* broken = nullptr);
std::vector<BenchmarkSpec> discover_benchmarks(const std::filesystem::path& root,
                                               std::vector<std::string>* broken = nullptr);

// By id ("a1") or full name ("a1_perception_2nodes"); throws BenchmarkError
// listing the known ids when there is no such benchmark.
BenchmarkSpec find_benchmark(const std::vector<std::filesystem::path>& roots,
                             const std::string& id_or_name);
BenchmarkSpec find_benchmark(const std::filesystem::path& root, const std::string& id_or_name);

// The registered kernel a node runs; throws BenchmarkError when none is registered by that name.
const plugin::KernelEntry& kernel_of(const NodeSpec& node);

// The kernel configuration of a node of the spec, its parameters checked against the kernel's
// declarations, with the workload's seed (benchmark.yaml `workload: seed`) when there is one.
// Throws BenchmarkError.
plugin::KernelConfig kernel_config(const NodeSpec& node,
                                   const std::map<std::string, std::string>& workload = {});

// Builds the node's kernel in `context`; throws std::invalid_argument naming the node when the
// kernel refuses its configuration or has no such backend.
std::shared_ptr<graph::Node> make_kernel_node(const NodeSpec& node, graph::Context& context,
                                              const std::map<std::string, std::string>& workload);

// Sets the loop rate of every kernel of `spec` that runs a control loop (its rate parameter).
// Throws std::invalid_argument with one line when the benchmark has none or `hz` is not a rate a
// loop can run at (0 < hz <= 100000).
void override_update_rate(BenchmarkSpec& spec, double hz);

// Runs every node of `spec` whose kernel has `backend` on it (--backend); the others keep theirs.
// Throws std::invalid_argument with one line when no kernel of the benchmark has it, naming the
// backends they have.
void override_backend(BenchmarkSpec& spec, const std::string& backend);

// A topic whose messages a device-resident run keeps on the device: published by node `from`,
// taken only by the nodes `to`, all of them on `backend` in one process.
struct ResidentTopic {
  std::string topic;
  std::string from;
  std::vector<std::string> to;
  std::string backend;
};

// The device-resident configuration (docs/design.md §6: type adaptation, as REP 2007 and
// NITROS do) of a single-process graph: a node's output stays on the device where no subscriber
// needs it on the host. That is, where every node that takes the topic runs on the publisher's
// backend, each kernel can hand its images over there (KernelInfo::device_resident_backends), and
// neither the Monitor (the graph's output, an observed truth) nor anything else takes it. Marks
// those ports (NodeSpec::device_resident_outputs) and returns the topics; throws
// std::invalid_argument with one line when there are none, saying what it needs.
std::vector<ResidentTopic> keep_on_device(BenchmarkSpec& spec);

}  // namespace robotperf::harness
