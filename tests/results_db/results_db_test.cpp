// The results database: what a recorded run holds, several processes recording at once, rebuilding
// from the files, and databases it must refuse.
#include "robotperf/results_db/results_db.hpp"

#include <gtest/gtest.h>
#include <sqlite3.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>
#include <set>

#include "../report/sample_runs.hpp"
#include "robotperf/report/history.hpp"
#include "robotperf/report/run_store.hpp"
#include "snapshot.hpp"

namespace robotperf::results_db {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using report::testing::SampleRun;
using report::testing::write_sample;

json read_json(const fs::path& p) {
  std::ifstream in(p);
  return json::parse(in);
}

class ResultsDb : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("robotperf-results-db-" + std::to_string(getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Run k of a test: its own start second, so its own file.
  static SampleRun sample(int k) {
    SampleRun s;
    s.start_unix_ns += static_cast<int64_t>(k) * 1'000'000'000;
    s.base_latency_ms = 2.0 + k;
    return s;
  }
  static void record_file(Database& db, const fs::path& file) { db.record(read_json(file), file); }
  fs::path database() const { return dir_ / kDatabaseFile; }

  fs::path dir_;
};

// Sets a database's schema version behind the library's back, as another program would.
void set_user_version(const fs::path& path, int version) {
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  const std::string sql = "PRAGMA user_version = " + std::to_string(version);
  EXPECT_EQ(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr), SQLITE_OK);
  sqlite3_close(db);
}

TEST_F(ResultsDb, ARecordedRunHoldsWhatItsFileSays) {
  SampleRun lossy = sample(1);
  lossy.lost = 3;
  const fs::path with_csv = write_sample(dir_, sample(0), /*csv=*/true, /*power_w=*/12.5);
  const fs::path without_csv = write_sample(dir_, lossy);
  auto db = Database::open(database());
  EXPECT_EQ(db.schema_version(), kSchemaVersion);
  json labelled = read_json(with_csv);
  labelled["labels"] = {{"board", "rev-b"}, {"attempt", 2}};
  db.record(labelled, with_csv);
  record_file(db, without_csv);
  record_file(db, without_csv);  // again: replaced, not added

  const auto runs = db.runs();
  ASSERT_EQ(runs.size(), 2u);
  for (const RunRow& r : runs) {
    const fs::path file = dir_ / r.file;
    SCOPED_TRACE(r.file);
    const report::StoredRun stored = report::load_run(file);
    EXPECT_EQ(r.file, file.filename().string());  // relative to the database's folder
    EXPECT_EQ(r.benchmark_id, "a1");
    EXPECT_EQ(r.started_utc, stored.started_utc);
    EXPECT_EQ(r.valid, stored.valid);
    EXPECT_EQ(r.rate_hz, 30.0);
    EXPECT_EQ(r.backend, "cpu");
    EXPECT_NE(r.configuration_key.find("a1 | AMD Ryzen 7 5800X | intra | single | cpu | black"),
              std::string::npos)
        << r.configuration_key;
    EXPECT_EQ(db.metric(r.id, "latency.p50")->value, stored.latency.p50);
    EXPECT_EQ(db.metric(r.id, "latency.p99")->value, stored.latency.p99);
    EXPECT_EQ(db.metric(r.id, "latency.max")->unit, "ms");
    EXPECT_EQ(db.metric(r.id, "count.matched")->value, static_cast<double>(stored.matched));
    const auto p50 = db.metric(r.id, "latency.p50");
    ASSERT_TRUE(p50->low && p50->high);
    EXPECT_LE(*p50->low, p50->value);
    EXPECT_GE(*p50->high, p50->value);
  }
  const RunRow& first = runs[0];
  EXPECT_TRUE(first.valid);
  EXPECT_EQ(first.samples_source, "csv");
  const auto samples = db.samples_ns(first.id);
  EXPECT_EQ(samples.size(), 100u);
  std::vector<double> csv_ms =
      report::read_latency_csv(dir_ / (fs::path(first.file).stem().string() + ".latencies.csv"));
  ASSERT_EQ(csv_ms.size(), samples.size());
  EXPECT_EQ(samples.front(), std::llround(csv_ms.front() * 1e6));
  EXPECT_EQ(db.metric(first.id, "power")->value, 12.5);
  EXPECT_EQ(db.metric(first.id, "power")->unit, "W");
  EXPECT_EQ(db.labels(first.id),
            (std::map<std::string, std::string>{{"attempt", "2"}, {"board", "rev-b"}}));
  EXPECT_TRUE(db.histogram(first.id).empty());

  const RunRow& second = runs[1];
  EXPECT_FALSE(second.valid);
  EXPECT_EQ(second.samples_source, "histogram");
  EXPECT_TRUE(db.samples_ns(second.id).empty());
  EXPECT_FALSE(db.metric(second.id, "power"));
  std::int64_t binned = 0;
  for (const auto& bin : db.histogram(second.id)) {
    EXPECT_LT(*bin.lower_ns, bin.upper_ns);
    binned += bin.count;
  }
  EXPECT_EQ(binned, 97);  // the matched messages
  EXPECT_EQ(db.metric(second.id, "count.lost")->value, 3.0);

  RunQuery of_a2;
  of_a2.benchmark_id = "a2";
  EXPECT_EQ(db.runs(of_a2).size(), 0u);
  RunQuery on_rev_b, on_rev_a;
  on_rev_b.labels = {{"board", "rev-b"}};
  on_rev_a.labels = {{"board", "rev-a"}};
  EXPECT_EQ(db.runs(on_rev_b).size(), 1u);
  EXPECT_EQ(db.runs(on_rev_a).size(), 0u);
  RunQuery since_second, before_second;
  since_second.since_utc = before_second.until_utc = second.started_utc;
  EXPECT_EQ(db.runs(since_second).size(), 1u);
  EXPECT_EQ(db.runs(before_second).at(0).file, first.file);
  RunQuery alike;
  alike.configuration_key = first.configuration_key;
  EXPECT_EQ(db.runs(alike).size(), 2u);
}

// Four processes open one new database at once (creating and migrating it) and record 20 runs
// each, opening it for every run as robotperf does: every run is there once, as its file says.
TEST_F(ResultsDb, SeveralProcessesRecordIntoOneDatabaseAtOnce) {
  constexpr int kProcesses = 4, kRunsEach = 20;
  std::vector<fs::path> files;
  for (int k = 0; k < kProcesses * kRunsEach; ++k)
    files.push_back(write_sample(dir_, sample(k), /*csv=*/k % 2 == 0));
  int start[2];
  ASSERT_EQ(pipe(start), 0);
  std::vector<pid_t> children;
  for (int p = 0; p < kProcesses; ++p) {
    const pid_t pid = fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
      close(start[1]);
      char c;
      // Every child waits here until the parent closes the pipe: they start together.
      [[maybe_unused]] const auto got = read(start[0], &c, 1);
      int status = 0;
      try {
        for (int k = p; k < kProcesses * kRunsEach; k += kProcesses) {
          auto db = Database::open(database());
          record_file(db, files[k]);
        }
      } catch (const std::exception& e) {
        std::fprintf(stderr, "process %d: %s\n", p, e.what());
        status = 1;
      }
      _exit(status);
    }
    children.push_back(pid);
  }
  close(start[0]);
  close(start[1]);
  for (pid_t child : children) {
    int status = 0;
    ASSERT_EQ(waitpid(child, &status, 0), child);
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  }

  const auto db = Database::open(database());
  const auto runs = db.runs();
  ASSERT_EQ(runs.size(), files.size());
  std::set<std::string> seen;
  for (const RunRow& r : runs) {
    EXPECT_TRUE(seen.insert(r.file).second) << r.file;
    const report::StoredRun stored = report::load_run(dir_ / r.file);
    EXPECT_EQ(r.valid, stored.valid);
    EXPECT_EQ(db.metric(r.id, "latency.p50")->value, stored.latency.p50);
    EXPECT_EQ(db.metric(r.id, "latency.p99")->value, stored.latency.p99);
    EXPECT_EQ(db.metric(r.id, "count.measured")->value, static_cast<double>(stored.measured));
    EXPECT_EQ(r.samples_source, stored.csv_path ? "csv" : "histogram");
    if (stored.csv_path) {
      EXPECT_EQ(db.samples_ns(r.id).size(), stored.matched);
    }
  }
  // The database each process made before linking it into place is gone.
  for (const auto& e : fs::directory_iterator(dir_)) {
    const std::string name = e.path().filename().string();
    EXPECT_TRUE(name.ends_with(".json") || name.ends_with(".csv") ||
                name.starts_with(kDatabaseFile))
        << "left behind: " << name;
    EXPECT_FALSE(name.ends_with(".new")) << "left behind: " << name;
  }
}

TEST_F(ResultsDb, RebuildingFromTheFilesGivesTheRowsRecordingGave) {
  SampleRun other = sample(2);
  other.id = "a2";
  other.lost = 1;
  std::vector<fs::path> files = {write_sample(dir_, sample(0), true, 3.0),
                                 write_sample(dir_, sample(1)), write_sample(dir_, other, true)};
  {
    auto db = Database::open(database());
    for (const auto& f : files) record_file(db, f);
  }
  const json recorded = testing::snapshot(Database::open(database()));
  ASSERT_EQ(recorded.size(), 3u);
  // Not runs: a file that is not JSON, a series summary (not even looked at).
  std::ofstream(dir_ / "notes.json") << "not json";
  std::ofstream(dir_ / "x.series.json") << "{}";

  const Rebuilt rebuilt = rebuild(dir_);
  EXPECT_EQ(rebuilt.database, database());
  EXPECT_EQ(rebuilt.recorded, 3u);
  ASSERT_EQ(rebuilt.skipped.size(), 1u);
  EXPECT_NE(rebuilt.skipped[0].find("notes.json: not valid JSON"), std::string::npos)
      << rebuilt.skipped[0];
  EXPECT_EQ(testing::snapshot(Database::open(database())), recorded);
  for (const auto& e : fs::directory_iterator(dir_))
    EXPECT_FALSE(e.path().extension() == ".tmp") << "left behind: " << e.path();
}

TEST_F(ResultsDb, ACorruptDatabaseIsRefusedAndRebuildReplacesIt) {
  write_sample(dir_, sample(0));
  std::ofstream(database()) << std::string(8192, 'x');
  try {
    Database::open(database());
    FAIL() << "a corrupt database opened";
  } catch (const DatabaseError& e) {
    const std::string what = e.what();
    EXPECT_TRUE(what.starts_with(database().string() + ": ")) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
  EXPECT_EQ(rebuild(dir_).recorded, 1u);
  EXPECT_EQ(Database::open(database()).runs().size(), 1u);
}

TEST_F(ResultsDb, ADatabaseOfAnUnknownSchemaVersionIsRefusedUntouched) {
  const fs::path file = write_sample(dir_, sample(0));
  {
    auto db = Database::open(database());
    record_file(db, file);
  }
  set_user_version(database(), kSchemaVersion + 1);
  try {
    Database::open(database());
    FAIL() << "a database of schema version " << kSchemaVersion + 1 << " opened";
  } catch (const DatabaseError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("schema version " + std::to_string(kSchemaVersion + 1) +
                        " is not one this robotperf knows"),
              std::string::npos)
        << what;
    EXPECT_NE(what.find("robotperf results rebuild-db " + dir_.string()), std::string::npos)
        << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
  set_user_version(database(), kSchemaVersion);
  EXPECT_EQ(Database::open(database()).runs().size(), 1u);  // its rows were left as they were
}

// A database of schema 1 (no document column) is migrated on open: its runs keep their rows, with
// no document until rebuilt, and runs recorded after hold theirs, which reads back as the file.
TEST_F(ResultsDb, ASchema1DatabaseIsMigratedAndRunsRecordedAfterHoldTheirDocument) {
  const fs::path old_run = write_sample(dir_, sample(0));
  const fs::path new_run = write_sample(dir_, sample(1), /*csv=*/true);
  {
    auto db = Database::open(database());
    record_file(db, old_run);
  }
  {
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open(database().c_str(), &db), SQLITE_OK);
    // Schema 1, as an older robotperf left it: what schema 2 added taken away.
    for (const char* drop :
         {"ALTER TABLE runs DROP COLUMN document", "ALTER TABLE runs DROP COLUMN warnings",
          "ALTER TABLE metrics DROP COLUMN better"})
      EXPECT_EQ(sqlite3_exec(db, drop, nullptr, nullptr, nullptr), SQLITE_OK) << drop;
    sqlite3_close(db);
  }
  set_user_version(database(), 1);
  auto db = Database::open(database());
  EXPECT_EQ(db.schema_version(), 2);
  record_file(db, new_run);
  ASSERT_EQ(db.runs().size(), 2u);

  sqlite3* raw = nullptr;
  ASSERT_EQ(sqlite3_open(database().c_str(), &raw), SQLITE_OK);
  sqlite3_stmt* statement = nullptr;
  ASSERT_EQ(sqlite3_prepare_v2(raw, "SELECT file, document FROM runs ORDER BY started_utc", -1,
                               &statement, nullptr),
            SQLITE_OK);
  std::vector<std::pair<std::string, std::optional<std::string>>> documents;
  while (sqlite3_step(statement) == SQLITE_ROW) {
    const auto* document = sqlite3_column_text(statement, 1);
    documents.emplace_back(reinterpret_cast<const char*>(sqlite3_column_text(statement, 0)),
                           document
                               ? std::optional<std::string>(reinterpret_cast<const char*>(document))
                               : std::nullopt);
  }
  sqlite3_finalize(statement);
  sqlite3_close(raw);
  ASSERT_EQ(documents.size(), 2u);
  EXPECT_EQ(documents[0].first, old_run.filename().string());
  EXPECT_FALSE(documents[0].second);
  ASSERT_TRUE(documents[1].second);
  const report::StoredRun from_file = report::load_run(new_run);
  const report::StoredRun from_database =
      report::run_from_json(json::parse(*documents[1].second), new_run);
  EXPECT_EQ(from_database.json, from_file.json);
  EXPECT_EQ(report::runs_table({from_database}), report::runs_table({from_file}));

  EXPECT_EQ(rebuild(dir_).recorded, 2u);  // and rebuilding gives the old run its document
  sqlite3* rebuilt = nullptr;
  ASSERT_EQ(sqlite3_open(database().c_str(), &rebuilt), SQLITE_OK);
  ASSERT_EQ(sqlite3_prepare_v2(rebuilt, "SELECT count(*) FROM runs WHERE document IS NULL", -1,
                               &statement, nullptr),
            SQLITE_OK);
  ASSERT_EQ(sqlite3_step(statement), SQLITE_ROW);
  EXPECT_EQ(sqlite3_column_int(statement, 0), 0);
  sqlite3_finalize(statement);
  sqlite3_close(rebuilt);
}

// The query plan SQLite chooses for `sql` on the database at `path`, one line per step.
std::string query_plan(const fs::path& path, const std::string& sql) {
  sqlite3* db = nullptr;
  EXPECT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  sqlite3_stmt* statement = nullptr;
  std::string plan;
  if (sqlite3_prepare_v2(db, ("EXPLAIN QUERY PLAN " + sql).c_str(), -1, &statement, nullptr) ==
      SQLITE_OK) {
    while (sqlite3_step(statement) == SQLITE_ROW)
      plan += reinterpret_cast<const char*>(sqlite3_column_text(statement, 3)) + std::string("\n");
  }
  sqlite3_finalize(statement);
  sqlite3_close(db);
  return plan;
}

// What reports and compare ask for is found through an index, not a scan of every run.
TEST_F(ResultsDb, TheQueriesReportsNeedUseIndexes) {
  Database::open(database());
  for (const auto& [sql, index] : std::vector<std::pair<std::string, std::string>>{
           {"SELECT id FROM runs WHERE benchmark_id = 'a1' AND started_utc >= '2026' ORDER BY "
            "started_utc",
            "runs_by_benchmark_and_time"},
           {"SELECT id FROM runs WHERE configuration_key = 'k' ORDER BY started_utc",
            "runs_by_configuration"},
           {"SELECT run_id FROM labels WHERE key = 'board' AND value = 'rev-b'",
            "labels_by_key_and_value"},
           {"SELECT value FROM metrics WHERE run_id = 1 AND name = 'latency.p99'", "PRIMARY KEY"},
           {"SELECT run_id, value FROM metrics WHERE name = 'latency.p99'", "metrics_by_name"},
           {"SELECT latency_ns FROM samples WHERE run_id = 1 ORDER BY seq", "PRIMARY KEY"}}) {
    const std::string plan = query_plan(database(), sql);
    EXPECT_NE(plan.find(index), std::string::npos) << sql << "\n" << plan;
    EXPECT_EQ(plan.find("TEMP B-TREE"), std::string::npos) << sql << "\n" << plan;
  }
}

// A file that exists but holds no schema yet (version 0, as sqlite3 leaves an empty file) is
// migrated like a new one.
TEST_F(ResultsDb, AnEmptyFileIsMigratedToTheCurrentSchema) {
  std::ofstream(database()).close();
  auto db = Database::open(database());
  EXPECT_EQ(db.schema_version(), kSchemaVersion);
  EXPECT_TRUE(db.runs().empty());
}

// A folder's runs listed from its database read as the files read: every field `results list`
// shows in any format, and history's figures and series.
TEST_F(ResultsDb, RunsListedFromTheDatabaseReadAsTheirFiles) {
  SampleRun invalid = sample(1);
  invalid.lost = 40;  // too lossy: INVALID, with its reasons
  SampleRun labelled = sample(2);
  labelled.labels = {{"rev", "abc; def"}, {"board", "orin-3"}};
  labelled.warnings = {{"governor", "CPU governor is powersave; pin it"}};
  write_sample(dir_, sample(0), /*csv=*/true, /*power_w=*/7.5);
  write_sample(dir_, invalid);
  write_sample(dir_, labelled);
  rebuild(dir_);
  const report::RunScan files = report::scan_results(dir_);
  auto synced = open_synced(dir_);
  ASSERT_TRUE(synced.has_value());
  EXPECT_TRUE(synced->skipped.empty());
  const std::vector<report::StoredRun> listed = synced->database.listed_runs();
  ASSERT_EQ(listed.size(), 3u);
  EXPECT_EQ(report::runs_json(listed), report::runs_json(files.runs));
  EXPECT_EQ(report::runs_table(listed), report::runs_table(files.runs));
  EXPECT_FALSE(listed[1].valid);
  EXPECT_EQ(listed[1].invalid_reasons, files.runs[1].invalid_reasons);
  EXPECT_EQ(listed[2].warnings, files.runs[2].warnings);

  report::HistoryOptions options;
  options.benchmark_id = "a1";
  options.metric = "latency.p99";
  const auto from_files = report::history_json(report::history(files.runs, options));
  const auto from_database =
      report::history_json(report::history(listed, options, metric_source(synced->database)));
  EXPECT_EQ(from_database, from_files);
  EXPECT_EQ(from_database["better"], "smaller");
}

// The database follows its folder: a file copied in is recorded, a file deleted leaves, a file
// that is no result is skipped as a scan of the folder skips it.
TEST_F(ResultsDb, ASyncedDatabaseFollowsItsFolder) {
  const fs::path first = write_sample(dir_, sample(0));
  const fs::path second = write_sample(dir_, sample(1));
  rebuild(dir_);
  fs::remove(first);
  const fs::path third = write_sample(dir_, sample(2));
  std::ofstream(dir_ / "notes.json") << "{\"not\": \"a result\"}";
  auto synced = open_synced(dir_);
  ASSERT_TRUE(synced.has_value());
  ASSERT_EQ(synced->skipped.size(), 1u);
  EXPECT_NE(synced->skipped[0].find("notes.json"), std::string::npos) << synced->skipped[0];
  std::vector<std::string> names;
  for (const auto& r : synced->database.listed_runs()) names.push_back(r.path.filename());
  EXPECT_EQ(names, (std::vector<std::string>{second.filename(), third.filename()}));
  // What was recorded stays: a second reader has nothing to record.
  EXPECT_EQ(Database::open(database()).runs().size(), 2u);
}

TEST_F(ResultsDb, AFolderWithoutADatabaseIsReadFromItsFiles) {
  write_sample(dir_, sample(0));
  EXPECT_FALSE(open_synced(dir_).has_value());
  EXPECT_FALSE(fs::exists(database())) << "reading made a database";
}

}  // namespace
}  // namespace robotperf::results_db
