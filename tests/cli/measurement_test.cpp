// How runs measure, end to end: runs that share a DDS domain, the values a run is given, arrival
// patterns, percentile intervals and the peak-throughput search.
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

using robotperf::test_support::Background;
using robotperf::test_support::Outcome;
using robotperf::test_support::robotperf_cli;

class Measurement : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("robotperf-isolation-" + std::to_string(getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    // i1: small stamped messages (TwistStamped) through a relay, so that 1 kHz is cheap.
    const fs::path package = dir_ / "benchmarks" / "test" / "i1_relay";
    fs::create_directories(package);
    std::ofstream(package / "benchmark.yaml")
        << "id: i1\nname: i1_relay\nshort: test\ndescription: test\nresults: []\n";
    std::ofstream(package / "graph.yaml")
        << "dataset: control/diffbot_cmd_vel\nrate_hz: 1000\nwarmup: 50\ndrain_s: 2.0\n"
           // Loss here measures the machine's load (each graph also serves the other run), not
           // the isolation these tests check: the bound is wide.
           "validity: {min_samples: 5, max_loss_percent: 50.0}\n"
           "inputs:\n  - {topic: /i1/in, type: geometry_msgs/msg/TwistStamped, stream: cmd_vel}\n"
           "output: {topic: /i1/out, type: geometry_msgs/msg/TwistStamped}\n"
           "nodes:\n  - name: relay\n    kernel: util/relay\n"
           "    parameters: {type: geometry_msgs/msg/TwistStamped, delay_ms: "
        << relay_delay_ms()
        << "}\n"
           "    topics: {input: /i1/in, output: /i1/out}\n";
  }
  void TearDown() override { fs::remove_all(dir_); }

  // The relay's service time: 4 ms (a limit near 250 Hz) for the peak search, else none.
  std::string relay_delay_ms() const {
    const std::string name = ::testing::UnitTest::GetInstance()->current_test_info()->name();
    return name.starts_with("FindPeak") ? "4" : "0";
  }

  std::string benchmarks() const { return "--benchmarks " + (dir_ / "benchmarks").string(); }

  nlohmann::json result_in(const fs::path& folder) {
    for (const auto& e : fs::directory_iterator(folder)) {
      if (e.path().extension() == ".json") {
        std::ifstream in(e.path());
        return nlohmann::json::parse(in);
      }
    }
    ADD_FAILURE() << "no result in " << folder;
    return {};
  }

  fs::path dir_;
};

bool has_warning(const nlohmann::json& j, const std::string& rule) {
  for (const auto& w : j["warnings"])
    if (w["rule"] == rule) return true;
  return false;
}

// Two runs of the same graph on the same domain at 1 kHz, at the same time: each graph also
// receives the other's inputs, and each Monitor the other graph's outputs. Neither run may count
// what the other sent (no duplicates, no unknown IDs, no matches borrowed), and both say that
// another run was there.
TEST_F(Measurement, TwoRunsOnOneDomainKeepTheirOwnCounts) {
  // Shared by the two runs on purpose, and by nothing else.
  const std::string domain = std::to_string(robotperf::rmw::find_quiet_domain("fastdds"));
  const std::string run = std::string(ROBOTPERF_EXECUTABLE) + " " + benchmarks() +
                          " run i1 --count 5000 --rmw fastdds --quiet --domain " + domain;
  Background a(run + " --output " + (dir_ / "a").string(), dir_ / "a.log");
  Background b(run + " --output " + (dir_ / "b").string(), dir_ / "b.log");
  ASSERT_EQ(a.wait(std::chrono::seconds(120)), 0) << a.output();
  ASSERT_EQ(b.wait(std::chrono::seconds(120)), 0) << b.output();
  std::size_t foreign = 0;
  for (const auto& folder : {dir_ / "a", dir_ / "b"}) {
    const nlohmann::json j = result_in(folder);
    const auto& c = j["counts"];
    EXPECT_EQ(c["sent"], 5000);
    EXPECT_EQ(c["duplicates"], 0) << folder;
    EXPECT_EQ(c["unknown"], 0) << folder;
    EXPECT_LE(c["matched"].get<int>(), c["measured"].get<int>());
    EXPECT_TRUE(j["validity"]["valid"].get<bool>()) << j["validity"].dump();
    foreign += c["foreign"].get<std::size_t>();
    EXPECT_FALSE(j["configuration"]["run_token"].get<std::string>().empty());
    // Each saw the other, before or during its run.
    EXPECT_FALSE(j["domain_peers"].empty()) << folder;
    EXPECT_TRUE(has_warning(j, "other_participants") || has_warning(j, "foreign_traffic"))
        << j["warnings"].dump();
  }
  EXPECT_NE(result_in(dir_ / "a")["configuration"]["run_token"],
            result_in(dir_ / "b")["configuration"]["run_token"]);
  // The runs overlapped by seconds at 1 kHz: their outputs crossed.
  EXPECT_GT(foreign, 0u);
}

TEST_F(Measurement, DomainAutoPicksADomainNobodyUses) {
  const Outcome o =
      robotperf_cli(benchmarks() + " run i1 --count 200 --rmw fastdds --domain auto --output " +
                    (dir_ / "out").string());
  ASSERT_EQ(o.exit_code, 0) << o.out;
  EXPECT_NE(o.out.find("--domain auto: domain "), std::string::npos) << o.out;
  const nlohmann::json j = result_in(dir_ / "out");
  const int domain = j["configuration"]["domain_id"];
  EXPECT_GE(domain, 1);
  EXPECT_LE(domain, 232);
  EXPECT_TRUE(j["domain_peers"].empty()) << j["domain_peers"].dump();
  EXPECT_FALSE(has_warning(j, "other_participants"));
}

// Values that used to crash, overflow or wrap: one line naming the option, exit 2, nothing run.
TEST_F(Measurement, BadRunValuesAreOneLineAndExitTwo) {
  for (const char* args :
       {"--rate 3e9", "--rate 1e-300", "--rate nan", "--drain 1e10", "--count -1", "--count 0",
        "--warmup -2", "--duration inf", "--duration -3", "--arrival burst:0", "--arrival zipf",
        "--domain 300", "--domain any"}) {
    const Outcome o = robotperf_cli(benchmarks() + " run i1 --quiet " + args + " --output " +
                                    (dir_ / "bad").string());
    EXPECT_EQ(o.exit_code, 2) << args << ": " << o.out;
    const std::string option = std::string(args).substr(0, std::string(args).find(' '));
    EXPECT_NE(o.out.find(option), std::string::npos) << args << ": " << o.out;
    EXPECT_EQ(std::count(o.out.begin(), o.out.end(), '\n'), 1) << args << ": " << o.out;
    EXPECT_FALSE(fs::exists(dir_ / "bad") && !fs::is_empty(dir_ / "bad")) << args;
  }
}

TEST_F(Measurement, PoissonArrivalsAreRecordedWithTheirSeed) {
  const Outcome o = robotperf_cli(benchmarks() +
                                  " run i1 --rmw intra --rate 200 --count 400 --arrival poisson "
                                  "--arrival-seed 9 --output " +
                                  (dir_ / "out").string());
  ASSERT_EQ(o.exit_code, 0) << o.out;
  EXPECT_NE(o.out.find("Poisson arrivals, seed 9"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("95 % intervals (from scheduled send, ms): p50 "), std::string::npos)
      << o.out;
  const nlohmann::json j = result_in(dir_ / "out");
  EXPECT_EQ(j["configuration"]["timeline"], "poisson");
  EXPECT_EQ(j["configuration"]["arrival_seed"], 9);
  EXPECT_EQ(j["counts"]["matched"], 350);
  EXPECT_TRUE(j["latency_ms"]["from_scheduled"]["p50_ci95"].is_array());
}

// A spinning Monitor is a configuration of its own: recorded, said in the summary, and never
// pooled or compared with runs whose Monitor slept unless asked for by field.
TEST_F(Measurement, ASpinningMonitorIsRecordedAndSelectable) {
  for (const char* wait : {"sleep", "spin"}) {
    const Outcome o =
        robotperf_cli(benchmarks() + " run i1 --rmw intra --rate 200 --count 120 " +
                      "--monitor-wait " + wait + " --output " + (dir_ / wait).string());
    ASSERT_EQ(o.exit_code, 0) << o.out;
    EXPECT_EQ(o.out.find("Monitor spinning") != std::string::npos, std::string(wait) == "spin")
        << o.out;
    const nlohmann::json j = result_in(dir_ / wait);
    EXPECT_EQ(j["configuration"]["monitor_wait"], wait);
    EXPECT_EQ(j["counts"]["matched"], 70);  // i1 warms up with 50
  }
  const Outcome list = robotperf_cli("results list " + (dir_ / "spin").string() + " --format json");
  ASSERT_EQ(list.exit_code, 0) << list.out;
  EXPECT_NE(list.out.find("\"monitor\": \"spin\""), std::string::npos) << list.out;
  const Outcome bad = robotperf_cli(benchmarks() + " run i1 --monitor-wait busy --output " +
                                    (dir_ / "bad").string());
  EXPECT_EQ(bad.exit_code, 2) << bad.out;
  EXPECT_NE(bad.out.find("--monitor-wait"), std::string::npos) << bad.out;
  // Spinning on the only CPU the run may use would starve the graph: refused in one line.
  const Outcome one_cpu = robotperf_cli(benchmarks() + " run i1 --monitor-wait spin --cpus 0 " +
                                        "--output " + (dir_ / "bad").string());
  EXPECT_EQ(one_cpu.exit_code, 2) << one_cpu.out;
  EXPECT_NE(one_cpu.out.find("--monitor-wait spin keeps a CPU busy"), std::string::npos)
      << one_cpu.out;
  EXPECT_EQ(std::count(one_cpu.out.begin(), one_cpu.out.end(), '\n'), 1) << one_cpu.out;
  EXPECT_FALSE(fs::exists(dir_ / "bad") && !fs::is_empty(dir_ / "bad"));
}

TEST_F(Measurement, RepeatWritesEveryRunAndTheSeries) {
  const fs::path out = dir_ / "out";
  const Outcome o = robotperf_cli(benchmarks() + " run i1 --rmw intra --rate 200 --count 120 " +
                                  "--repeat 3 --repeat-pause 0.1 --quiet --output " + out.string());
  ASSERT_EQ(o.exit_code, 0) << o.out;
  EXPECT_NE(o.out.find("series i1: 3 runs, 3 valid"), std::string::npos) << o.out;
  std::size_t results = 0;
  fs::path series_file;
  for (const auto& e : fs::directory_iterator(out)) {
    const std::string name = e.path().filename().string();
    if (name.ends_with(".series.json")) {
      series_file = e.path();
    } else if (name.ends_with(".json")) {
      ++results;
    }
  }
  EXPECT_EQ(results, 3u);
  ASSERT_FALSE(series_file.empty());
  std::ifstream in(series_file);
  const nlohmann::json s = nlohmann::json::parse(in);
  EXPECT_EQ(s["schema"], "robotperf.series/1");
  EXPECT_EQ(s["files"].size(), 3u);
  const auto& p50 = s["figures"]["latency p50"];
  EXPECT_EQ(p50["values"].size(), 3u);
  EXPECT_LE(p50["min"].get<double>(), p50["median"].get<double>());
  // Three runs cannot bound a median with 95 % confidence: the interval says so.
  EXPECT_TRUE(p50["median_ci95"][0].is_null());
  // The series file is not a run: listing the folder skips it quietly.
  const Outcome list = robotperf_cli("results list " + out.string());
  EXPECT_EQ(list.exit_code, 0) << list.out;
  EXPECT_EQ(list.out.find("skipped"), std::string::npos) << list.out;
}

TEST_F(Measurement, FindPeakReportsTheSustainedRateAndEveryStep) {
  const Outcome o = robotperf_cli(benchmarks() +
                                  " run i1 --find-peak --rate-range 100:1000 --duration 1 "
                                  "--peak-resolution 10 --loss-bound 0 --rmw intra --output " +
                                  (dir_ / "out").string());
  ASSERT_EQ(o.exit_code, 0) << o.out;
  EXPECT_NE(o.out.find("peak search: loss <= 0 %"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("sustained"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("(peak: the highest rate"), std::string::npos) << o.out;
  const nlohmann::json j = result_in(dir_ / "out");
  EXPECT_EQ(j["throughput"]["kind"], "peak");
  const auto& steps = j["peak_search"]["steps"];
  ASSERT_GE(steps.size(), 3u);
  EXPECT_EQ(steps[0]["rate_hz"], 100.0);
  // 1 / 4 ms, less the relay's own overhead.
  const double rate = j["configuration"]["rate_hz"];
  EXPECT_GE(rate, 100.0);
  EXPECT_LT(rate, 260.0);
  EXPECT_FALSE(j["peak_search"]["stop_reason"].get<std::string>().empty());
  // --find-peak sizes its steps itself.
  EXPECT_EQ(robotperf_cli(benchmarks() + " run i1 --find-peak --count 10").exit_code, 2);
  EXPECT_EQ(robotperf_cli(benchmarks() + " run i1 --loss-bound 3").exit_code, 2);
}

}  // namespace
