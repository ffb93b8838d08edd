#include "robotperf/harness/benchmark_spec.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <map>
#include <set>
#include <sstream>

#include "robotperf/harness/suggestions.hpp"

namespace robotperf::harness {
namespace {

namespace fs = std::filesystem;

constexpr std::size_t kMaxExecutorThreads = 256;

// Reads one YAML file and reports every problem as "<file>:<line>: <what>".
class YamlFile {
 public:
  explicit YamlFile(fs::path path) : path_(std::move(path)) {
    if (!fs::exists(path_)) throw BenchmarkError(path_.string() + ": file not found");
    try {
      root_ = YAML::LoadFile(path_.string());
    } catch (const YAML::Exception& e) {
      throw BenchmarkError(path_.string() + ":" + std::to_string(e.mark.line + 1) +
                           ": malformed YAML: " + e.msg);
    }
    if (!root_.IsMap())
      throw BenchmarkError(path_.string() + ": expected a mapping at the top level");
    refuse_duplicate_keys(root_);
  }

  const YAML::Node& root() const { return root_; }

  // yaml-cpp keeps the first of two equal keys and says nothing: a package whose second value
  // was meant would run with the first.
  void refuse_duplicate_keys(const YAML::Node& node) const {
    if (node.IsSequence()) {
      for (const auto& item : node) refuse_duplicate_keys(item);
    } else if (node.IsMap()) {
      std::map<std::string, int> first_line;
      for (const auto& kv : node) {
        if (kv.first.IsScalar()) {
          const auto [at, added] = first_line.emplace(kv.first.Scalar(), kv.first.Mark().line + 1);
          if (!added) {
            fail(kv.first, "duplicate key '" + kv.first.Scalar() + "' (first at line " +
                               std::to_string(at->second) + ")");
          }
        }
        refuse_duplicate_keys(kv.second);
      }
    }
  }

  [[noreturn]] void fail(const YAML::Node& at, const std::string& what) const {
    std::string where = path_.string();
    if (at.IsDefined() && at.Mark().line >= 0) where += ":" + std::to_string(at.Mark().line + 1);
    throw BenchmarkError(where + ": " + what);
  }

  void allow_keys(const YAML::Node& map, std::initializer_list<const char*> keys) const {
    if (!map.IsMap()) fail(map, "expected a mapping");
    std::set<std::string> allowed(keys.begin(), keys.end());
    for (const auto& kv : map) {
      const auto key = kv.first.as<std::string>();
      if (!allowed.contains(key)) {
        std::string list;
        for (const auto& k : allowed) list += (list.empty() ? "" : ", ") + k;
        fail(kv.first, "unknown key '" + key + "' (expected one of: " + list + ")");
      }
    }
  }

  template <class T>
  T get(const YAML::Node& map, const char* key, const T& fallback) const {
    const YAML::Node n = map[key];
    if (!n.IsDefined() || n.IsNull()) return fallback;
    try {
      return n.as<T>();
    } catch (const YAML::Exception&) {
      fail(n, std::string("'") + key + "' has the wrong type");
    }
  }

  // A name that becomes part of a file name (valid_file_name_part); `what` says whose it is.
  std::string require_file_name_part(const YAML::Node& map, const char* key,
                                     const std::string& what) const {
    std::string name = require_string(map, key);
    if (!valid_file_name_part(name)) {
      fail(map[key], what + " '" + name +
                         "' is not a name robotperf can put in a file name: letters, digits, "
                         "'.', '-' and '_', starting with a letter, a digit or '_' (at most 128)");
    }
    return name;
  }

  std::string require_string(const YAML::Node& map, const char* key) const {
    const YAML::Node n = map[key];
    if (!n.IsDefined() || n.IsNull()) fail(map, std::string("missing '") + key + "'");
    if (!n.IsScalar()) fail(n, std::string("'") + key + "' must be a string");
    return n.as<std::string>();
  }

  rmw::QoS qos(const YAML::Node& map) const {
    const auto name = get<std::string>(map, "qos", "default");
    try {
      return rmw::QoS::from_profile_name(name);
    } catch (const std::invalid_argument& e) {
      fail(map["qos"], e.what());
    }
  }

  std::map<std::string, std::string> string_map(const YAML::Node& map, const char* key) const {
    std::map<std::string, std::string> out;
    const YAML::Node n = map[key];
    if (!n.IsDefined() || n.IsNull()) return out;
    if (!n.IsMap()) fail(n, std::string("'") + key + "' must be a mapping");
    for (const auto& kv : n) {
      if (!kv.second.IsScalar())
        fail(kv.second, "value of '" + kv.first.as<std::string>() + "' must be a scalar");
      out[kv.first.as<std::string>()] = kv.second.as<std::string>();
    }
    return out;
  }

 private:
  fs::path path_;
  YAML::Node root_;
};

BoundaryTopic boundary_topic(const YamlFile& file, const YAML::Node& n, bool is_input) {
  if (is_input) {
    file.allow_keys(n, {"topic", "type", "stream", "qos"});
  } else {
    file.allow_keys(n, {"topic", "type", "qos", "state"});
  }
  BoundaryTopic t;
  t.topic = file.require_string(n, "topic");
  t.type = file.require_string(n, "type");
  if (is_input) t.stream = file.require_string(n, "stream");
  t.qos = file.qos(n);
  if (!is_input) t.state = file.get<bool>(n, "state", false);
  try {
    rmw::dds_topic_name(t.topic);
  } catch (const std::invalid_argument& e) {
    file.fail(n["topic"], e.what());
  }
  return t;
}

// graph.yaml `plugins:`, loaded first: they may register the kernels, dataset and evaluator the
// graph names.
void load_plugins(const YamlFile& file, BenchmarkSpec& spec) {
  const YAML::Node& root = file.root();
  if (const YAML::Node plugins = root["plugins"]; plugins.IsDefined()) {
    if (!plugins.IsSequence()) file.fail(plugins, "'plugins' must be a list of files");
    for (const auto& entry : plugins) {
      if (!entry.IsScalar()) file.fail(entry, "a plug-in is a file name");
      const fs::path plugin = spec.dir / entry.as<std::string>();
      try {
        plugin::registry().load(plugin);
      } catch (const plugin::PluginError& e) {
        file.fail(entry, e.what());
      }
      spec.plugins.push_back(plugin);
    }
  }
}

// The dataset, the rate, counts, processes, security, the executor and the validity bounds.
void load_settings(const YamlFile& file, BenchmarkSpec& spec) {
  const YAML::Node& root = file.root();
  spec.dataset = file.require_string(root, "dataset");
  spec.rate_hz = file.get<double>(root, "rate_hz", 30.0);
  if (!(spec.rate_hz > 0)) file.fail(root["rate_hz"], "rate_hz must be positive");
  spec.count = file.get<std::size_t>(root, "count", 0);
  spec.warmup = file.get<std::size_t>(root, "warmup", 0);
  spec.drain_s = file.get<double>(root, "drain_s", 2.0);
  spec.sample = file.get<std::string>(root, "sample", "");
  spec.processes = file.get<std::string>(root, "processes", "single");
  if (spec.processes != "single" && spec.processes != "per-node")
    file.fail(root["processes"], "processes must be 'single' or 'per-node'");
  if (const YAML::Node security = root["security"]; security.IsDefined()) {
    if (!security.IsScalar() || (security.Scalar() != "required" && security.Scalar() != "none"))
      file.fail(security, "security must be 'required' (DDS Security, --security) or 'none'");
    spec.security_required = security.Scalar() == "required";
  }
  if (const YAML::Node network = root["network"]; network.IsDefined()) {
    if (!network.IsMap()) file.fail(network, "network must be a map (vpn:, topology:)");
    file.allow_keys(network, {"vpn", "topology"});
    const std::string vpn = file.get<std::string>(network, "vpn", "none");
    const std::string topology = file.get<std::string>(network, "topology", "same-subnet");
    if (const auto v = vpn_from_name(vpn))
      spec.network.vpn = *v;
    else
      file.fail(network["vpn"], "network: vpn must be 'wireguard' or 'none'");
    if (const auto t = topology_from_name(topology))
      spec.network.topology = *t;
    else
      file.fail(network["topology"], "network: topology must be 'same-subnet' or 'routed'");
  }
  if (!(spec.drain_s >= 0)) file.fail(root["drain_s"], "drain_s must be >= 0");
  spec.executor_threads = file.get<std::size_t>(root, "executor_threads", 1);
  // More threads than that only contend: the graph's nodes run one callback at a time each.
  if (spec.executor_threads == 0 || spec.executor_threads > kMaxExecutorThreads) {
    file.fail(root["executor_threads"],
              "executor_threads must be 1 to " + std::to_string(kMaxExecutorThreads));
  }
  if (const YAML::Node v = root["validity"]; v.IsDefined()) {
    file.allow_keys(v, {"min_samples", "max_loss_percent"});
    spec.min_samples = file.get<std::size_t>(v, "min_samples", spec.min_samples);
    spec.max_loss_percent = file.get<double>(v, "max_loss_percent", spec.max_loss_percent);
    if (!(spec.max_loss_percent >= 0 && spec.max_loss_percent <= 100))
      file.fail(v["max_loss_percent"], "max_loss_percent must be within 0-100");
    if (spec.min_samples == 0) file.fail(v["min_samples"], "min_samples must be >= 1");
  }
}

// The Playback's inputs and the Monitor's output; returns the input topics.
std::set<std::string> load_boundary(const YamlFile& file, BenchmarkSpec& spec) {
  const YAML::Node& root = file.root();
  // A missing key is an invalid node in yaml-cpp: asking its type throws, so check it is defined.
  const YAML::Node inputs = root["inputs"];
  if (!inputs.IsDefined() || !inputs.IsSequence() || inputs.size() == 0)
    file.fail(root, "'inputs' must be a non-empty list");
  std::set<std::string> input_topics;
  for (const auto& n : inputs) {
    spec.inputs.push_back(boundary_topic(file, n, true));
    if (!input_topics.insert(spec.inputs.back().topic).second)
      file.fail(n["topic"], "two inputs are published on " + spec.inputs.back().topic);
  }
  const YAML::Node outputs = root["outputs"];
  if (outputs.IsDefined()) {
    if (root["output"].IsDefined())
      file.fail(root["outputs"], "give 'output' (one) or 'outputs' (a list), not both");
    if (!outputs.IsSequence() || outputs.size() == 0)
      file.fail(outputs, "'outputs' must be a non-empty list");
    std::set<std::string> output_topics;
    for (const auto& n : outputs) {
      BoundaryTopic out = boundary_topic(file, n, false);
      if (!output_topics.insert(out.topic).second)
        file.fail(n["topic"], "two outputs are monitored on " + out.topic);
      if (output_topics.size() == 1) {
        spec.output = std::move(out);
      } else {
        spec.more_outputs.push_back(std::move(out));
      }
    }
    return input_topics;
  }
  if (!root["output"].IsDefined()) file.fail(root, "missing 'output' (or 'outputs')");
  spec.output = boundary_topic(file, root["output"], false);
  return input_topics;
}

// graph.yaml `launch:`, an external graph's processes; their names go into `names`.
void load_launch(const YamlFile& file, BenchmarkSpec& spec, std::set<std::string>& names) {
  const YAML::Node& root = file.root();
  if (const YAML::Node launch = root["launch"]; launch.IsDefined()) {
    if (!launch.IsSequence()) file.fail(launch, "'launch' must be a list of processes");
    for (const auto& l : launch) {
      file.allow_keys(l, {"name", "command", "cwd", "env"});
      LaunchSpec process;
      process.name = file.require_file_name_part(l, "name", "launched process name");
      if (!names.insert(process.name).second) file.fail(l, "duplicate name '" + process.name + "'");
      const YAML::Node command = l["command"];
      if (!command.IsSequence() || command.size() == 0)
        file.fail(l, "'command' must be a non-empty list: the program and its arguments");
      for (const auto& word : command) {
        if (!word.IsScalar()) file.fail(word, "each word of a command is a string");
        process.command.push_back(word.Scalar());
      }
      process.cwd = file.get<std::string>(l, "cwd", ".");
      process.env = file.string_map(l, "env");
      spec.launch.push_back(std::move(process));
    }
  }
}

// One of graph.yaml's `nodes:`, its name added to `names`; a port wired to a boundary topic must
// carry the boundary's type.
NodeSpec load_node(const YamlFile& file, const YAML::Node& n,
                   const std::vector<const BoundaryTopic*>& boundary,
                   std::set<std::string>& names) {
  file.allow_keys(n, {"name", "kernel", "backend", "host", "parameters", "topics", "qos"});
  NodeSpec node;
  node.name = file.require_string(n, "name");
  try {
    rmw::parse_node_name(node.name);
  } catch (const std::invalid_argument& e) {
    file.fail(n["name"], e.what());
  }
  if (!names.insert(node.name).second) file.fail(n, "duplicate node name '" + node.name + "'");
  node.kernel = file.require_string(n, "kernel");
  const plugin::KernelEntry* entry = plugin::registry().find_kernel(node.kernel);
  if (entry == nullptr) {
    file.fail(n["kernel"], "unknown kernel '" + node.kernel +
                               "' (registered: " + plugin::names_of(plugin::registry().kernels()) +
                               "; a plug-in's kernel needs --plugin or 'plugins:')");
  }
  const plugin::KernelInfo& info = entry->info;
  node.backend = file.get<std::string>(n, "backend", "cpu");
  node.host = file.get<std::string>(n, "host", "");
  if (n["host"].IsDefined() && !valid_host_name(node.host)) {
    file.fail(n["host"],
              "host '" + node.host + "' is not a host name (letters, digits, '.', '-' and '_')");
  }
  if (std::ranges::count(info.backends, node.backend) == 0) {
    std::string backends;
    for (const auto& b : info.backends) backends += (backends.empty() ? "" : ", ") + b;
    file.fail(n["backend"], "kernel " + node.kernel + " has no backend '" + node.backend +
                                "' (it has: " + backends + ")");
  }
  node.parameters = file.string_map(n, "parameters");
  try {
    plugin::Parameters(info.parameters, node.parameters, "node '" + node.name + "'");
  } catch (const std::invalid_argument& e) {
    file.fail(n["parameters"], e.what());
  }
  node.topics = file.string_map(n, "topics");
  node.qos = file.qos(n);
  for (const auto& [port, topic] : node.topics) {
    const plugin::PortInfo* p = info.find_port(port);
    if (p == nullptr)
      file.fail(n["topics"], "kernel " + node.kernel + " has no port '" + port + "'");
    // A port of a fixed type wired to a boundary topic must carry the boundary's type.
    for (const BoundaryTopic* b : boundary) {
      if (b->topic == topic && !p->type.empty() && p->type != b->type) {
        file.fail(n["topics"], "port '" + port + "' of " + node.kernel + " carries " + p->type +
                                   ", but " + topic + " is declared " + b->type);
      }
    }
  }
  return node;
}

// graph.yaml `functional:`, the evaluator of the outputs and the truth it reads.
void load_functional(const YamlFile& file, BenchmarkSpec& spec) {
  const YAML::Node f = file.root()["functional"];
  if (!f.IsDefined()) return;
  file.allow_keys(
      f, {"evaluator", "truth", "sample", "observed_truth", "second_output", "parameters"});
  FunctionalSpec functional;
  functional.evaluator = file.require_string(f, "evaluator");
  const plugin::EvaluatorEntry* entry = plugin::registry().find_evaluator(functional.evaluator);
  if (entry == nullptr) {
    file.fail(f["evaluator"],
              "unknown functional evaluator '" + functional.evaluator +
                  "' (registered: " + plugin::names_of(plugin::registry().evaluators()) + ")");
  }
  const plugin::EvaluatorInfo* info = &entry->info;
  functional.parameters = file.string_map(f, "parameters");
  try {
    plugin::Parameters(info->parameters, functional.parameters,
                       "evaluator " + functional.evaluator);
  } catch (const std::invalid_argument& e) {
    file.fail(f["parameters"], e.what());
  }
  if (info->output_type != spec.output.type) {
    file.fail(f["evaluator"], "evaluator " + info->name + " reads " + info->output_type +
                                  ", but the output is " + spec.output.type);
  }
  functional.truth = file.string_map(f, "truth");
  for (const auto& role : info->truth_roles) {
    if (!functional.truth.contains(role)) {
      file.fail(f, "evaluator " + info->name + " needs truth stream '" + role + "'");
    }
  }
  for (const auto& [role, stream] : functional.truth) {
    if (std::ranges::count(info->truth_roles, role) == 0) {
      file.fail(f["truth"], "evaluator " + info->name + " has no truth role '" + role + "'");
    }
  }
  functional.sample = file.get<std::size_t>(f, "sample", functional.sample);
  // The evaluator's second topic: a truth observed during the run, or a second output of the
  // graph; one slot under the name that says which.
  functional.observed_truth_topic = file.get<std::string>(f, "observed_truth", "");
  if (const auto second = file.get<std::string>(f, "second_output", ""); !second.empty()) {
    if (!functional.observed_truth_topic.empty())
      file.fail(f, "give observed_truth or second_output, not both");
    functional.observed_truth_topic = second;
  }
  if (info->observed_truth_type.empty() != functional.observed_truth_topic.empty()) {
    file.fail(f, info->observed_truth_type.empty()
                     ? "evaluator " + info->name + " takes no observed_truth or second_output"
                     : "evaluator " + info->name +
                           " needs an observed_truth or second_output "
                           "topic (" +
                           info->observed_truth_type + ")");
  }
  spec.functional = std::move(functional);
}

// The graph's own nodes against its inputs, before anything runs: an input no node reads would
// run to 100 % loss, and a node that publishes onto an input feeds the Playback's topic, looping
// messages back as duplicates. A graph with launched or attached nodes is not known here.
void check_wiring(const YamlFile& file, const BenchmarkSpec& spec) {
  if (spec.external() || spec.nodes.empty()) return;
  const YAML::Node& root = file.root();
  std::set<std::string> read;
  for (const NodeSpec& node : spec.nodes) {
    const plugin::KernelInfo& info = plugin::registry().find_kernel(node.kernel)->info;
    for (const auto& [port, topic] : node.topics) {
      if (std::ranges::count(info.inputs, port, &plugin::PortInfo::name) != 0) read.insert(topic);
      const bool publishes = std::ranges::count(info.outputs, port, &plugin::PortInfo::name) != 0;
      if (publishes && std::ranges::count(spec.inputs, topic, &BoundaryTopic::topic) != 0) {
        file.fail(root["nodes"], "node '" + node.name + "' publishes (port '" + port + "') on " +
                                     topic +
                                     ", an input of the graph: its messages would loop back "
                                     "into the graph as the Playback's; give it a topic of its "
                                     "own");
      }
    }
  }
  for (std::size_t i = 0; i < spec.inputs.size(); ++i) {
    if (!read.contains(spec.inputs[i].topic)) {
      file.fail(root["inputs"][i], "input " + spec.inputs[i].topic +
                                       " is read by no node: every message sent on it would be "
                                       "lost; wire it to a node's input port or remove it");
    }
  }
}

void load_graph(const fs::path& path, BenchmarkSpec& spec) {
  const YamlFile file(path);
  const YAML::Node& root = file.root();
  file.allow_keys(root, {"plugins", "dataset", "rate_hz", "count", "warmup", "drain_s", "sample",
                         "executor_threads", "processes", "security", "network", "validity",
                         "inputs", "output", "outputs", "nodes", "launch", "attach", "functional"});
  load_plugins(file, spec);
  load_settings(file, spec);
  const std::set<std::string> input_topics = load_boundary(file, spec);
  std::vector<const BoundaryTopic*> boundary{&spec.output};
  for (const auto& out : spec.more_outputs) boundary.push_back(&out);
  for (const auto& in : spec.inputs) boundary.push_back(&in);
  std::set<std::string> names;
  load_launch(file, spec, names);
  spec.attach = file.get<bool>(root, "attach", false);
  if (spec.attach && !spec.launch.empty())
    file.fail(root["attach"], "attach: true is for a graph already running, not with launch:");
  const YAML::Node nodes = root["nodes"];
  if (nodes.IsDefined() ? !nodes.IsSequence() : !spec.external()) {
    file.fail(root, "'nodes' must be a list (or the graph external: launch: or attach: true)");
  }
  for (const auto& n : nodes) spec.nodes.push_back(load_node(file, n, boundary, names));
  check_wiring(file, spec);
  if (spec.network != NetworkLayout{} && spec.hosts().empty()) {
    file.fail(root["network"],
              "network: describes the path to another host, but no node has host:");
  }
  // The Monitor would time the Playback's own messages. Only a graph of nothing (no node, no
  // process) does that on purpose: it measures the harness itself.
  const YAML::Node output_node = root["outputs"].IsDefined() ? root["outputs"] : root["output"];
  if (input_topics.contains(spec.output.topic) && (!spec.nodes.empty() || spec.external())) {
    file.fail(output_node, "the output topic " + spec.output.topic +
                               " is also an input: the Monitor would time the Playback's own "
                               "messages, not the graph's outputs");
  }
  for (const auto& out : spec.more_outputs) {
    if (input_topics.contains(out.topic))
      file.fail(output_node, "the output topic " + out.topic + " is also an input");
    if (out.state != spec.output.state)
      file.fail(output_node, "outputs are all state streams or none (" + out.topic + ")");
  }
  load_functional(file, spec);
}

// benchmark.yaml `functional: {thresholds: {<metric>: {min: x, max: y}}}`.
void load_thresholds(const YamlFile& meta, BenchmarkSpec& spec) {
  const YAML::Node f = meta.root()["functional"];
  if (!f.IsDefined() || f.IsNull()) return;
  meta.allow_keys(f, {"thresholds"});
  if (!spec.functional) {
    meta.fail(f, "functional thresholds are given but graph.yaml names no functional evaluator");
  }
  const plugin::EvaluatorInfo& info =
      plugin::registry().find_evaluator(spec.functional->evaluator)->info;
  const YAML::Node thresholds = f["thresholds"];
  if (!thresholds.IsDefined() || thresholds.IsNull()) return;
  if (!thresholds.IsMap()) meta.fail(thresholds, "'thresholds' must be a mapping");
  for (const auto& kv : thresholds) {
    const auto metric = kv.first.as<std::string>();
    const bool known =
        std::ranges::any_of(info.metrics, [&](const auto& m) { return m.name == metric; });
    if (!known) {
      std::string names;
      for (const auto& m : info.metrics) names += (names.empty() ? "" : ", ") + m.name;
      meta.fail(kv.first, "evaluator " + info.name + " has no metric '" + metric +
                              "' (it has: " + names + ")");
    }
    meta.allow_keys(kv.second, {"min", "max"});
    FunctionalThreshold t;
    if (kv.second["min"].IsDefined()) t.min = meta.get<double>(kv.second, "min", 0.0);
    if (kv.second["max"].IsDefined()) t.max = meta.get<double>(kv.second, "max", 0.0);
    if (!t.min && !t.max) meta.fail(kv.second, "threshold of '" + metric + "' needs min or max");
    spec.functional->thresholds[metric] = t;
  }
}

}  // namespace

const NodeSpec* BenchmarkSpec::find_node(const std::string& node_name) const {
  for (const auto& n : nodes) {
    if (n.name == node_name) return &n;
  }
  return nullptr;
}

std::vector<std::string> BenchmarkSpec::hosts() const {
  std::set<std::string> out;
  for (const auto& n : nodes) {
    if (!n.host.empty()) out.insert(n.host);
  }
  return {out.begin(), out.end()};
}

bool valid_host_name(const std::string& name) {
  return !name.empty() && std::ranges::all_of(name, [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '-' || c == '_';
  });
}

bool valid_file_name_part(const std::string& name) {
  return !name.empty() && name.size() <= 128 && name.front() != '.' && name.front() != '-' &&
         valid_host_name(name);
}

BenchmarkSpec load_benchmark(const fs::path& dir) {
  BenchmarkSpec spec;
  spec.dir = dir;
  spec.category = dir.parent_path().filename().string();
  // Every shape of node is checked before use; yaml-cpp's own exceptions (a mapping used as a
  // key, say) still become one line naming the package.
  try {
    const YamlFile meta(dir / "benchmark.yaml");
    spec.id = meta.require_file_name_part(meta.root(), "id", "id");
    spec.name = meta.require_file_name_part(meta.root(), "name", "name");
    spec.short_description = meta.get<std::string>(meta.root(), "short", "");
    spec.description = meta.get<std::string>(meta.root(), "description", "");
    spec.workload = meta.string_map(meta.root(), "workload");
    load_graph(dir / "graph.yaml", spec);
    load_thresholds(meta, spec);
  } catch (const YAML::Exception& e) {
    throw BenchmarkError(dir.string() + ": unexpected YAML structure: " + e.what());
  }
  return spec;
}

std::vector<BenchmarkSpec> discover_benchmarks(const std::vector<fs::path>& roots,
                                               std::vector<std::string>* broken) {
  std::vector<BenchmarkSpec> out;
  for (const auto& root : roots) {
    std::error_code ec;
    if (!fs::is_directory(root, ec))
      throw BenchmarkError("benchmarks folder not found: " + root.string());
    // Packages lie two levels down (<root>/<category>/<package>); one given a level too high up
    // would otherwise be skipped without a word.
    if (fs::exists(root / "graph.yaml")) {
      const std::string why = root.string() +
                              " is a benchmark package, not a folder of them: give the folder "
                              "that holds its category folder (<folder>/<category>/" +
                              root.filename().string() + ")";
      if (!broken) throw BenchmarkError(why);
      broken->push_back(why);
      continue;
    }
    for (const auto& category : fs::directory_iterator(root)) {
      if (!category.is_directory()) continue;
      if (fs::exists(category.path() / "graph.yaml")) {
        if (broken) {
          broken->push_back(category.path().string() +
                            ": a benchmark package directly in the benchmarks folder, where "
                            "category folders go: move it into one (" +
                            (root / "<category>" / category.path().filename()).string() + ")");
        }
        continue;
      }
      for (const auto& package : fs::directory_iterator(category.path())) {
        if (!fs::exists(package.path() / "graph.yaml")) continue;
        try {
          out.push_back(load_benchmark(package.path()));
        } catch (const BenchmarkError& e) {
          if (broken) broken->push_back(e.what());
        }
      }
    }
  }
  std::ranges::sort(out, [](const auto& a, const auto& b) { return a.id < b.id; });
  for (std::size_t i = 1; i < out.size(); ++i) {
    if (out[i].id == out[i - 1].id) {
      throw BenchmarkError("benchmark id " + out[i].id +
                           " is defined twice: " + out[i - 1].dir.string() + " and " +
                           out[i].dir.string() + " (give one of them another id)");
    }
  }
  return out;
}

std::vector<BenchmarkSpec> discover_benchmarks(const fs::path& root,
                                               std::vector<std::string>* broken) {
  return discover_benchmarks(std::vector<fs::path>{root}, broken);
}

BenchmarkSpec find_benchmark(const std::vector<fs::path>& roots, const std::string& id_or_name) {
  std::vector<std::string> broken;
  auto all = discover_benchmarks(roots, &broken);
  for (auto& spec : all) {
    if (spec.id == id_or_name || spec.name == id_or_name) return std::move(spec);
  }
  // A package that failed to load is reported with its own error.
  for (const auto& b : broken) {
    if (b.find("/" + id_or_name) != std::string::npos) throw BenchmarkError(b);
  }
  std::string ids;
  std::vector<std::string> names;
  for (const auto& s : all) {
    ids += (ids.empty() ? "" : ", ") + s.id;
    names.push_back(s.id);
    names.push_back(s.name);
  }
  throw BenchmarkError("unknown benchmark '" + id_or_name + "'" + did_you_mean(id_or_name, names) +
                       " (available: " + ids + "; see 'robotperf list')");
}

BenchmarkSpec find_benchmark(const fs::path& root, const std::string& id_or_name) {
  return find_benchmark(std::vector<fs::path>{root}, id_or_name);
}

const plugin::KernelEntry& kernel_of(const NodeSpec& node) {
  const plugin::KernelEntry* entry = plugin::registry().find_kernel(node.kernel);
  if (entry == nullptr)
    throw BenchmarkError("node '" + node.name + "': unknown kernel '" + node.kernel + "'");
  return *entry;
}

plugin::KernelConfig kernel_config(const NodeSpec& node,
                                   const std::map<std::string, std::string>& workload) {
  plugin::KernelConfig config;
  config.node_name = node.name;
  config.backend = node.backend;
  if (const auto seed = workload.find("seed"); seed != workload.end()) {
    uint64_t value = 0;
    const std::string& text = seed->second;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (ec != std::errc() || end != text.data() + text.size())
      throw BenchmarkError("workload seed: '" + text + "' is not a valid number");
    config.workload_seed = value;
  }
  try {
    config.parameters = plugin::Parameters(kernel_of(node).info.parameters, node.parameters,
                                           "node '" + node.name + "'");
  } catch (const std::invalid_argument& e) {
    throw BenchmarkError(e.what());
  }
  config.topics = node.topics;
  config.qos = node.qos;
  config.device_resident_outputs = node.device_resident_outputs;
  return config;
}

std::shared_ptr<graph::Node> make_kernel_node(const NodeSpec& node, graph::Context& context,
                                              const std::map<std::string, std::string>& workload) {
  const plugin::KernelEntry& entry = kernel_of(node);
  if (std::ranges::count(entry.info.backends, node.backend) == 0) {
    throw std::invalid_argument("node '" + node.name + "': kernel " + node.kernel +
                                " has no backend '" + node.backend + "'");
  }
  const std::string who = "node '" + node.name + "'";
  std::shared_ptr<graph::Node> built;
  try {
    built = entry.factory_on(node.backend)(context, kernel_config(node, workload));
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    throw std::invalid_argument(what.starts_with(who) ? what : who + ": " + what);
  } catch (const std::exception& e) {
    // A kernel that cannot start (a missing device, a plug-in's own failure) is named with where
    // it came from.
    throw std::runtime_error(who + ": kernel " + node.kernel + " (" +
                             entry.origin_on(node.backend) + ") failed to start: " + e.what());
  }
  if (!built) {
    throw std::runtime_error("node '" + node.name + "': kernel " + node.kernel + " (" +
                             entry.origin_on(node.backend) + ") built no node");
  }
  return built;
}

void override_update_rate(BenchmarkSpec& spec, double hz) {
  // Beyond 100 kHz the period (10 us) is shorter than one cycle's wake-up on a general-purpose OS.
  if (!std::isfinite(hz) || !(hz > 0) || hz > 100'000)
    throw std::invalid_argument("--update-rate must be a rate in Hz, above 0 and at most 100000");
  bool found = false;
  for (auto& n : spec.nodes) {
    const auto& loop = kernel_of(n).info.control_loop;
    if (!loop) continue;
    std::ostringstream text;
    text.precision(17);
    text << hz;
    n.parameters[loop->rate_parameter] = text.str();
    found = true;
  }
  if (!found)
    throw std::invalid_argument(
        "--update-rate applies to benchmarks whose kernels run a control loop (a controller "
        "manager's); " +
        spec.id + " has none");
}

void override_backend(BenchmarkSpec& spec, const std::string& backend) {
  std::set<std::string> available;
  bool found = false;
  for (auto& n : spec.nodes) {
    const auto& backends = kernel_of(n).info.backends;
    available.insert(backends.begin(), backends.end());
    if (std::ranges::count(backends, backend) == 0) continue;
    n.backend = backend;
    found = true;
  }
  if (!found) {
    std::string names;
    for (const auto& b : available) names += (names.empty() ? "" : ", ") + b;
    throw std::invalid_argument("--backend " + backend + ": no kernel of " + spec.id +
                                " has it (they have: " + (names.empty() ? "none" : names) + ")");
  }
}

std::vector<ResidentTopic> keep_on_device(BenchmarkSpec& spec) {
  // Whether `node` keeps or takes `port`'s data on its device.
  const auto on_device = [](const NodeSpec& node, const std::vector<plugin::PortInfo>& ports,
                            const std::string& port) {
    const auto& backends = kernel_of(node).info.device_resident_backends;
    const auto it = std::ranges::find(ports, port, &plugin::PortInfo::name);
    return it != ports.end() && it->device_resident &&
           std::ranges::count(backends, node.backend) > 0;
  };
  // What takes each topic: the nodes (by index) with an input port wired to it, and whether that
  // port takes it on the node's device.
  std::map<std::string, std::vector<std::pair<std::size_t, bool>>> takers;
  for (std::size_t i = 0; i < spec.nodes.size(); ++i) {
    const NodeSpec& node = spec.nodes[i];
    const auto& inputs = kernel_of(node).info.inputs;
    for (const auto& [port, topic] : node.topics) {
      if (std::ranges::count(inputs, port, &plugin::PortInfo::name) > 0)
        takers[topic].emplace_back(i, on_device(node, inputs, port));
    }
  }
  std::set<std::string> on_the_host{spec.output.topic};
  for (const auto& out : spec.more_outputs) on_the_host.insert(out.topic);
  if (spec.functional && !spec.functional->observed_truth_topic.empty())
    on_the_host.insert(spec.functional->observed_truth_topic);
  std::vector<ResidentTopic> kept;
  for (NodeSpec& from : spec.nodes) {
    const auto& outputs = kernel_of(from).info.outputs;
    for (const auto& [port, topic] : from.topics) {
      if (!on_device(from, outputs, port)) continue;
      const auto taken = takers.find(topic);
      if (on_the_host.contains(topic) || taken == takers.end()) continue;
      ResidentTopic t{topic, from.name, {}, from.backend};
      bool all = true;
      for (const auto& [i, takes_on_device] : taken->second) {
        const NodeSpec& to = spec.nodes[i];
        all = all && takes_on_device && to.backend == from.backend;
        t.to.push_back(to.name);
      }
      if (!all) continue;
      from.device_resident_outputs.insert(port);
      kept.push_back(std::move(t));
    }
  }
  if (kept.empty()) {
    throw std::invalid_argument(
        "--device-resident: no topic of " + spec.id +
        " can stay on the device: that needs a node whose output only other nodes take, all on "
        "one backend on which their kernels hand data over through those ports (as a1's rectify "
        "and resize do on cuda)");
  }
  return kept;
}

}  // namespace robotperf::harness
