// External graphs: processes robotperf did not build (graph.yaml `launch:`), measured by the
// Playback and Monitor around them. The nodes are echo_peer, a separate program on robotperf's rmw
// library, and foreign_image_node, a C program on Cyclone DDS's C API that shares no code with
// robotperf; both are launched as a ROS 2 node runs: until SIGINT.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "../command_line.hpp"
#include "../sanitized_build.hpp"
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

  // Writes package `id` with `graph` as its graph.yaml; returns the arguments that run it on
  // `rmw`.
  std::string package_run(const std::string& id, const std::string& graph, const std::string& rmw) {
    const fs::path package = dir_ / "benchmarks" / "external" / id;
    fs::create_directories(package);
    std::ofstream(package / "benchmark.yaml")
        << "id: " << id << "\nname: " << id << "\nshort: test\ndescription: test\nresults: []\n";
    std::ofstream(package / "graph.yaml") << graph;
    return "--benchmarks " + (dir_ / "benchmarks").string() + " run " + id + " --rmw " + rmw +
           " --quiet --domain " + std::to_string(robotperf::rmw::reserved_domain()) + " --output " +
           (dir_ / "results").string();
  }
  // Writes package `id` with `graph` as its graph.yaml and runs it on `rmw`.
  Outcome run_package(const std::string& id, const std::string& graph, const std::string& rmw,
                      const std::string& extra = "") {
    return robotperf_cli(package_run(id, graph, rmw) + extra);
  }

  // Runs x1: 130 payloads at 50 Hz through echo_peer in `mode` (see echo_peer.cpp).
  Outcome run_echo(const std::string& mode, const std::string& rmw = "fastdds",
                   const std::string& echo_topic = "/pong", const std::string& extra = "",
                   const std::string& input_qos = "default") {
    return run_package(
        "x1",
        "dataset: middleware/payload\nrate_hz: 50\ncount: 130\nwarmup: 10\n"
        "validity: {min_samples: 100}\n"
        "inputs:\n  - {topic: /ping, type: sensor_msgs/msg/Image, stream: payload, qos: " +
            input_qos +
            "}\n"
            "output: {topic: /pong, type: sensor_msgs/msg/Image}\n"
            "launch:\n  - name: echo\n    command: [" ROBOTPERF_ECHO_PEER
            ", '${rmw}', '${domain}', /ping, " +
            echo_topic + ", " + mode +
            "]\n"
            "functional: {evaluator: payload_echo, truth: {sent: payload}, sample: 0}\n",
        rmw, extra);
  }
  // A graph of foreign_image_node in `mode` between /camera/image_raw and /foreign/image, whose
  // output is declared as `output_type` (and checked to echo the input when it is an Image).
  static std::string foreign_graph(const std::string& mode, int count,
                                   const std::string& output_type = "sensor_msgs/msg/Image") {
    return "dataset: perception/image\nrate_hz: 30\ncount: " + std::to_string(count) +
           "\nwarmup: 10\nvalidity: {min_samples: " + std::to_string(count - 10) +
           "}\n"
           "inputs:\n  - {topic: /camera/image_raw, type: sensor_msgs/msg/Image, stream: image}\n"
           "output: {topic: /foreign/image, type: " +
           output_type +
           "}\n"
           "launch:\n  - name: foreign\n    command: [" ROBOTPERF_FOREIGN_IMAGE_NODE
           ", '${domain}', /camera/image_raw, /foreign/image, " +
           mode + ", vga_echo]\n" +
           (output_type == "sensor_msgs/msg/Image"
                ? "functional: {evaluator: payload_echo, truth: {sent: image}, sample: 0}\n"
                : "");
  }
  // Runs x2: the perception/image dataset (640x480 rgb8) at 30 Hz through foreign_image_node.
  Outcome run_foreign(const std::string& mode, const std::string& rmw, int count,
                      const std::string& extra = "") {
    return run_package("x2", foreign_graph(mode, count), rmw, extra);
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

// Grey-box: the launched node's own ros2:* events go into the run's trace and count as the run's
// (echo_peer announces itself as a node built with tracetools does), so the publish-to-take table
// has both of its topics.
TEST_F(ExternalGraph, GreyRunTracesTheLaunchedNodesOwnEvents) {
  const Outcome o = run_echo("until-signal", "fastdds", "/pong", " --mode grey");
  const auto j = result();
  ASSERT_TRUE(j.is_object()) << o.out;
  // Every process of the user is recorded, so other tests' runs meanwhile share the tracer's
  // buffers: where they made it discard events or lose packets the run is INVALID (3).
  const auto& trace = j["grey"]["trace"];
  if (trace["discarded_events"] == 0 && trace["lost_packets"] == 0) {
    EXPECT_EQ(o.exit_code, 0) << o.out;
    EXPECT_EQ(j["counts"]["matched"], 120);
  } else {
    EXPECT_EQ(o.exit_code, 3) << o.out;
  }
  std::set<std::string> rows;
  for (const auto& t : j["grey"]["topics"])
    rows.insert(t["topic"].get<std::string>() + ": " + t["publisher"].get<std::string>() + " -> " +
                t["subscriber"].get<std::string>());
  EXPECT_TRUE(rows.contains("/ping: robotperf_playback -> echo_peer")) << j["grey"].dump();
  EXPECT_TRUE(rows.contains("/pong: echo_peer -> robotperf_monitor")) << j["grey"].dump();
}

// A second Ctrl-C ends robotperf at once, and the launched processes with it: here one that
// ignores the first, so that the run is still waiting for it to stop.
TEST_F(ExternalGraph, ASecondInterruptStopsTheLaunchedProcessesToo) {
  const std::string stubborn = "613." + std::to_string(getpid());  // sleep's seconds: ours alone
  const fs::path readings = dir_ / "readings";
  const std::string run_args =
      package_run("x1",
                  "dataset: middleware/payload\nrate_hz: 50\ncount: 100000\nwarmup: 10\n"
                  "inputs:\n  - {topic: /ping, type: sensor_msgs/msg/Image, stream: payload}\n"
                  "output: {topic: /pong, type: sensor_msgs/msg/Image}\n"
                  "launch:\n  - name: echo\n    command: [" ROBOTPERF_ECHO_PEER
                  ", '${rmw}', '${domain}', /ping, /pong, until-signal]\n"
                  "  - name: stubborn\n    command: [sh, -c, \"trap '' INT TERM; exec sleep " +
                      stubborn + "\"]\n",
                  "fastdds");
  robotperf::test_support::Background run(std::string(ROBOTPERF_EXECUTABLE) + " " + run_args +
                                              " --power-meter 'echo x >> " + readings.string() +
                                              "; echo 5'",
                                          dir_ / "log");
  auto readings_taken = [&] {
    std::ifstream in(readings);
    return std::count(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>(), '\n');
  };
  // The meter's second reading: the run is under way.
  ASSERT_TRUE(robotperf::test_support::eventually([&] { return readings_taken() >= 2; },
                                                  std::chrono::seconds(60)))
      << run.output();
  auto stubborn_left = [&] {
    // The brackets keep pgrep's own shell, whose command line holds the pattern, out.
    return robotperf::test_support::shell("pgrep -f '[s]leep " + stubborn + "'").exit_code == 0;
  };
  ASSERT_TRUE(stubborn_left());
  run.signal(SIGINT);
  ASSERT_TRUE(robotperf::test_support::eventually(
      [&] { return run.output().find("interrupted: ending") != std::string::npos; },
      std::chrono::seconds(30)))
      << run.output();
  run.signal(SIGINT);
  EXPECT_EQ(run.wait(std::chrono::seconds(30)), 130) << run.output();
  EXPECT_TRUE(robotperf::test_support::eventually([&] { return !stubborn_left(); },
                                                  std::chrono::seconds(10)));
  robotperf::test_support::shell("pkill -KILL -f '[s]leep " + stubborn + "'");
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

// A launched node that exits while the graph is still connecting: the graph as given cannot run
// (exit 2), and the message says it ended before connecting, with its log's last lines.
TEST_F(ExternalGraph, NodeExitingBeforeTheGraphConnectsIsRefused) {
  const Outcome o =
      run_package("x3",
                  "dataset: middleware/payload\nrate_hz: 50\ncount: 130\nwarmup: 10\n"
                  "inputs:\n  - {topic: /ping, type: sensor_msgs/msg/Image, stream: payload}\n"
                  "output: {topic: /pong, type: sensor_msgs/msg/Image}\n"
                  "launch:\n  - name: camera_driver\n    command: [/bin/sh, -c, "
                  "'echo cannot open /dev/video9 >&2; exit 4']\n",
                  "fastdds");
  EXPECT_EQ(o.exit_code, 2) << o.out;
  EXPECT_NE(o.out.find("launched process 'camera_driver'"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("ended before the graph connected (exited with status 4)"),
            std::string::npos)
      << o.out;
  EXPECT_NE(o.out.find("cannot open /dev/video9"), std::string::npos) << o.out;
  EXPECT_EQ(o.out.find("during the run"), std::string::npos) << o.out;
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
// with the node on its topic, what it asks for, why it does not match, and the QoS we offer.
TEST_F(ExternalGraph, QosIncompatibleEndpointIsNamedWithWhoIsOnItsTopic) {
  const Outcome o =
      run_echo("until-signal", "fastdds", "/pong", " --connect-timeout 3", "sensor_data");
  EXPECT_EQ(o.exit_code, 2) << o.out;
  EXPECT_NE(o.out.find("robotperf_playback publishing /ping [sensor_msgs/msg/Image] has no peer: "
                       "node /echo_peer subscribes it as sensor_msgs/msg/Image (reliable, "
                       "volatile): a reliable subscription needs a reliable publisher (ours: "
                       "best_effort, volatile, keep_last 5)"),
            std::string::npos)
      << o.out;
}

// An output declared with another type than the node publishes: named with the node's type.
TEST_F(ExternalGraph, TypeMismatchAtTheOutputIsNamed) {
  const Outcome o = run_package("x3", foreign_graph("copy", 40, "sensor_msgs/msg/CameraInfo"),
                                "cyclonedds", " --connect-timeout 3");
  EXPECT_EQ(o.exit_code, 2) << o.out;
  EXPECT_NE(o.out.find("robotperf_monitor subscribing /foreign/image [sensor_msgs/msg/CameraInfo] "
                       "has no peer: node /vga_echo publishes it as sensor_msgs/msg/Image "
                       "(reliable, volatile): its type is sensor_msgs/msg/Image"),
            std::string::npos)
      << o.out;
}

// A node of another code base (Cyclone's C API and IDL compiler), fed VGA colour images at 30 Hz
// on its own vendor and across vendors: every image comes back, byte for byte. Across vendors its
// side of discovery may complete hundreds of milliseconds after ours; the warm-up is repeated
// until it delivers, so that no measured message meets an unmatched reader.
TEST_F(ExternalGraph, ForeignNodeAtVgaColour30HzLosesNothing) {
  if (kSanitizedBuild) GTEST_SKIP() << kRateNeedsUnsanitizedBuild;
  for (const std::string rmw : {"cyclonedds", "fastdds"}) {
    fs::remove_all(dir_ / "results");
    const Outcome o = run_foreign("copy", rmw, 100);
    ASSERT_EQ(o.exit_code, 0) << rmw << "\n" << o.out;
    const auto j = result();
    EXPECT_EQ(j["counts"]["matched"], 90) << rmw;
    EXPECT_EQ(j["counts"]["lost"], 0) << rmw;
    EXPECT_EQ(j["functional"]["metrics"]["identical_fraction"]["value"], 1.0) << rmw;
    EXPECT_EQ(j["launched"][0]["stopped_by"], "stopped by SIGINT") << j["launched"].dump();
    EXPECT_GE(j["configuration"]["warmup_repeated_s"].get<double>(), 0.0);
  }
}

// The launched node is on the domain by design: listed in domain_peers, but no "other
// participant" (which would make --strict refuse every external graph).
TEST_F(ExternalGraph, ALaunchedNodeIsTheGraphsOwnNotAnotherParticipant) {
  const Outcome o = run_foreign("copy", "cyclonedds", 40);
  ASSERT_TRUE(o.exit_code == 0 || o.exit_code == 3) << o.out;  // 3: a sanitized build's loss
  const auto j = result();
  ASSERT_FALSE(j["domain_peers"].empty()) << j.dump();
  for (const auto& w : j["warnings"]) EXPECT_NE(w["rule"], "other_participants") << w.dump();
}

// A node that matches every endpoint but never publishes: refused once --connect-timeout has
// passed, however long the warm-up is repeated.
TEST_F(ExternalGraph, ForeignNodeThatNeverDeliversIsRefused) {
  const auto start = std::chrono::steady_clock::now();
  const Outcome o = run_foreign("drop", "cyclonedds", 40, " --connect-timeout 2");
  EXPECT_EQ(o.exit_code, 2) << o.out;
  EXPECT_NE(o.out.find("delivered no output to its warm-up messages"), std::string::npos) << o.out;
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(20));
}

TEST_F(ExternalGraph, ForeignNodeThatRestampsIsNamedNotLost) {
  const Outcome o = run_foreign("restamp", "cyclonedds", 40);
  EXPECT_EQ(o.exit_code, 3) << o.out;
  EXPECT_NE(o.out.find("does not copy its input's header"), std::string::npos) << o.out;
}

// `robotperf graph` lists a node it did not make, from that node's own ros_discovery_info and
// discovery data, across vendors (the node is on Cyclone DDS, the listing on Fast DDS).
TEST_F(ExternalGraph, GraphVerbListsAForeignNode) {
  fs::create_directories(dir_);
  const int domain = robotperf::rmw::reserved_domain();
  robotperf::test_support::Background node(std::string(ROBOTPERF_FOREIGN_IMAGE_NODE) + " " +
                                               std::to_string(domain) +
                                               " /camera/image_raw /vga/image copy vga_echo",
                                           dir_ / "node.log");
  const std::string args = "graph --rmw fastdds --listen 2 --domain " + std::to_string(domain);
  const Outcome json_out = robotperf_cli(args + " --json");
  ASSERT_EQ(json_out.exit_code, 0) << json_out.out;
  const auto graph = nlohmann::json::parse(json_out.out);
  const nlohmann::json* found = nullptr;
  for (const auto& p : graph["participants"]) {
    for (const auto& n : p["nodes"]) {
      if (n["name"] == "/vga_echo") found = &n;
    }
  }
  ASSERT_NE(found, nullptr) << graph.dump(2) << "\n" << node.output();
  ASSERT_EQ((*found)["endpoints"].size(), 2u);
  for (const auto& e : (*found)["endpoints"]) {
    EXPECT_EQ(e["type"], "sensor_msgs/msg/Image");
    EXPECT_EQ(e["reliability"], "reliable");
    EXPECT_EQ(e["type_hash"],
              "RIHS01_d31d41a9a4c4bc8eae9be757b0beed306564f7526c88ea6a4588fb9582527d47");
    EXPECT_EQ(e["topic"], e["kind"] == "publisher" ? "/vga/image" : "/camera/image_raw");
  }
  const Outcome text = robotperf_cli(args);
  ASSERT_EQ(text.exit_code, 0) << text.out;
  EXPECT_NE(text.out.find("\n  /vga_echo   (participant "), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("  /vga/image  [sensor_msgs/msg/Image]  1 publisher, 0 subscriptions"),
            std::string::npos)
      << text.out;
}

TEST_F(ExternalGraph, NeedsADdsTransport) {
  const Outcome o = run_echo("until-signal", "intra");
  EXPECT_EQ(o.exit_code, 2) << o.out;
  EXPECT_NE(o.out.find("reached through DDS"), std::string::npos) << o.out;
}

}  // namespace
