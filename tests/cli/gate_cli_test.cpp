// The regression gate (compare --baseline/--candidate --fail-on-regression) on results files
// written by the real writer: a planted regression fails it, identical configurations pass it
// trial after trial, too few runs or an unknown side are bad input, an INVALID candidate fails
// it, and its JUnit XML and Markdown are written for CI.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include "../command_line.hpp"
#include "../report/sample_runs.hpp"

namespace {

namespace fs = std::filesystem;
using robotperf::report::testing::SampleRun;
using robotperf::report::testing::write_sample;
using robotperf::test_support::robotperf_cli;
using robotperf::test_support::shell;

std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

class Gate : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("robotperf-gate-" + std::to_string(getpid()));
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // `runs` runs of a1 labelled rev=`rev` in `folder`, their latencies `scale` times 5 ms with a
  // run-to-run spread of +-`noise` (a fraction), drawn from `random`.
  void write_runs(const fs::path& folder, const std::string& rev, int runs, double scale,
                  double noise, std::mt19937& random) {
    std::uniform_real_distribution<double> spread(-noise, noise);
    for (int i = 0; i < runs; ++i) {
      SampleRun s;
      s.base_latency_ms = 5.0 * scale * (1.0 + spread(random));
      s.labels = {{"rev", rev}};
      s.start_unix_ns += static_cast<int64_t>(next_++) * 1'000'000'000;
      write_sample(folder, s);
    }
  }
  fs::path dir_;
  int next_ = 0;
};

std::string gate_command(const fs::path& folder, double percent) {
  return "compare --baseline label.rev=main --candidate label.rev=pr --fail-on-regression " +
         std::to_string(percent) + " --results " + folder.string();
}

TEST_F(Gate, APlanted20PercentRegressionAcrossSixRepeatsFailsIt) {
  std::mt19937 random(7);
  write_runs(dir_ / "r", "main", 6, 1.0, 0.03, random);
  write_runs(dir_ / "r", "pr", 6, 1.2, 0.03, random);
  const auto o =
      robotperf_cli(gate_command(dir_ / "r", 10) + " --junit " + (dir_ / "gate.xml").string() +
                    " --markdown " + (dir_ / "gate.md").string());
  EXPECT_EQ(o.exit_code, 1) << o.out;
  EXPECT_NE(o.out.find("latency p50"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("REGRESSION (the medians' 95 % intervals do not overlap)"),
            std::string::npos)
      << o.out;
  EXPECT_NE(o.out.find("result: FAIL: 2 regressions beyond 10.0 %"), std::string::npos) << o.out;
  // The axis compared is not called a difference of configuration.
  EXPECT_EQ(o.out.find("differ in"), std::string::npos) << o.out;

  const std::string xml = read_text(dir_ / "gate.xml");
  EXPECT_NE(xml.find("failures=\"2\""), std::string::npos) << xml;
  EXPECT_NE(xml.find("<testcase classname=\"a1\" name=\"latency p50\"><failure message=\"latency "
                     "p50 +"),
            std::string::npos)
      << xml;
  const auto parsed = shell("python3 -c 'import sys, xml.dom.minidom as m; m.parse(sys.argv[1])' " +
                            (dir_ / "gate.xml").string());
  EXPECT_EQ(parsed.exit_code, 0) << "not well-formed XML: " << parsed.out;
  EXPECT_NE(read_text(dir_ / "gate.md").find("### robotperf gate: FAIL"), std::string::npos);

  // Within a threshold above the change, the same runs pass.
  EXPECT_EQ(robotperf_cli(gate_command(dir_ / "r", 30)).exit_code, 0);
}

// Two identical configurations over 20 trials of 6 runs a side: no false alarm. Under the null
// the disjoint-intervals rule fires on one figure with probability 2 / C(12, 6) = 0.2 %, and only
// a difference beyond the threshold counts (docs/guides/gate-ci.md).
TEST_F(Gate, IdenticalConfigurationsPassItTrialAfterTrial) {
  std::mt19937 random(11);
  int false_alarms = 0;
  for (int trial = 0; trial < 20; ++trial) {
    const fs::path folder = dir_ / ("t" + std::to_string(trial));
    write_runs(folder, "main", 6, 1.0, 0.05, random);
    write_runs(folder, "pr", 6, 1.0, 0.05, random);
    const auto o = robotperf_cli(gate_command(folder, 5));
    ASSERT_TRUE(o.exit_code == 0 || o.exit_code == 1) << o.out;
    false_alarms += o.exit_code == 1;
    EXPECT_NE(o.out.find("result: PASS"), std::string::npos) << o.out;
  }
  EXPECT_EQ(false_alarms, 0);
}

TEST_F(Gate, TooFewRunsOrAnUnknownSideIsBadInput) {
  std::mt19937 random(3);
  write_runs(dir_ / "r", "main", 2, 1.0, 0.03, random);
  write_runs(dir_ / "r", "pr", 2, 1.5, 0.03, random);
  auto o = robotperf_cli(gate_command(dir_ / "r", 10));
  EXPECT_EQ(o.exit_code, 2) << o.out;
  EXPECT_NE(o.out.find("the gate judged nothing: each side needs at least 3 valid runs"),
            std::string::npos)
      << o.out;
  o = robotperf_cli(
      "compare --baseline label.rev=nope --candidate label.rev=pr "
      "--fail-on-regression 10 --results " +
      (dir_ / "r").string());
  EXPECT_EQ(o.exit_code, 2) << o.out;
  EXPECT_NE(o.out.find("'label.rev=nope' matches no results file"), std::string::npos) << o.out;
}

TEST_F(Gate, AnInvalidCandidateRunFailsIt) {
  std::mt19937 random(5);
  write_runs(dir_ / "r", "main", 3, 1.0, 0.02, random);
  write_runs(dir_ / "r", "pr", 3, 1.0, 0.02, random);
  SampleRun lossy;
  lossy.lost = 4;
  lossy.labels = {{"rev", "pr"}};
  lossy.start_unix_ns += 100'000'000'000;
  write_sample(dir_ / "r", lossy);
  const auto o = robotperf_cli(gate_command(dir_ / "r", 10));
  EXPECT_EQ(o.exit_code, 1) << o.out;
  EXPECT_NE(o.out.find("1 of 4 candidate runs INVALID"), std::string::npos) << o.out;
}

}  // namespace
