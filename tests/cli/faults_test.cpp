// Faults a run must survive and say how it ended: a node whose callback hangs, Ctrl-C, SIGTERM.
// Each keeps the partial result, leaves no process behind and exits with its own status.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "../command_line.hpp"

namespace {

namespace fs = std::filesystem;
using robotperf::test_support::Background;
using robotperf::test_support::eventually;
using robotperf::test_support::robotperf_cli;

class Faults : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("robotperf-faults-" + std::to_string(getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // A benchmark folder with f1: the camera stream through a relay with `relay_parameters`.
  std::string benchmarks(const std::string& relay_parameters) {
    const fs::path package = dir_ / "benchmarks" / "test" / "f1_relay";
    fs::create_directories(package);
    std::ofstream(package / "benchmark.yaml")
        << "id: f1\nname: f1_relay\nshort: test\ndescription: test\nresults: []\n";
    std::ofstream(package / "graph.yaml")
        << "dataset: perception/image\nrate_hz: 20\nwarmup: 0\n"
           "validity: {min_samples: 5, max_loss_percent: 0.0}\n"
           "inputs:\n  - {topic: /in, type: sensor_msgs/msg/Image, stream: image}\n"
           "output: {topic: /out, type: sensor_msgs/msg/Image}\n"
           "nodes:\n  - name: relay\n    kernel: util/relay\n    parameters: {"
        << relay_parameters << "}\n    topics: {input: /in, output: /out}\n";
    return "--benchmarks " + (dir_ / "benchmarks").string();
  }
  std::string domain() const { return std::to_string(10 + getpid() % 20); }

  nlohmann::json result() {
    for (const auto& e : fs::directory_iterator(dir_ / "results")) {
      if (e.path().extension() == ".json") {
        std::ifstream in(e.path());
        return nlohmann::json::parse(in);
      }
    }
    return {};
  }
  // How often the power meter of a run was read: once before the run, then in its window.
  static int readings_of(const fs::path& file) {
    std::ifstream in(file);
    std::string line;
    int n = 0;
    while (std::getline(in, line)) ++n;
    return n;
  }

  // Whether a node process of this test's package still runs (the brackets keep pgrep's own
  // shell out of the match).
  bool children_left() const {
    return robotperf::test_support::shell("pgrep -f '[r]obotperf node " + dir_.string() + "'")
               .exit_code == 0;
  }

  fs::path dir_;
};

TEST_F(Faults, AHungCallbackEndsTheRunNamingTheNode) {
  for (const std::string layout : {"single", "per-node"}) {
    fs::remove_all(dir_ / "results");
    const auto start = std::chrono::steady_clock::now();
    const auto o = robotperf_cli(
        benchmarks("delay_ms: 600000") + " run f1 --count 40 --callback-timeout 1 --quiet --rmw " +
        (layout == "single" ? "intra" : "fastdds --processes per-node") + " --domain " + domain() +
        " --output " + (dir_ / "results").string());
    const auto took = std::chrono::steady_clock::now() - start;
    EXPECT_EQ(o.exit_code, 3) << layout << ": " << o.out;
    // Bounded although the callback never returns (it would for ten minutes).
    EXPECT_LT(took, std::chrono::seconds(60)) << layout;
    EXPECT_NE(o.out.find("node 'relay'"), std::string::npos) << o.out;
    EXPECT_NE(o.out.find("hung: its callback has run for"), std::string::npos) << o.out;
    const auto j = result();
    ASSERT_TRUE(j.is_object()) << layout << ": no result written";
    EXPECT_EQ(j["completed"], false);
    EXPECT_EQ(j["validity"]["valid"], false);
    EXPECT_LT(j["counts"]["sent"].get<int>(), 40);
    EXPECT_NE(j["nodes"][0]["exit_status"].get<std::string>().find("hung"), std::string::npos)
        << j["nodes"].dump();
    EXPECT_FALSE(children_left()) << layout;
  }
}

TEST_F(Faults, InterruptsEndTheRunKeepingWhatItMeasured) {
  for (const int signal_number : {SIGINT, SIGTERM}) {
    fs::remove_all(dir_ / "results");
    // The meter is read once before the run and then during the measured window: its second
    // reading says the run is under way.
    const fs::path readings = dir_ / ("readings-" + std::to_string(signal_number));
    const std::string meter = "--power-meter 'echo x >> " + readings.string() + "; echo 5'";
    Background run(std::string(ROBOTPERF_EXECUTABLE) + " " + benchmarks("") +
                       " run f1 --count 2000 --quiet " + meter + " --domain " + domain() +
                       " --output " + (dir_ / "results").string(),
                   dir_ / "log");
    ASSERT_TRUE(eventually([&] { return readings_of(readings) >= 2; }, std::chrono::seconds(60)))
        << run.output();
    run.signal(signal_number);
    EXPECT_EQ(run.wait(std::chrono::seconds(30)), 128 + signal_number) << run.output();
    EXPECT_NE(run.output().find("interrupted: ending the run"), std::string::npos) << run.output();
    const auto j = result();
    ASSERT_TRUE(j.is_object()) << "no result written: " << run.output();
    EXPECT_EQ(j["interrupted"], true);
    EXPECT_EQ(j["completed"], false);
    EXPECT_GT(j["counts"]["sent"].get<int>(), 0);
    EXPECT_LT(j["counts"]["sent"].get<int>(), 2000);
    EXPECT_EQ(j["errors"][0],
              signal_number == SIGINT ? "interrupted by SIGINT" : "interrupted by SIGTERM");
  }
}

TEST_F(Faults, ASecondInterruptForcesAndStopsTheNodeProcesses) {
  // Per node, a child whose callback will not return for ten minutes: after the first Ctrl-C the
  // runner waits its shutdown grace for it; the second ends everything at once.
  const fs::path readings = dir_ / "readings";
  Background run(std::string(ROBOTPERF_EXECUTABLE) + " " + benchmarks("delay_ms: 600000") +
                     " run f1 --count 2000 --rmw fastdds --processes per-node --callback-timeout "
                     "1000 --quiet --power-meter 'echo x >> " +
                     readings.string() + "; echo 5' --domain " + domain() + " --output " +
                     (dir_ / "results").string(),
                 dir_ / "log");
  ASSERT_TRUE(eventually([&] { return readings_of(readings) >= 2; }, std::chrono::seconds(60)))
      << run.output();
  run.signal(SIGINT);
  ASSERT_TRUE(
      eventually([&] { return run.output().find("interrupted: ending") != std::string::npos; },
                 std::chrono::seconds(30)))
      << run.output();
  run.signal(SIGINT);
  EXPECT_EQ(run.wait(std::chrono::seconds(30)), 130) << run.output();
  EXPECT_NE(run.output().find("interrupted again: stopping now"), std::string::npos)
      << run.output();
  EXPECT_TRUE(eventually([&] { return !children_left(); }, std::chrono::seconds(10)));
}

}  // namespace
