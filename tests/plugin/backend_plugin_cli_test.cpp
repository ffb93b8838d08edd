// A plug-in's own backend and output comparison, used as the built-in categories' are: `run
// --backend` runs its kernel there and judges the answers with its comparison, `sysinfo` lists
// its devices, and a backend it cannot run is refused with its own line.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "../command_line.hpp"
#include "robotperf/rmw/transport.hpp"

namespace {

namespace fs = std::filesystem;

using robotperf::test_support::Outcome;
using robotperf::test_support::robotperf_cli;

class BackendPlugin : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("robotperf-backend-plugin-" + std::to_string(getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Package `id` under dir_/benchmarks/tests/, running the plug-in's kernel with its
  // accelerator off by `accelerator_error`.
  void add_package(const std::string& id, double accelerator_error) {
    std::ostringstream parameters;
    parameters << "{accelerator_error: " << accelerator_error << "}";
    add_package(id, "backend_plugin/offset", parameters.str());
  }
  // Package `id` running `kernel` with `parameters` (a YAML map) on the plug-in's joint states.
  void add_package(const std::string& id, const std::string& kernel,
                   const std::string& parameters) {
    const fs::path package = dir_ / "benchmarks" / "tests" / (id + "_offset");
    fs::create_directories(package);
    std::ofstream(package / "benchmark.yaml")
        << "id: " << id << "\nname: " << id
        << "_offset\nshort: the backend plug-in's kernel\ndescription: test\nresults: []\n";
    std::ofstream(package / "graph.yaml")
        << "dataset: backend_plugin/joints\nrate_hz: 50\nwarmup: 2\n"
           "validity: {min_samples: 10, max_loss_percent: 0.0}\n"
           "inputs:\n  - {topic: /states, type: sensor_msgs/msg/JointState, stream: states}\n"
           "output: {topic: /offset, type: sensor_msgs/msg/JointState}\n"
           "nodes:\n  - name: offset\n    kernel: "
        << kernel
        << "\n    topics: {input: /states, output: /offset}\n    parameters: " << parameters
        << "\n";
  }

  std::string with_plugin(const std::string& command) const {
    return "--plugin " + std::string(BACKEND_PLUGIN) + " --benchmarks " +
           (dir_ / "benchmarks").string() + " " + command;
  }

  // Runs `id` on the plug-in's backend; the results file's JSON, null when there is none.
  nlohmann::json run_on_accelerator(const std::string& id, Outcome& outcome) const {
    const fs::path out = dir_ / ("out-" + id);
    outcome = robotperf_cli(with_plugin(
        "run " + id + " --backend test_accelerator --count 40 --quiet --domain " +
        std::to_string(robotperf::rmw::reserved_domain()) + " --output " + out.string()));
    if (!fs::is_directory(out)) return nullptr;
    for (const auto& e : fs::directory_iterator(out)) {
      if (e.path().extension() == ".json") {
        std::ifstream in(e.path());
        return nlohmann::json::parse(in);
      }
    }
    return nullptr;
  }

  fs::path dir_;
};

TEST_F(BackendPlugin, RunOnItsBackendIsJudgedByItsComparison) {
  add_package("x1", 0.0);
  Outcome o;
  const nlohmann::json j = run_on_accelerator("x1", o);
  ASSERT_EQ(o.exit_code, 0) << o.out;
  ASSERT_TRUE(j.is_object()) << o.out;
  EXPECT_EQ(j["nodes"][0]["backend"], "test_accelerator") << j["nodes"].dump();
  const nlohmann::json& check = j["backend_check"];
  ASSERT_TRUE(check.is_object()) << j.dump();
  EXPECT_EQ(check["backend"], "test_accelerator");
  EXPECT_EQ(check["output_type"], "sensor_msgs/msg/JointState");
  EXPECT_EQ(check["criterion"], "joint positions within 1e-9 (backend_plugin)");
  EXPECT_GT(check["compared"].get<int>(), 0);
  EXPECT_EQ(check["agreement"], 1.0);
  EXPECT_EQ(check["passed"], true) << check.dump();
}

// The plug-in's implementation of a built-in kernel (util/relay) on its backend: the node on
// test_accelerator is the plug-in's, recorded as its origin, and answers as the cpu's relay does.
TEST_F(BackendPlugin, ItsImplementationOfABuiltInKernelRunsOnItsBackend) {
  add_package("x4", "util/relay", "{type: sensor_msgs/msg/JointState}");
  Outcome o;
  const nlohmann::json j = run_on_accelerator("x4", o);
  ASSERT_EQ(o.exit_code, 0) << o.out;
  ASSERT_TRUE(j.is_object()) << o.out;
  const nlohmann::json& node = j["nodes"][0];
  EXPECT_EQ(node["kernel"], "util/relay") << node.dump();
  EXPECT_EQ(node["backend"], "test_accelerator") << node.dump();
  EXPECT_EQ(node["origin"], fs::canonical(BACKEND_PLUGIN).string()) << node.dump();
  EXPECT_EQ(j["backend_check"]["passed"], true) << j["backend_check"].dump();

  // Its kernel list names the backend the plug-in added to the built-in kernel.
  const Outcome list = robotperf_cli(with_plugin("list kernels"));
  ASSERT_EQ(list.exit_code, 0) << list.out;
  const std::size_t relay = list.out.find("util/relay");
  ASSERT_NE(relay, std::string::npos) << list.out;
  EXPECT_NE(list.out.find("cpu, test_accelerator", relay), std::string::npos) << list.out;
}

TEST_F(BackendPlugin, AnAnswerItsComparisonRejectsMakesTheRunInvalid) {
  add_package("x2", 0.5);
  Outcome o;
  const nlohmann::json j = run_on_accelerator("x2", o);
  EXPECT_EQ(o.exit_code, 3) << o.out;
  ASSERT_TRUE(j.is_object()) << o.out;
  const nlohmann::json& check = j["backend_check"];
  ASSERT_TRUE(check.is_object()) << j.dump();
  EXPECT_EQ(check["passed"], false);
  EXPECT_EQ(check["agreement"], 0.0);
  EXPECT_EQ(j["functional"]["valid"], false);
  EXPECT_NE(check["reasons"][0].get<std::string>().find(
                "test_accelerator drifts from cpu: joint positions within 1e-9 (backend_plugin)"),
            std::string::npos)
      << check.dump();
}

TEST_F(BackendPlugin, SysinfoListsItsDevicesBesideTheBuiltInBackends) {
  const Outcome o = robotperf_cli(with_plugin("sysinfo"));
  ASSERT_EQ(o.exit_code, 0) << o.out;
  const auto j = nlohmann::json::parse(o.out);
  ASSERT_EQ(j["test_accelerator_devices"].size(), 1u) << o.out;
  EXPECT_EQ(j["test_accelerator_devices"][0]["name"], "test accelerator 0");
  EXPECT_EQ(j["test_accelerator_devices"][0]["memory_bytes"], 1 << 20);
  EXPECT_TRUE(j["test_unbuilt_devices"].is_array());
  EXPECT_TRUE(j["test_unbuilt_devices"].empty());
  EXPECT_TRUE(j["opencl_devices"].is_array()) << o.out;
  EXPECT_TRUE(j["cuda_devices"].is_array()) << o.out;
  EXPECT_FALSE(j.contains("cpu_devices")) << o.out;
}

TEST_F(BackendPlugin, ABackendThisBuildLacksIsRefusedWithItsOwnLine) {
  add_package("x3", 0.0);
  const Outcome o = robotperf_cli(
      with_plugin("run x3 --backend test_unbuilt --count 20 --output " + (dir_ / "out").string()));
  EXPECT_EQ(o.exit_code, 2) << o.out;
  EXPECT_EQ(o.out,
            "robotperf: --backend test_unbuilt: the test_unbuilt backend was not built into this "
            "robotperf\n");
  EXPECT_FALSE(fs::exists(dir_ / "out"));
}

}  // namespace
