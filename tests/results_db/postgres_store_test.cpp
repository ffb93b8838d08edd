// The PostgreSQL store against a server of the test's own: what a pushed run holds (the rows the
// SQLite store records of it), reading runs back as their files read, pushing again, schemas it
// must refuse, and URLs it must refuse.
#include "robotperf/results_db/postgres_store.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <map>
#include <memory>

#include "../report/sample_runs.hpp"
#include "postgres_server.hpp"
#include "robotperf/report/run_store.hpp"
#include "robotperf/results_db/results_db.hpp"

namespace robotperf::results_db {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using report::testing::SampleRun;
using report::testing::write_sample;
using test_support::PostgresServer;
using Rows = std::vector<std::vector<std::string>>;

class ResultsDbPostgres : public ::testing::Test {
 protected:
  void SetUp() override {
    if (test_support::postgres_bin_dir().empty())
      GTEST_SKIP() << "no PostgreSQL server binaries in /usr/lib/postgresql/*/bin (apt install "
                      "postgresql)";
    server_ = std::make_unique<PostgresServer>();
    server_->create_database("results");
    dir_ = server_->dir() / "files";
    fs::create_directories(dir_);
  }

  static SampleRun sample(int k) {
    SampleRun s;
    s.start_unix_ns += static_cast<int64_t>(k) * 1'000'000'000;
    s.base_latency_ms = 2.0 + k;
    return s;
  }
  std::string url() const { return server_->socket_url("results"); }
  Rows query(const std::string& sql) const { return server_->query("results", sql); }

  std::unique_ptr<PostgresServer> server_;
  fs::path dir_;
};

// A real as JSON writes it, "null" for none: the same text for the same double from either store.
std::string real_text(double v) {
  return json(v).dump();
}

// The metrics of the run of `file` as "value unit low high", by name, from either store.
std::map<std::string, std::string> postgres_metrics(const PostgresServer& server,
                                                    const std::string& file) {
  // PostgreSQL's text of a double reads back as that double.
  auto text = [](const std::string& s) { return s.empty() ? "null" : real_text(std::stod(s)); };
  std::map<std::string, std::string> out;
  for (const auto& row : server.query("results",
                                      "SELECT m.name, m.value, m.unit, m.low, m.high FROM metrics "
                                      "m JOIN runs r ON r.id = m.run_id WHERE r.file = '" +
                                          file + "'"))
    out[row[0]] = text(row[1]) + " " + row[2] + " " + text(row[3]) + " " + text(row[4]);
  return out;
}

std::map<std::string, std::string> sqlite_metrics(const Database& db, const std::string& file) {
  auto text = real_text;
  std::map<std::string, std::string> out;
  for (const RunRow& r : db.runs()) {
    if (r.file != file) continue;
    for (const MetricRow& m : db.metrics(r.id))
      out[m.name] = text(m.value) + " " + m.unit + " " + (m.low ? text(*m.low) : "null") + " " +
                    (m.high ? text(*m.high) : "null");
  }
  return out;
}

TEST_F(ResultsDbPostgres, APushedRunHoldsTheRowsSqliteRecordsAndReadsBackAsItsFile) {
  SampleRun labelled = sample(0), lossy = sample(1);
  labelled.labels = {{"board", "rev-b"}, {"rev", "main"}};
  lossy.lost = 3;
  write_sample(dir_, labelled, /*csv=*/true, /*power_w=*/12.5);
  write_sample(dir_, lossy);
  const report::RunScan scan = report::scan_results(dir_);
  ASSERT_EQ(scan.runs.size(), 2u);

  auto store = PostgresStore::connect(url());
  EXPECT_EQ(store.schema_version(), kPostgresSchemaVersion);
  EXPECT_EQ(store.target(), url());  // the socket's folder as the host, no credentials
  const Pushed pushed = store.push(scan.runs);
  EXPECT_EQ(pushed.pushed, 2u);
  EXPECT_TRUE(pushed.skipped.empty());

  auto sqlite = Database::open(dir_ / kDatabaseFile);
  for (const auto& run : scan.runs) sqlite.record(run.json, run.path);
  for (const auto& run : scan.runs) {
    const std::string file = run.path.filename().string();
    SCOPED_TRACE(file);
    const auto metrics = postgres_metrics(*server_, file);
    EXPECT_GT(metrics.size(), 30u);
    EXPECT_EQ(metrics, sqlite_metrics(sqlite, file));
    const Rows row = query(
        "SELECT valid, samples_source, configuration_key, machine->>'hostname', "
        "(SELECT count(*) FROM samples s WHERE s.run_id = r.id), "
        "(SELECT coalesce(sum(count), 0) FROM histogram h WHERE h.run_id = r.id) "
        "FROM runs r WHERE file = '" +
        file + "'");
    ASSERT_EQ(row.size(), 1u);
    EXPECT_EQ(row[0][0], run.valid ? "t" : "f");
    EXPECT_EQ(row[0][1], run.csv_path ? "csv" : "histogram");
    EXPECT_EQ(row[0][2], sqlite.runs().at(&run - scan.runs.data()).configuration_key);
    EXPECT_EQ(row[0][3], "bench-host");
    EXPECT_EQ(row[0][4], run.csv_path ? std::to_string(run.matched) : "0");
    EXPECT_EQ(row[0][5], run.csv_path ? "0" : std::to_string(run.matched));
  }
  EXPECT_EQ(query("SELECT r.file, l.key, l.value FROM labels l JOIN runs r ON r.id = l.run_id "
                  "ORDER BY l.key"),
            (Rows{{scan.runs[0].path.filename().string(), "board", "rev-b"},
                  {scan.runs[0].path.filename().string(), "rev", "main"}}));

  const report::RunScan back = store.runs();
  EXPECT_TRUE(back.skipped.empty());
  ASSERT_EQ(back.runs.size(), 2u);
  for (std::size_t i = 0; i < back.runs.size(); ++i) {
    EXPECT_EQ(back.runs[i].path, scan.runs[i].path.filename());
    EXPECT_EQ(back.runs[i].json, scan.runs[i].json);
    EXPECT_FALSE(back.runs[i].csv_path);
  }
  EXPECT_EQ(report::runs_table(back.runs), report::runs_table(scan.runs));
}

// A run pushed again keeps its row (and id) and gets its rows anew; a run of another machine with
// the same file name is another run.
TEST_F(ResultsDbPostgres, PushingARunAgainReplacesItAndAnotherMachinesRunOfTheSameNameIsAdded) {
  write_sample(dir_, sample(0), /*csv=*/true);
  write_sample(dir_, sample(1));
  const report::RunScan scan = report::scan_results(dir_);
  auto store = PostgresStore::connect(url());
  EXPECT_EQ(store.push(scan.runs).pushed, 2u);
  const Rows first = query("SELECT id, file FROM runs ORDER BY id");
  const Rows counts = query(
      "SELECT (SELECT count(*) FROM metrics), (SELECT count(*) FROM samples), "
      "(SELECT count(*) FROM histogram)");
  // Twice in one push (its folder and its file) is once, too.
  std::vector<report::StoredRun> twice = scan.runs;
  twice.push_back(scan.runs[0]);
  EXPECT_EQ(PostgresStore::connect(url()).push(twice).pushed, 2u);
  EXPECT_EQ(query("SELECT id, file FROM runs ORDER BY id"), first);
  EXPECT_EQ(query("SELECT (SELECT count(*) FROM metrics), (SELECT count(*) FROM samples), "
                  "(SELECT count(*) FROM histogram)"),
            counts);

  report::StoredRun other_board = scan.runs[1];
  other_board.json["machine"]["hostname"] = "board-2";
  EXPECT_EQ(store.push({other_board}).pushed, 1u);
  EXPECT_EQ(query("SELECT count(*), count(DISTINCT file) FROM runs"), (Rows{{"3", "2"}}));
}

TEST_F(ResultsDbPostgres, ADatabaseOfANewerSchemaIsRefusedUntouched) {
  write_sample(dir_, sample(0));
  PostgresStore::connect(url()).push(report::scan_results(dir_).runs);
  query("UPDATE schema_version SET version = 99");
  try {
    PostgresStore::connect(url());
    FAIL() << "a database of schema version 99 was used";
  } catch (const DatabaseError& e) {
    const std::string what = e.what();
    EXPECT_TRUE(what.starts_with(url() + ": schema version 99 is not one this robotperf knows"))
        << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
  EXPECT_EQ(query("SELECT count(*) FROM runs"), (Rows{{"1"}}));
}

// Needs no server.
TEST(ResultsDbPostgresUrl, AServerThatIsNotThereIsOneLineNamingIt) {
  const std::string nowhere = "postgresql://robotperf@127.0.0.1:1/results";
  try {
    PostgresStore::connect(nowhere);
    FAIL() << "connected to port 1";
  } catch (const ConnectionError& e) {
    const std::string what = e.what();
    EXPECT_TRUE(what.starts_with(nowhere + ": cannot connect: ")) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
}

// Needs no server.
TEST(ResultsDbPostgresUrl, UrlsHoldingAPasswordAreRefusedWithoutRepeatingIt) {
  for (const std::string url :
       {"postgresql://ci:s3cret-pw@db.lab/robotperf", "postgres://ci:s3cret-pw@db.lab",
        "postgresql://db.lab/robotperf?password=s3cret-pw",
        "postgresql://db.lab/robotperf?sslmode=require&sslpassword=s3cret-pw",
        "postgresql://db.lab/robotperf?%70assword=s3cret-pw"}) {
    SCOPED_TRACE(url);
    try {
      checked_url(url, "--to");
      FAIL() << "accepted";
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("--to holds a password: give it with PGPASSWORD or a password file"),
                std::string::npos)
          << what;
      EXPECT_EQ(what.find("s3cret"), std::string::npos) << what;
    }
  }
  for (const std::string url : {"db.lab/robotperf", "host=db.lab dbname=robotperf", ""})
    EXPECT_THROW(checked_url(url, "--to"), std::invalid_argument) << url;
  EXPECT_THROW(checked_url("postgresql://db.lab/robotperf?nonsense=1", "--to"),
               std::invalid_argument);
  for (const std::string url :
       {"postgresql://ci@db.lab:5433/robotperf?sslmode=verify-full", "postgresql:///robotperf",
        "postgres://db.lab/robotperf?service=lab"})
    EXPECT_EQ(checked_url(url, "--to"), url);
}

}  // namespace
}  // namespace robotperf::results_db
