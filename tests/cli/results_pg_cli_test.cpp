// `results push` and the read verbs' --from against a PostgreSQL server each test starts: pushes
// from several processes at once, pushing again, the same listing as the files', and credentials
// that come from libpq's sources only and are shown nowhere.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "../command_line.hpp"
#include "../report/sample_runs.hpp"
#include "../results_db/postgres_server.hpp"
#include "robotperf/report/run_store.hpp"

namespace {

namespace fs = std::filesystem;
using robotperf::report::testing::SampleRun;
using robotperf::report::testing::write_sample;
using robotperf::test_support::Background;
using robotperf::test_support::PostgresServer;
using robotperf::test_support::robotperf_cli;
using Rows = std::vector<std::vector<std::string>>;

class ResultsDbPostgresCli : public ::testing::Test {
 protected:
  void SetUp() override {
    if (robotperf::test_support::postgres_bin_dir().empty())
      GTEST_SKIP() << "no PostgreSQL server binaries in /usr/lib/postgresql/*/bin (apt install "
                      "postgresql)";
    server_ = std::make_unique<PostgresServer>();
    server_->create_database("results");
  }

  // `count` runs in the folder `name` under the server's folder, k from `first` on: each its own
  // start second, so its own file; every other one with a .latencies.csv.
  fs::path write_runs(const std::string& name, int first, int count) const {
    const fs::path dir = server_->dir() / name;
    fs::create_directories(dir);
    for (int k = first; k < first + count; ++k) {
      SampleRun s;
      s.start_unix_ns += static_cast<int64_t>(k) * 1'000'000'000;
      s.base_latency_ms = 2.0 + k % 7;
      s.rmw = k % 3 ? "intra" : "fastdds";
      s.labels = {{"batch", name}};
      write_sample(dir, s, /*csv=*/k % 2 == 0);
    }
    return dir;
  }
  std::string url() const { return server_->socket_url("results"); }
  Rows query(const std::string& sql) const { return server_->query("results", sql); }

  std::unique_ptr<PostgresServer> server_;
};

// Four processes push at once into a new database (each migrating it), each its own eight runs
// and the same four shared ones: every run is there once, with the figures and labels its file has.
TEST_F(ResultsDbPostgresCli, PushesFromSeveralProcessesAtOnceHoldWhatTheFilesSay) {
  constexpr int kProcesses = 4, kRunsEach = 8, kShared = 4;
  const fs::path shared = write_runs("shared", 100, kShared);
  std::vector<std::unique_ptr<Background>> pushes;
  std::vector<fs::path> folders;
  for (int p = 0; p < kProcesses; ++p) {
    folders.push_back(write_runs("board" + std::to_string(p), p * kRunsEach, kRunsEach));
    pushes.push_back(std::make_unique<Background>(
        std::string(ROBOTPERF_EXECUTABLE) + " results push --to " + url() + " " +
            folders.back().string() + " " + shared.string(),
        server_->dir() / ("push-" + std::to_string(p) + ".log")));
  }
  for (auto& push : pushes) {
    ASSERT_EQ(push->wait(std::chrono::seconds(120)), 0) << push->output();
    EXPECT_NE(push->output().find(url() + ": pushed " + std::to_string(kRunsEach + kShared) +
                                  " run(s)\n"),
              std::string::npos)
        << push->output();
  }
  folders.push_back(shared);

  std::size_t files = 0;
  for (const fs::path& folder : folders) {
    for (const auto& run : robotperf::report::scan_results(folder).runs) {
      ++files;
      const std::string file = run.path.filename().string();
      SCOPED_TRACE(file);
      const Rows row = query(
          "SELECT r.valid, r.rmw, r.started_utc, p50.value, p99.value, matched.value, "
          "l.value, (SELECT count(*) FROM samples s WHERE s.run_id = r.id) FROM runs r "
          "JOIN metrics p50 ON p50.run_id = r.id AND p50.name = 'latency.p50' "
          "JOIN metrics p99 ON p99.run_id = r.id AND p99.name = 'latency.p99' "
          "JOIN metrics matched ON matched.run_id = r.id AND matched.name = 'count.matched' "
          "JOIN labels l ON l.run_id = r.id AND l.key = 'batch' WHERE r.file = '" +
          file + "'");
      ASSERT_EQ(row.size(), 1u);
      EXPECT_EQ(row[0][0], run.valid ? "t" : "f");
      EXPECT_EQ(row[0][1], run.rmw);
      EXPECT_EQ(row[0][2], run.started_utc);
      EXPECT_EQ(std::stod(row[0][3]), run.latency.p50);
      EXPECT_EQ(std::stod(row[0][4]), run.latency.p99);
      EXPECT_EQ(std::stod(row[0][5]), static_cast<double>(run.matched));
      EXPECT_EQ(row[0][6], folder.filename().string());
      EXPECT_EQ(row[0][7], run.csv_path ? std::to_string(run.matched) : "0");
    }
  }
  EXPECT_EQ(files, std::size_t{kProcesses * kRunsEach + kShared});
  EXPECT_EQ(query("SELECT count(*), count(DISTINCT file) FROM runs"),
            (Rows{{std::to_string(files), std::to_string(files)}}));
  EXPECT_EQ(query("SELECT version FROM schema_version"), (Rows{{"1"}}));
}

TEST_F(ResultsDbPostgresCli, PushingTwiceIsIdempotentAndSkippedFilesAreNamed) {
  const fs::path dir = write_runs("results", 0, 5);
  std::ofstream(dir / "broken.json") << "{";
  const auto first = robotperf_cli("results push --to " + url() + " " + dir.string());
  ASSERT_EQ(first.exit_code, 0) << first.out;
  EXPECT_NE(first.out.find(url() + ": pushed 5 run(s), 1 file(s) skipped"), std::string::npos)
      << first.out;
  EXPECT_NE(
      first.out.find("robotperf: skipped " + (dir / "broken.json").string() + ": not valid JSON"),
      std::string::npos)
      << first.out;
  const std::string everything =
      "SELECT r.id, r.file, r.document_sha256, (SELECT count(*) FROM metrics m WHERE m.run_id = "
      "r.id), (SELECT count(*) FROM samples s WHERE s.run_id = r.id), (SELECT count(*) FROM "
      "histogram h WHERE h.run_id = r.id) FROM runs r ORDER BY r.id";
  const Rows pushed = query(everything);
  ASSERT_EQ(pushed.size(), 5u);

  // Again, the folder through the environment variable and one of its files named as well.
  const auto again =
      robotperf_cli("results push " + dir.string() + " " + (dir / pushed[0][1]).string(),
                    "ROBOTPERF_RESULTS_URL=" + url());
  ASSERT_EQ(again.exit_code, 0) << again.out;
  EXPECT_NE(again.out.find(": pushed 5 run(s)"), std::string::npos) << again.out;
  EXPECT_EQ(query(everything), pushed);
}

TEST_F(ResultsDbPostgresCli, ReadVerbsFromTheDatabaseShowWhatTheFilesShow) {
  const fs::path dir = write_runs("results", 0, 6);
  ASSERT_EQ(robotperf_cli("results push --to " + url() + " " + dir.string()).exit_code, 0);

  const auto files = robotperf_cli("results list " + dir.string());
  ASSERT_EQ(files.exit_code, 0) << files.out;
  EXPECT_NE(files.out.find("a1-intra-"), std::string::npos) << files.out;
  const auto from = robotperf_cli("results list --from " + url());
  EXPECT_EQ(from.exit_code, 0) << from.out;
  EXPECT_EQ(from.out, files.out);
  const auto by_environment = robotperf_cli("results list", "ROBOTPERF_RESULTS_URL=" + url());
  EXPECT_EQ(by_environment.out, files.out);
  // A folder named beats the environment variable: this one holds no runs.
  fs::create_directories(server_->dir() / "empty");
  const auto folder_first = robotperf_cli("results list " + (server_->dir() / "empty").string(),
                                          "ROBOTPERF_RESULTS_URL=" + url());
  EXPECT_EQ(folder_first.exit_code, 0) << folder_first.out;
  EXPECT_EQ(folder_first.out.find("a1-intra-"), std::string::npos) << folder_first.out;
  // And beats --from, saying so.
  const auto both =
      robotperf_cli("results list " + (server_->dir() / "empty").string() + " --from " + url());
  EXPECT_EQ(both.exit_code, 0) << both.out;
  EXPECT_EQ(both.out.find("a1-intra-"), std::string::npos) << both.out;
  EXPECT_NE(both.out.find("robotperf: reading the results named; --from is left aside"),
            std::string::npos)
      << both.out;

  const std::string sides = "compare rmw=intra rmw=fastdds ";
  const auto compared_files = robotperf_cli(sides + "--results " + dir.string());
  ASSERT_EQ(compared_files.exit_code, 0) << compared_files.out;
  EXPECT_EQ(robotperf_cli(sides + "--from " + url()).out, compared_files.out);

  const auto history_files = robotperf_cli("history a1 --format json --results " + dir.string());
  ASSERT_EQ(history_files.exit_code, 0) << history_files.out;
  const auto history_from = robotperf_cli("history a1 --format json --from " + url());
  ASSERT_EQ(history_from.exit_code, 0) << history_from.out;
  // The same points; a point's files are named without their folder either way.
  EXPECT_EQ(nlohmann::json::parse(history_from.out), nlohmann::json::parse(history_files.out));

  const fs::path md = server_->dir() / "report.md";
  const auto reported = robotperf_cli("report --from " + url() + " --md " + md.string());
  ASSERT_EQ(reported.exit_code, 0) << reported.out;
  std::ifstream in(md);
  const std::string report{std::istreambuf_iterator<char>(in), {}};
  const auto first = robotperf::report::scan_results(dir).runs.front();
  EXPECT_NE(report.find(first.stem()), std::string::npos);
}

// Needs no server: the URL is refused before any connection.
TEST(ResultsDbPostgresCliUrl, AUrlWithAPasswordIsRefusedInOneLineThatDoesNotRepeatIt) {
  for (const std::string& verb :
       {std::string("results push --to "), std::string("results list --from "),
        std::string("compare a b --from "), std::string("report --md - --from "),
        std::string("history a1 --from ")}) {
    const auto o = robotperf_cli(verb + "postgresql://ci:s3cret-pw@127.0.0.1:1/results");
    EXPECT_EQ(o.exit_code, 2) << verb << o.out;
    EXPECT_EQ(o.out.find("s3cret"), std::string::npos) << o.out;
    EXPECT_NE(o.out.find("holds a password: give it with PGPASSWORD or a password file"),
              std::string::npos)
        << o.out;
    EXPECT_EQ(std::count(o.out.begin(), o.out.end(), '\n'), 1) << o.out;
  }
}

// Over TCP the server asks for the password (scram-sha-256): a password file gives it, and it
// is in no output nor in the database; without it, or with an sslmode this server cannot give,
// the connection is refused in one line that names the database.
TEST_F(ResultsDbPostgresCli, CredentialsFromAPasswordFileWorkAndAreShownNowhere) {
  const fs::path dir = write_runs("results", 0, 3);
  const fs::path passfile = server_->dir() / "pgpass";
  std::ofstream(passfile) << "127.0.0.1:" << server_->port() << ":results:" << PostgresServer::kUser
                          << ":" << server_->password() << "\n";
  ASSERT_EQ(chmod(passfile.c_str(), 0600), 0);
  const std::string tcp = server_->tcp_url("results");
  const std::string with_file = "PGPASSFILE=" + passfile.string();

  std::string outputs;
  const auto pushed = robotperf_cli("results push --to " + tcp + " " + dir.string(), with_file);
  outputs += pushed.out;
  ASSERT_EQ(pushed.exit_code, 0) << pushed.out;
  EXPECT_NE(pushed.out.find(tcp + ": pushed 3 run(s)"), std::string::npos) << pushed.out;
  const auto listed = robotperf_cli("results list --format json --from " + tcp, with_file);
  outputs += listed.out;
  EXPECT_EQ(listed.exit_code, 0) << listed.out;
  const fs::path html = server_->dir() / "report.html";
  const auto reported =
      robotperf_cli("report --from " + tcp + " --html " + html.string(), with_file);
  EXPECT_EQ(reported.exit_code, 0) << reported.out;
  std::ifstream in(html);
  outputs += reported.out + std::string{std::istreambuf_iterator<char>(in), {}};
  EXPECT_EQ(outputs.find(server_->password()), std::string::npos);
  EXPECT_EQ(
      query("SELECT count(*) FROM runs WHERE document::TEXT LIKE '%" + server_->password() + "%'"),
      (Rows{{"0"}}));

  // Nothing to answer the server's question with (no password file, no PGPASSWORD).
  const auto refused = robotperf_cli("results list --from " + tcp,
                                     "PGPASSFILE=" + (server_->dir() / "none").string());
  EXPECT_EQ(refused.exit_code, 2) << refused.out;
  EXPECT_TRUE(refused.out.starts_with("robotperf: " + tcp + ": cannot connect: ")) << refused.out;
  EXPECT_EQ(std::count(refused.out.begin(), refused.out.end(), '\n'), 1) << refused.out;

  // sslmode reaches libpq: this server has no TLS, so "require" cannot be met.
  const auto tls = robotperf_cli("results list --from " + tcp + "?sslmode=require", with_file);
  EXPECT_EQ(tls.exit_code, 2) << tls.out;
  EXPECT_NE(tls.out.find("SSL"), std::string::npos) << tls.out;
  EXPECT_EQ(tls.out.find(server_->password()), std::string::npos);
}

}  // namespace
