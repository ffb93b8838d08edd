// The results database as runs fill it: several runs at once into one folder, rebuild-db, and a
// database a run cannot use (its results file and exit status stay what they would be).
#include <gtest/gtest.h>
#include <sqlite3.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "../command_line.hpp"
#include "../results_db/snapshot.hpp"
#include "robotperf/results_db/results_db.hpp"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using robotperf::results_db::Database;
using robotperf::test_support::Background;
using robotperf::test_support::robotperf_cli;

constexpr const char* kRun = "run a5 --count 40 --rate 200 --quiet --output ";

std::vector<fs::path> result_files(const fs::path& dir) {
  std::vector<fs::path> out;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (name.starts_with("a5-") && e.path().extension() == ".json") out.push_back(e.path());
  }
  return out;
}

json read_json(const fs::path& p) {
  std::ifstream in(p);
  return json::parse(in);
}

// The exit status robotperf gives a run its results file calls valid or not.
int status_of(const fs::path& file) {
  return read_json(file).at("validity").at("valid").get<bool>() ? 0 : 3;
}

class ResultsDbCli : public ::testing::Test {
 protected:
  // Four runs started at once into one folder (two with --csv), shared by the tests that read it.
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("robotperf-results-db-cli-" + std::to_string(getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    std::vector<std::unique_ptr<Background>> runs;
    for (int i = 0; i < 4; ++i) {
      runs.push_back(std::make_unique<Background>(std::string(ROBOTPERF_EXECUTABLE) + " " + kRun +
                                                      (dir_ / "results").string() +
                                                      (i % 2 ? " --csv" : ""),
                                                  dir_ / ("run-" + std::to_string(i) + ".log")));
    }
    for (auto& run : runs) {
      const int code = run->wait(std::chrono::seconds(240));
      ASSERT_TRUE(code == 0 || code == 3) << run->output();
      ASSERT_EQ(run->output().find("rebuild-db"), std::string::npos) << run->output();
    }
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static fs::path dir_;
};
fs::path ResultsDbCli::dir_;

TEST_F(ResultsDbCli, RunsStartedAtOnceAreEachRecordedOnceAsTheirFilesSay) {
  const fs::path results = dir_ / "results";
  const auto files = result_files(results);
  ASSERT_EQ(files.size(), 4u);
  const auto db = Database::open(results / robotperf::results_db::kDatabaseFile);
  robotperf::results_db::RunQuery of_a5;
  of_a5.benchmark_id = "a5";
  const auto runs = db.runs(of_a5);
  ASSERT_EQ(runs.size(), 4u);
  std::set<std::string> seen;
  std::size_t from_csv = 0;
  for (const auto& r : runs) {
    SCOPED_TRACE(r.file);
    EXPECT_TRUE(seen.insert(r.file).second);
    const json j = read_json(results / r.file);
    const json& latency = j.at("latency_ms").at("from_scheduled");
    EXPECT_EQ(r.started_utc, j.at("started_utc"));
    EXPECT_EQ(r.valid, j.at("validity").at("valid").get<bool>());
    EXPECT_EQ(r.rate_hz, 200.0);
    EXPECT_EQ(db.metric(r.id, "latency.p50")->value, latency.at("p50").get<double>());
    EXPECT_EQ(db.metric(r.id, "latency.p99")->value, latency.at("p99").get<double>());
    const auto matched = j.at("counts").at("matched").get<std::size_t>();
    EXPECT_EQ(db.metric(r.id, "count.matched")->value, static_cast<double>(matched));
    EXPECT_EQ(db.metric(r.id, "count.measured")->value,
              j.at("counts").at("measured").get<double>());
    EXPECT_EQ(r.git_revision, j.at("software").at("git_revision"));
    if (r.samples_source == "csv") {
      ++from_csv;
      EXPECT_EQ(db.samples_ns(r.id).size(), matched);
    } else {
      EXPECT_EQ(r.samples_source, "histogram");
    }
  }
  EXPECT_EQ(from_csv, 2u);
  // Every run of one configuration at one rate: one key.
  robotperf::results_db::RunQuery alike;
  alike.configuration_key = runs[0].configuration_key;
  EXPECT_EQ(db.runs(alike).size(), 4u);
}

TEST_F(ResultsDbCli, RebuildDbGivesTheRowsTheRunsRecorded) {
  const fs::path results = dir_ / "results";
  const fs::path database = results / robotperf::results_db::kDatabaseFile;
  const json recorded = robotperf::results_db::testing::snapshot(Database::open(database));
  ASSERT_EQ(recorded.size(), 4u);
  std::ofstream(results / "broken.json") << "{";
  const auto o = robotperf_cli("results rebuild-db " + results.string());
  fs::remove(results / "broken.json");
  ASSERT_EQ(o.exit_code, 0) << o.out;
  EXPECT_NE(o.out.find(database.string() + ": rebuilt from " + results.string() +
                       ": 4 run(s) recorded, 1 file(s) skipped"),
            std::string::npos)
      << o.out;
  EXPECT_NE(
      o.out.find("robotperf: skipped " + (results / "broken.json").string() + ": not valid JSON"),
      std::string::npos)
      << o.out;
  EXPECT_EQ(robotperf::results_db::testing::snapshot(Database::open(database)), recorded);
  EXPECT_EQ(robotperf_cli("results rebuild-db " + (dir_ / "nothing").string()).exit_code, 2);
}

// A database robotperf cannot write to: the run keeps its file and exit status, and stderr names
// the database and the fix, which then repairs it.
TEST(ResultsDbCliFaults, ACorruptDatabaseCostsTheRunOneLineAndRebuildDbRepairsIt) {
  const fs::path dir =
      fs::temp_directory_path() / ("robotperf-results-db-corrupt-" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path database = dir / robotperf::results_db::kDatabaseFile;
  std::ofstream(database) << std::string(4096, '#');
  const auto o = robotperf_cli(std::string(kRun) + dir.string());
  const auto files = result_files(dir);
  ASSERT_EQ(files.size(), 1u) << o.out;
  EXPECT_EQ(o.exit_code, status_of(files[0])) << o.out;
  EXPECT_NE(o.out.find("robotperf: the run is not in " + database.string() + " ("),
            std::string::npos)
      << o.out;
  EXPECT_NE(o.out.find("robotperf results rebuild-db " + dir.string() + " makes the database"),
            std::string::npos)
      << o.out;
  EXPECT_NO_THROW(read_json(files[0]));

  const auto rebuilt = robotperf_cli("results rebuild-db " + dir.string());
  ASSERT_EQ(rebuilt.exit_code, 0) << rebuilt.out;
  EXPECT_NE(rebuilt.out.find(": 1 run(s) recorded"), std::string::npos) << rebuilt.out;
  const auto runs = Database::open(database).runs();
  ASSERT_EQ(runs.size(), 1u);
  EXPECT_EQ(runs[0].file, files[0].filename().string());
  fs::remove_all(dir);
}

TEST(ResultsDbCliFaults, ADatabaseOfAFutureSchemaIsLeftAloneAndNamed) {
  const fs::path dir =
      fs::temp_directory_path() / ("robotperf-results-db-future-" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path database = dir / robotperf::results_db::kDatabaseFile;
  Database::open(database);
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(database.c_str(), &db), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(db, "PRAGMA user_version = 99", nullptr, nullptr, nullptr), SQLITE_OK);
  sqlite3_close(db);
  const auto o = robotperf_cli(std::string(kRun) + dir.string());
  const auto files = result_files(dir);
  ASSERT_EQ(files.size(), 1u) << o.out;
  EXPECT_EQ(o.exit_code, status_of(files[0])) << o.out;
  EXPECT_NE(o.out.find("(schema version 99 is not one this robotperf knows (up to " +
                       std::to_string(robotperf::results_db::kSchemaVersion) + ")"),
            std::string::npos)
      << o.out;
  fs::remove_all(dir);
}

}  // namespace
