// The nodes of a per-node run travel to each node process as the runner resolved them.
#include "robotperf/harness/node_spec_wire.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <stdexcept>
#include <string>

#include "robotperf/harness/run.hpp"
#include "robotperf/rmw/transport.hpp"
#include "test_package.hpp"

namespace robotperf::harness {
namespace {

using testing::relay_graph;
using testing::TestPackage;

bool same_node(const NodeSpec& a, const NodeSpec& b) {
  return a.name == b.name && a.kernel == b.kernel && a.backend == b.backend && a.host == b.host &&
         a.parameters == b.parameters && a.topics == b.topics && a.qos == b.qos &&
         a.device_resident_outputs == b.device_resident_outputs;
}

TEST(NodeSpecWire, TheChildRunsTheNodesAsTheRunnerResolvedThem) {
  TestPackage p("wire", relay_graph("fail_after: 10"));
  const BenchmarkSpec package = load_benchmark(p.dir());
  BenchmarkSpec resolved = package;
  NodeSpec& relay = resolved.nodes.at(0);
  relay.backend = "opencl";
  relay.host = "robot-b";
  relay.parameters["fail_after"] = "a value with spaces, \"quotes\" and {braces}";
  relay.qos = rmw::QoS::sensor_data();
  relay.device_resident_outputs = {"output"};

  const std::string encoded = encode_nodes(resolved.nodes);
  EXPECT_EQ(encoded.find_first_not_of("0123456789abcdef"), std::string::npos)
      << "a word no shell splits or expands: " << encoded;
  BenchmarkSpec child = package;
  use_encoded_nodes(child, encoded);
  ASSERT_EQ(child.nodes.size(), 1u);
  EXPECT_TRUE(same_node(child.nodes[0], relay));
  EXPECT_FALSE(same_node(child.nodes[0], package.nodes[0]));
}

TEST(NodeSpecWire, RefusesWhatTheRunnerDoesNotWrite) {
  TestPackage p("wire_refused", relay_graph(""));
  BenchmarkSpec spec = load_benchmark(p.dir());
  EXPECT_THROW(use_encoded_nodes(spec, "5"), std::invalid_argument);
  EXPECT_THROW(use_encoded_nodes(spec, "zz"), std::invalid_argument);
  EXPECT_THROW(use_encoded_nodes(spec, encode_nodes({})), std::invalid_argument)
      << "another graph than the package's";
  BenchmarkSpec renamed = spec;
  renamed.nodes[0].name = "other";
  EXPECT_THROW(use_encoded_nodes(spec, encode_nodes(renamed.nodes)), std::invalid_argument);
  const std::string not_nodes = "7b7d";  // {}
  EXPECT_THROW(use_encoded_nodes(spec, not_nodes), std::invalid_argument);
  EXPECT_EQ(spec.nodes[0].name, "relay") << "a refused encoding leaves the package's nodes";
}

// --update-rate reaches the controller's own process with its node, not as a flag to re-apply.
TEST(NodeSpecWire, APerNodeControllerRunsAtTheOverriddenRate) {
  RunOptions o;
  o.load.count = 60;
  o.load.warmup = 5;
  o.nodes.update_rate_hz = 250;
  o.transport.rmw = "fastdds";
  o.processes.layout = ProcessLayout::kPerNode;
  o.transport.domain_id = rmw::reserved_domain();
  o.processes.node_command = {ROBOTPERF_EXECUTABLE, "node"};
  const RunResult r = run_benchmark(
      find_benchmark(std::filesystem::path(ROBOTPERF_SOURCE_DIR) / "benchmarks", "c3"), o);
  EXPECT_TRUE(r.errors.empty()) << r.errors.front();
  ASSERT_EQ(r.control_loops.size(), 1u);
  EXPECT_EQ(r.control_loops[0].update_rate_hz, 250.0);
  EXPECT_GT(r.nodes.at(0).pid, 0) << "the controller ran in a process of its own";
}

}  // namespace
}  // namespace robotperf::harness
