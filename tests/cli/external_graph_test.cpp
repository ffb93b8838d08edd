// External graphs: processes robotperf did not build (graph.yaml `launch:`), measured by the
// Playback and Monitor around them. The node is echo_peer, a separate program on robotperf's rmw
// library, launched as a ROS 2 node runs: until SIGINT.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "../command_line.hpp"
#include "robotperf/rmw/transport.hpp"

namespace {

namespace fs = std::filesystem;
using robotperf::test_support::Outcome;
using robotperf::test_support::robotperf_cli;

class ExternalGraph : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("robotperf-external-" + std::to_string(getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Runs x1: 130 payloads at 50 Hz through echo_peer in `mode` (see echo_peer.cpp).
  Outcome run_echo(const std::string& mode, const std::string& rmw = "fastdds",
                   const std::string& echo_topic = "/pong", const std::string& extra = "",
                   const std::string& input_qos = "default") {
    const fs::path package = dir_ / "benchmarks" / "external" / "x1_echo";
    fs::create_directories(package);
    std::ofstream(package / "benchmark.yaml")
        << "id: x1\nname: x1_echo\nshort: test\ndescription: test\nresults: []\n";
    std::ofstream(package / "graph.yaml")
        << "dataset: middleware/payload\nrate_hz: 50\ncount: 130\nwarmup: 10\n"
           "validity: {min_samples: 100}\n"
           "inputs:\n  - {topic: /ping, type: sensor_msgs/msg/Image, stream: payload, qos: "
        << input_qos
        << "}\n"
           "output: {topic: /pong, type: sensor_msgs/msg/Image}\n"
           "launch:\n  - name: echo\n    command: [" ROBOTPERF_ECHO_PEER
           ", '${rmw}', '${domain}', /ping, "
        << echo_topic << ", " << mode
        << "]\n"
           "functional: {evaluator: payload_echo, truth: {sent: payload}, sample: 0}\n";
    return robotperf_cli("--benchmarks " + (dir_ / "benchmarks").string() + " run x1 --rmw " + rmw +
                         " --quiet --domain " + std::to_string(robotperf::rmw::reserved_domain()) +
                         " --output " + (dir_ / "results").string() + extra);
  }
  nlohmann::json result() {
    for (const auto& e : fs::directory_iterator(dir_ / "results")) {
      if (e.path().extension() == ".json") return nlohmann::json::parse(std::ifstream(e.path()));
    }
    return {};
  }

  fs::path dir_;
};

TEST_F(ExternalGraph, LaunchedNodeIsMeasuredAndStoppedByAnInterrupt) {
  for (const std::string rmw : {"fastdds", "cyclonedds"}) {
    fs::remove_all(dir_ / "results");
    const Outcome o = run_echo("until-signal", rmw);
    ASSERT_EQ(o.exit_code, 0) << rmw << "\n" << o.out;
    const auto j = result();
    EXPECT_EQ(j["counts"]["matched"], 120);
    EXPECT_EQ(j["functional"]["metrics"]["identical_fraction"]["value"], 1.0);
    ASSERT_EQ(j["launched"].size(), 1u);
    const auto& echo = j["launched"][0];
    EXPECT_EQ(echo["stopped_by"], "stopped by SIGINT") << echo.dump();
    EXPECT_EQ(echo["exit_status"], "ok");
    EXPECT_TRUE(fs::exists(echo["log"].get<std::string>()));
    // Its own CPU and memory, beside the runner's.
    bool sampled = false;
    for (const auto& p : j["resources"]["processes"]) sampled = sampled || p["label"] == "echo";
    EXPECT_TRUE(sampled) << j["resources"].dump();
  }
}

TEST_F(ExternalGraph, NodeDyingMidRunEndsTheRunWithItsLogKept) {
  const auto start = std::chrono::steady_clock::now();
  const Outcome o = run_echo("exit-after=40");
  EXPECT_EQ(o.exit_code, 3) << o.out;
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(30));
  EXPECT_NE(o.out.find("launched process 'echo'"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("exited with status 7"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("exiting after 40 echoes"), std::string::npos) << o.out;  // its log's tail
  const auto j = result();
  EXPECT_FALSE(j["completed"].get<bool>());
  EXPECT_GE(j["counts"]["matched"].get<int>(), 25);  // what was measured is kept
  EXPECT_EQ(j["launched"][0]["stopped_by"], "ended during the run");
  EXPECT_TRUE(fs::exists(j["launched"][0]["log"].get<std::string>()));
}

TEST_F(ExternalGraph, NodeThatDoesNotCopyTheHeaderIsNamedNotLost) {
  const Outcome o = run_echo("restamp");
  EXPECT_EQ(o.exit_code, 3) << o.out;
  EXPECT_NE(o.out.find("does not copy its input's header"), std::string::npos) << o.out;
  EXPECT_EQ(o.out.find("% lost, above"), std::string::npos) << o.out;
}

// A graph that never publishes the output: refused once --connect-timeout has passed.
TEST_F(ExternalGraph, GraphThatNeverConnectsIsRefusedAfterTheConnectTimeout) {
  const auto start = std::chrono::steady_clock::now();
  const Outcome o = run_echo("until-signal", "fastdds", "/elsewhere", " --connect-timeout 2");
  EXPECT_EQ(o.exit_code, 2) << o.out;
  // One line per endpoint without its peer, saying who else is on its topic.
  EXPECT_NE(o.out.find("\n  robotperf_monitor subscribing /pong [sensor_msgs/msg/Image] has no "
                       "peer: no other participant on domain"),
            std::string::npos)
      << o.out;
  EXPECT_EQ(o.out.find("publishing /ping"), std::string::npos) << "the echo reads /ping\n" << o.out;
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(12));
}

// A best-effort Playback cannot feed a node that asks for reliable delivery: the endpoint is named,
// with the node's participant that is on its topic and the QoS we offer.
TEST_F(ExternalGraph, QosIncompatibleEndpointIsNamedWithWhoIsOnItsTopic) {
  const Outcome o =
      run_echo("until-signal", "fastdds", "/pong", " --connect-timeout 3", "sensor_data");
  EXPECT_EQ(o.exit_code, 2) << o.out;
  EXPECT_NE(o.out.find("robotperf_playback publishing /ping [sensor_msgs/msg/Image] has no peer: "
                       "participant(s) 'robotperf' have an endpoint on it that did not match: "
                       "check its type and QoS (ours: best_effort, volatile, keep_last 5)"),
            std::string::npos)
      << o.out;
}

TEST_F(ExternalGraph, NeedsADdsTransport) {
  const Outcome o = run_echo("until-signal", "intra");
  EXPECT_EQ(o.exit_code, 2) << o.out;
  EXPECT_NE(o.out.find("reached through DDS"), std::string::npos) << o.out;
}

}  // namespace
