// Faults a run must survive and say how it ended: a node whose callback hangs, Ctrl-C, SIGTERM, a
// plug-in kernel that throws or crashes, a node process (a DDS peer) that vanishes, a full disk.
// Each keeps the partial result, leaves no process behind and exits with its own status.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "../command_line.hpp"
#include "robotperf/rmw/transport.hpp"

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

  // A benchmark folder with f1: the camera stream through a relay with `relay_parameters`; the
  // relay is `kernel`, util/relay unless a test names the faulty plug-in's.
  std::string benchmarks(const std::string& relay_parameters,
                         const std::string& kernel = "util/relay") {
    const fs::path package = dir_ / "benchmarks" / "test" / "f1_relay";
    fs::create_directories(package);
    std::ofstream(package / "benchmark.yaml")
        << "id: f1\nname: f1_relay\nshort: test\ndescription: test\nresults: []\n";
    std::ofstream(package / "graph.yaml")
        << "dataset: perception/image\nrate_hz: 20\nwarmup: 0\n"
           "validity: {min_samples: 5, max_loss_percent: 0.0}\n"
           "inputs:\n  - {topic: /in, type: sensor_msgs/msg/Image, stream: image}\n"
           "output: {topic: /out, type: sensor_msgs/msg/Image}\n"
           "nodes:\n  - name: relay\n    kernel: "
        << kernel << "\n    parameters: {" << relay_parameters
        << "}\n    topics: {input: /in, output: /out}\n";
    return "--benchmarks " + (dir_ / "benchmarks").string() +
           (kernel == "util/relay" ? "" : " --plugin " FAULTY_PLUGIN);
  }
  std::string domain() const { return std::to_string(robotperf::rmw::reserved_domain()); }

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

  // Starts `run f1 <args>` of benchmarks(`relay`) in the background, to --output results/, with
  // a power meter that counts its readings in `readings`. The meter is read once before the run
  // and then during the measured window: true once its second reading says timing has begun.
  bool start_measuring(std::optional<Background>& run, const std::string& relay,
                       const std::string& args, const fs::path& readings) {
    run.emplace(std::string(ROBOTPERF_EXECUTABLE) + " " + benchmarks(relay) + " run f1 " + args +
                    " --quiet --power-meter 'echo x >> " + readings.string() + "; echo 5'" +
                    " --domain " + domain() + " --output " + (dir_ / "results").string(),
                dir_ / "log");
    return eventually([&] { return readings_of(readings) >= 2; }, std::chrono::seconds(60));
  }

  // The pgrep/pkill pattern of this test's node processes (the brackets keep pgrep's own shell
  // out of the match; options such as --plugin may stand before `node`).
  std::string node_pattern() const { return "'[r]obotperf.* node " + dir_.string() + "'"; }
  // Whether a node process of this test's package still runs.
  bool children_left() const {
    return robotperf::test_support::shell("pgrep -f " + node_pattern()).exit_code == 0;
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

// Whether process `pid` has a handler of its own for `signal_number` (/proc's SigCgt mask).
bool catches(pid_t pid, int signal_number) {
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(status, line);) {
    if (line.starts_with("SigCgt:"))
      return (std::stoull(line.substr(7), nullptr, 16) >> (signal_number - 1) & 1) != 0;
  }
  return false;
}

// SIGHUP (a dropped ssh session) and SIGQUIT (Ctrl-\) end a run as SIGINT and SIGTERM do.
TEST_F(Faults, InterruptsEndTheRunKeepingWhatItMeasured) {
  for (const int signal_number : {SIGINT, SIGTERM, SIGHUP, SIGQUIT}) {
    fs::remove_all(dir_ / "results");
    std::optional<Background> started;
    ASSERT_TRUE(start_measuring(started, "", "--count 2000",
                                dir_ / ("readings-" + std::to_string(signal_number))))
        << started->output();
    Background& run = *started;
    run.signal(signal_number);
    EXPECT_EQ(run.wait(std::chrono::seconds(30)), 128 + signal_number) << run.output();
    EXPECT_NE(run.output().find("interrupted: ending the run"), std::string::npos) << run.output();
    const auto j = result();
    ASSERT_TRUE(j.is_object()) << "no result written: " << run.output();
    EXPECT_EQ(j["interrupted"], true);
    EXPECT_EQ(j["completed"], false);
    EXPECT_GT(j["counts"]["sent"].get<int>(), 0);
    EXPECT_LT(j["counts"]["sent"].get<int>(), 2000);
    EXPECT_EQ(j["errors"][0], std::string("interrupted by SIG") + sigabbrev_np(signal_number));
  }
}

// The handlers are in place before the run makes anything (here: the domain --domain auto
// reserves while it listens for other participants, 3.5 s): a SIGTERM then ends it cleanly
// with no result, not by default handling.
TEST_F(Faults, ASignalBeforeTheRunStartsEndsItCleanly) {
  Background run(std::string(ROBOTPERF_EXECUTABLE) + " " + benchmarks("") +
                     " run f1 --count 20 --rmw fastdds --domain auto --output " +
                     (dir_ / "results").string(),
                 dir_ / "log");
  ASSERT_TRUE(eventually([&] { return catches(run.pid(), SIGTERM); }, std::chrono::seconds(30)))
      << run.output();
  EXPECT_EQ(run.output().find("--domain auto: domain"), std::string::npos)
      << "the handlers came only after the domain was chosen: " << run.output();
  run.signal(SIGTERM);
  EXPECT_EQ(run.wait(std::chrono::seconds(60)), 128 + SIGTERM) << run.output();
  EXPECT_NE(run.output().find("interrupted by SIGTERM"), std::string::npos) << run.output();
  EXPECT_FALSE(fs::exists(dir_ / "results") && !fs::is_empty(dir_ / "results"));
}

// An interrupted --repeat keeps the runs it made, and its series file says it ended early.
TEST_F(Faults, AnInterruptedSeriesSaysItEndedEarly) {
  std::optional<Background> started;
  ASSERT_TRUE(start_measuring(started, "", "--repeat 3 --count 2000", dir_ / "readings"))
      << started->output();
  Background& run = *started;
  run.signal(SIGINT);
  EXPECT_EQ(run.wait(std::chrono::seconds(30)), 130) << run.output();
  EXPECT_NE(run.output().find("ended early after 1 of 3 runs: interrupted by SIGINT"),
            std::string::npos)
      << run.output();
  nlohmann::json series;
  for (const auto& e : fs::directory_iterator(dir_ / "results")) {
    if (e.path().string().ends_with(".series.json"))
      series = nlohmann::json::parse(std::ifstream(e.path()));
  }
  ASSERT_TRUE(series.is_object()) << run.output();
  EXPECT_EQ(series["runs"], 1);
  EXPECT_EQ(series["planned_runs"], 3);
  EXPECT_EQ(series["complete"], false);
  EXPECT_EQ(series["ended_early"], "interrupted by SIGINT");
}

TEST_F(Faults, ASecondInterruptForcesAndStopsTheNodeProcesses) {
  // Per node, a child whose callback will not return for ten minutes: after the first Ctrl-C the
  // runner waits its shutdown grace for it; the second ends everything at once.
  std::optional<Background> started;
  ASSERT_TRUE(start_measuring(started, "delay_ms: 600000",
                              "--count 2000 --rmw fastdds --processes per-node "
                              "--callback-timeout 1000",
                              dir_ / "readings"))
      << started->output();
  Background& run = *started;
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

TEST_F(Faults, APluginKernelThatThrowsEndsTheRunNamingIt) {
  for (const std::string layout : {"single", "per-node"}) {
    fs::remove_all(dir_ / "results");
    const auto o = robotperf_cli(
        benchmarks("throw_after: 10", "faulty_plugin/relay") + " run f1 --count 40 --quiet --rmw " +
        (layout == "single" ? "intra" : "fastdds --processes per-node") + " --domain " + domain() +
        " --output " + (dir_ / "results").string());
    EXPECT_EQ(o.exit_code, 3) << layout << ": " << o.out;
    const auto j = result();
    ASSERT_TRUE(j.is_object()) << layout << ": no result written: " << o.out;
    EXPECT_EQ(j["completed"], false) << layout;
    EXPECT_EQ(j["validity"]["valid"], false) << layout;
    EXPECT_GE(j["counts"]["matched"].get<int>(), 1) << layout << ": what it measured is kept";
    EXPECT_NE(j["errors"].dump().find("node 'relay'"), std::string::npos) << j["errors"].dump();
    EXPECT_NE(j["errors"].dump().find("device lost after 10 frames"), std::string::npos)
        << layout << j["errors"].dump();
    EXPECT_NE(j["nodes"][0]["exit_status"].get<std::string>(), "ok") << layout;
    EXPECT_FALSE(children_left()) << layout;
  }
}

// A kernel whose accelerated backend answers differently from its cpu backend: the run compares
// a sample of its answers with the cpu's to the same inputs and is functionally invalid, though
// the benchmark has no ground truth; the same kernel without drift passes the check.
TEST_F(Faults, ABackendThatDriftsFromTheCpuIsFunctionallyInvalid) {
  for (const std::string drift : {"0", "3"}) {
    fs::remove_all(dir_ / "results");
    const auto o = robotperf_cli(benchmarks("drift: " + drift, "faulty_plugin/relay") +
                                 " run f1 --count 30 --backend opencl --output " +
                                 (dir_ / "results").string());
    const auto j = result();
    ASSERT_TRUE(j.is_object()) << o.out;
    const auto& check = j["backend_check"];
    ASSERT_TRUE(check.is_object()) << j.dump();
    EXPECT_EQ(check["backend"], "opencl");
    EXPECT_EQ(check["compared"], 16);
    if (drift == "0") {
      EXPECT_EQ(o.exit_code, 0) << o.out;
      EXPECT_EQ(check["passed"], true);
      EXPECT_EQ(check["agreement"], 1.0);
      EXPECT_NE(o.out.find("backend check (opencl against cpu on the same inputs, 16 outputs)"),
                std::string::npos)
          << o.out;
    } else {
      EXPECT_EQ(o.exit_code, 3) << o.out;
      EXPECT_EQ(check["passed"], false);
      EXPECT_EQ(check["agreement"], 0.0);
      EXPECT_EQ(j["functional"]["valid"], false);
      EXPECT_NE(o.out.find("functional result: INVALID — opencl drifts from cpu"),
                std::string::npos)
          << o.out;
    }
  }
}

TEST_F(Faults, APluginKernelThatRefusesToStartIsOneLine) {
  for (const std::string layout : {"single", "per-node"}) {
    fs::remove_all(dir_ / "results");
    const auto o = robotperf_cli(
        benchmarks("refuse: true", "faulty_plugin/relay") + " run f1 --count 40 --quiet --rmw " +
        (layout == "single" ? "intra" : "fastdds --processes per-node") + " --domain " + domain() +
        " --output " + (dir_ / "results").string());
    EXPECT_EQ(o.exit_code, 1) << layout;
    EXPECT_NE(o.out.find("node 'relay': kernel faulty_plugin/relay"), std::string::npos)
        << layout << ": " << o.out;
    EXPECT_NE(o.out.find("the accelerator this kernel needs is not present"), std::string::npos)
        << layout << ": " << o.out;
    EXPECT_EQ(o.out.find("terminate called"), std::string::npos) << o.out;
    EXPECT_FALSE(children_left()) << layout;
  }
}

// The relay is the Playback's and the Monitor's DDS peer: its process crashes (abort) or is
// killed from outside mid-run. The run ends naming it, keeps what it measured, and counts the
// frames the dead node took with it as lost.
TEST_F(Faults, ANodeProcessThatVanishesMidRunIsNamed) {
  for (const std::string how : {"crash", "kill"}) {
    fs::remove_all(dir_ / "results");
    const fs::path readings = dir_ / ("readings-" + how);
    Background run(std::string(ROBOTPERF_EXECUTABLE) + " " +
                       benchmarks(how == "crash" ? "abort_after: 10" : "", "faulty_plugin/relay") +
                       " run f1 --count 200 --rmw fastdds --processes per-node --quiet "
                       "--power-meter 'echo x >> " +
                       readings.string() + "; echo 5' --domain " + domain() + " --output " +
                       (dir_ / "results").string(),
                   dir_ / ("log-" + how));
    if (how == "kill") {
      ASSERT_TRUE(eventually([&] { return readings_of(readings) >= 3; }, std::chrono::seconds(60)))
          << run.output();
      ASSERT_EQ(robotperf::test_support::shell("pkill -KILL -f " + node_pattern()).exit_code, 0);
    }
    EXPECT_EQ(run.wait(std::chrono::seconds(60)), 3) << how << ": " << run.output();
    const auto j = result();
    ASSERT_TRUE(j.is_object()) << how << ": no result written: " << run.output();
    EXPECT_EQ(j["validity"]["valid"], false) << how;
    EXPECT_GT(j["counts"]["lost"].get<int>(), 0) << how << ": " << j["counts"].dump();
    const std::string status = j["nodes"][0]["exit_status"];
    EXPECT_NE(status.find("killed by signal"), std::string::npos) << how << ": " << status;
    EXPECT_FALSE(children_left()) << how;
  }
}

// --output on a full file system (a small tmpfs, mounted in a user and mount namespace of the
// test's own): the summary is printed, the results go to a folder under TMPDIR that stderr names,
// exit 1, and the files already in the output folder are untouched, with no temporary file left.
TEST_F(Faults, AFullDiskKeepsTheResultElsewhere) {
  if (robotperf::test_support::shell("unshare --user --map-root-user --mount true").exit_code !=
      0) {
    GTEST_SKIP() << "no user namespaces here: cannot mount a small tmpfs";
  }
  const fs::path full = dir_ / "full";
  fs::create_directories(full);
  const std::string script =
      "mount -t tmpfs -o size=64k tmpfs " + full.string() + " && echo previous > " + full.string() +
      "/earlier.json && head -c 57344 /dev/zero > " + full.string() +
      "/filler && TMPDIR=" + dir_.string() + " " + ROBOTPERF_EXECUTABLE + " " + benchmarks("") +
      " run f1 --count 30 --quiet --csv --output " + full.string() + "; echo exit=\\$?; cat " +
      full.string() + "/earlier.json; ls -A " + full.string();
  const auto o = robotperf::test_support::shell("unshare --user --map-root-user --mount sh -c \"" +
                                                script + "\"");
  EXPECT_NE(o.out.find("exit=1"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("No space left on device"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("result:"), std::string::npos) << "no summary: " << o.out;
  EXPECT_NE(o.out.find("previous\nearlier.json\nfiller\n"), std::string::npos)
      << "the full folder changed: " << o.out;
  // The result kept elsewhere is whole.
  std::vector<fs::path> kept;
  for (const auto& e : fs::recursive_directory_iterator(dir_)) {
    if (e.path().string().find("robotperf-unsaved-") != std::string::npos) kept.push_back(e.path());
  }
  std::sort(kept.begin(), kept.end());
  ASSERT_EQ(kept.size(), 3u) << "expected the folder, the .json and the .latencies.csv";
  std::ifstream in(kept[1]);
  const auto j = nlohmann::json::parse(in);
  EXPECT_EQ(j["counts"]["sent"], 30);
  EXPECT_NE(o.out.find(kept[0].string()), std::string::npos) << "stderr names where: " << o.out;
}

}  // namespace
