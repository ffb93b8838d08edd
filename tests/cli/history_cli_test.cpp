// `robotperf history` on results files written by the real writer: a planted step is marked where
// it is, in its direction; a steady history has none; --by pools a revision's runs into one point;
// configurations are kept apart; bad input is one line.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <random>
#include <string>

#include "../command_line.hpp"
#include "../report/sample_runs.hpp"

namespace {

namespace fs = std::filesystem;
using robotperf::report::testing::SampleRun;
using robotperf::report::testing::write_sample;
using robotperf::test_support::robotperf_cli;

class History : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("robotperf-history-" + std::to_string(getpid()));
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // `runs` runs of a1, one a second, their latencies about `level` ms with a spread of +-2 %.
  void write_runs(int runs, double level, const std::string& rev,
                  const std::string& rmw = "intra") {
    std::uniform_real_distribution<double> spread(-0.02, 0.02);
    for (int i = 0; i < runs; ++i) {
      SampleRun s;
      s.rmw = rmw;
      s.base_latency_ms = level * (1.0 + spread(random_));
      s.labels = {{"rev", rev}};
      s.start_unix_ns += (next_++) * 1'000'000'000LL;
      write_sample(dir_, s);
    }
  }
  std::string history(const std::string& arguments) {
    return "history a1 --results " + dir_.string() + " " + arguments;
  }
  fs::path dir_;
  std::mt19937 random_{5};
  long long next_ = 0;
};

TEST_F(History, MarksAPlantedStepWhereItIsAndWhichWay) {
  for (int rev = 0; rev < 10; ++rev) write_runs(1, 5.0, "r" + std::to_string(rev));
  for (int rev = 10; rev < 18; ++rev) write_runs(1, 6.0, "r" + std::to_string(rev));
  const auto o = robotperf_cli(history("--format json"));
  ASSERT_EQ(o.exit_code, 0) << o.out;
  const auto j = nlohmann::json::parse(o.out);
  ASSERT_EQ(j["series"].size(), 1u) << o.out;
  const auto& series = j["series"][0];
  EXPECT_EQ(series["points"].size(), 18u);
  ASSERT_EQ(series["changes"].size(), 1u) << o.out;
  EXPECT_EQ(series["changes"][0]["index"], 10);
  EXPECT_GT(series["changes"][0]["change_percent"].get<double>(), 10);
  EXPECT_EQ(j["better"], "smaller");

  const auto text = robotperf_cli(history(""));
  ASSERT_EQ(text.exit_code, 0) << text.out;
  EXPECT_NE(text.out.find("<- change: "), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("worse (p = "), std::string::npos) << text.out;
}

TEST_F(History, ASteadyHistoryHasNoChangePoint) {
  for (int rev = 0; rev < 16; ++rev) write_runs(1, 5.0, "r" + std::to_string(rev));
  const auto o = robotperf_cli(history(""));
  ASSERT_EQ(o.exit_code, 0) << o.out;
  EXPECT_NE(o.out.find("no change point"), std::string::npos) << o.out;
  EXPECT_EQ(o.out.find("<- change"), std::string::npos) << o.out;
}

TEST_F(History, ByALabelPoolsEachValuesRunsIntoOnePoint) {
  for (int rev = 0; rev < 4; ++rev) write_runs(3, 5.0, "v" + std::to_string(rev));
  const auto o = robotperf_cli(history("--by rev --format json"));
  ASSERT_EQ(o.exit_code, 0) << o.out;
  const auto j = nlohmann::json::parse(o.out);
  ASSERT_EQ(j["series"].size(), 1u) << o.out;
  const auto& points = j["series"][0]["points"];
  ASSERT_EQ(points.size(), 4u) << o.out;
  EXPECT_EQ(points[0]["revision"], "v0");
  EXPECT_EQ(points[3]["revision"], "v3");
  EXPECT_EQ(points[1]["runs"], 3);
  // A pooled point's interval is its runs' range, around their median.
  EXPECT_LE(points[1]["low"].get<double>(), points[1]["value"].get<double>());
  EXPECT_GE(points[1]["high"].get<double>(), points[1]["value"].get<double>());
}

TEST_F(History, ConfigurationsAreSeriesOfTheirOwn) {
  write_runs(6, 5.0, "a", "intra");
  write_runs(6, 9.0, "a", "fastdds");
  const auto o = robotperf_cli(history("--format json"));
  ASSERT_EQ(o.exit_code, 0) << o.out;
  const auto j = nlohmann::json::parse(o.out);
  ASSERT_EQ(j["series"].size(), 2u) << o.out;
  // Neither series has a change: the transports' difference is not a step of either.
  EXPECT_TRUE(j["series"][0]["changes"].empty()) << o.out;
  EXPECT_TRUE(j["series"][1]["changes"].empty()) << o.out;
}

// A folder with a results database is read through it (fast for many runs): history, the list
// and compare read as they do from the files.
TEST_F(History, AFoldersDatabaseReadsAsItsFiles) {
  for (int rev = 0; rev < 8; ++rev) write_runs(1, 5.0, "r" + std::to_string(rev));
  for (int rev = 8; rev < 14; ++rev) write_runs(1, 6.5, "r" + std::to_string(rev));
  const auto history_files = robotperf_cli(history("--format json --by rev"));
  const auto list_files = robotperf_cli("results list " + dir_.string() + " --format csv");
  const std::string compare = "compare label.rev=r1 label.rev=r12 --results " + dir_.string();
  const auto compare_files = robotperf_cli(compare);
  ASSERT_EQ(compare_files.exit_code, 0) << compare_files.out;
  const std::string unknown = "compare label.rev=r1 no-such-board --results " + dir_.string();
  const auto unknown_files = robotperf_cli(unknown);
  ASSERT_EQ(history_files.exit_code, 0) << history_files.out;
  ASSERT_FALSE(fs::exists(dir_ / "robotperf.db"));
  ASSERT_EQ(robotperf_cli("results rebuild-db " + dir_.string()).exit_code, 0);
  EXPECT_EQ(robotperf_cli(history("--format json --by rev")).out, history_files.out);
  EXPECT_EQ(robotperf_cli("results list " + dir_.string() + " --format csv").out, list_files.out);
  EXPECT_EQ(robotperf_cli(compare).out, compare_files.out);
  const auto unknown_database = robotperf_cli(unknown);
  EXPECT_EQ(unknown_database.exit_code, 2);
  EXPECT_EQ(unknown_database.out, unknown_files.out);
  // A run added after the database was made is read as well.
  write_runs(1, 6.5, "r14");
  const auto j = nlohmann::json::parse(robotperf_cli(history("--format json")).out);
  EXPECT_EQ(j["series"][0]["points"].size(), 15u);
  EXPECT_EQ(j["series"][0]["changes"].size(), 1u);
}

// --label chooses runs in every read verb: the list, history and the report.
TEST_F(History, LabelsChooseTheRunsOfEveryReadVerb) {
  write_runs(4, 5.0, "main");
  write_runs(3, 5.0, "pr");
  const auto listed =
      robotperf_cli("results list " + dir_.string() + " --label rev=pr --format json");
  ASSERT_EQ(listed.exit_code, 0) << listed.out;
  const auto rows = nlohmann::json::parse(listed.out);
  ASSERT_EQ(rows.size(), 3u) << listed.out;
  for (const auto& row : rows) EXPECT_EQ(row["labels"], "rev=pr");

  const auto h =
      nlohmann::json::parse(robotperf_cli(history("--label rev=main --format json")).out);
  EXPECT_EQ(h["series"][0]["points"].size(), 4u);

  const auto md = robotperf_cli("report " + dir_.string() + " --label rev=pr --md -");
  ASSERT_EQ(md.exit_code, 0) << md.out;
  EXPECT_NE(md.out.find("rev=pr"), std::string::npos);
  EXPECT_EQ(md.out.find("rev=main"), std::string::npos) << md.out;

  const auto bad = robotperf_cli("results list " + dir_.string() + " --label rev");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.out.find("expected KEY=VALUE"), std::string::npos) << bad.out;
}

TEST_F(History, AnUnknownMetricOrBenchmarkIsOneLine) {
  write_runs(3, 5.0, "a");
  const auto metric = robotperf_cli(history("--metric latency.p51"));
  EXPECT_EQ(metric.exit_code, 2);
  EXPECT_NE(metric.out.find("no run of a1 has the metric latency.p51; its runs have: "),
            std::string::npos)
      << metric.out;
  EXPECT_NE(metric.out.find("latency.p50"), std::string::npos) << metric.out;
  const auto id = robotperf_cli("history zz9 --results " + dir_.string());
  EXPECT_EQ(id.exit_code, 2);
  EXPECT_NE(id.out.find("no runs of zz9"), std::string::npos) << id.out;
}

}  // namespace
