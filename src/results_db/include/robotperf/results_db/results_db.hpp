// The results database: every run of a results folder also recorded in SQLite
// (<folder>/robotperf.db), for queries over many runs. The JSON files stay the record the
// database is made from: `rebuild` makes it again from them (docs/design.md §8).
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "robotperf/report/history.hpp"
#include "robotperf/report/run_store.hpp"

struct sqlite3;

namespace robotperf::results_db {

// The database's file name in a results folder.
inline constexpr const char* kDatabaseFile = "robotperf.db";
// The schema this robotperf writes (PRAGMA user_version); older databases are migrated on open.
inline constexpr int kSchemaVersion = 2;

// A database that cannot be opened, migrated, written or read; the message names its file.
class DatabaseError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// One row of the runs table.
struct RunRow {
  std::int64_t id = 0;
  std::string file;  // the results JSON, relative to the database's folder when inside it
  std::string benchmark_id, benchmark_name, category;
  std::string started_utc;  // "2026-11-22T07:42:22Z"
  bool valid = false;
  std::string mode, rmw, processes, backend, arrivals, monitor_wait;
  std::optional<double> rate_hz;
  std::string hardware, configuration_key, robotperf_version, git_revision;
  std::string samples_source;  // "csv", "histogram" or "none"
};

// One row of the metrics table: a figure of a run, with its 95 % interval where one is known.
struct MetricRow {
  std::string name;
  double value = 0;
  std::string unit;
  std::optional<double> low, high;
  std::string better;  // which way is better: "smaller", "larger", or "" (unknown)
};

// One bin of a run's latency histogram, in ns; the non-positive latencies are the bin with no
// lower edge.
struct HistogramBin {
  std::optional<double> lower_ns;
  double upper_ns = 0;
  std::int64_t count = 0;
};

// Which runs `Database::runs` returns; an empty field selects every run.
struct RunQuery {
  std::string benchmark_id, configuration_key;
  std::string since_utc, until_utc;  // started_utc >= since and < until ("2026-11-22T07:42:22Z")
  std::vector<std::pair<std::string, std::string>> labels;  // every (key, value) must be present
};

struct Rebuilt;
Rebuilt rebuild(const std::filesystem::path& folder);

class Database {
 public:
  // Opens the database at `path`, creating it, or migrating it from an older schema. WAL mode and
  // a busy timeout let several processes write to one database at once. Throws DatabaseError.
  static Database open(const std::filesystem::path& path);

  // Records the run `result` (a robotperf.result/1 document) written to `json_file`, in one
  // transaction; a run already recorded from that file is replaced. Latency samples come from the
  // .latencies.csv beside the file when there is one, else the histogram the result holds.
  // Throws DatabaseError, or report::ReportError for a result that is not a usable run.
  void record(const nlohmann::json& result, const std::filesystem::path& json_file);

  // Runs in start order (then file name).
  std::vector<RunRow> runs(const RunQuery& query = {}) const;
  std::vector<MetricRow> metrics(std::int64_t run) const;  // by name
  std::optional<MetricRow> metric(std::int64_t run, const std::string& name) const;
  std::vector<std::int64_t> samples_ns(std::int64_t run) const;  // in message order
  std::vector<HistogramBin> histogram(std::int64_t run) const;
  std::map<std::string, std::string> labels(std::int64_t run) const;

  // Every run with the fields `results list` and `history` read, from the runs, metrics and labels
  // tables, without reading a results file: for listing and choosing among many runs. Its `path`
  // is the file under the database's folder (as `file` names it), its `json` is empty, and what
  // only the file holds (per-hop and callback tables, peak steps, the histogram) is left out. In
  // start order, then file name.
  std::vector<report::StoredRun> listed_runs() const;
  // The figure `name` of each run that has it, keyed by the run's path as listed_runs gives it.
  std::map<std::filesystem::path, MetricRow> metric_of_runs(const std::string& name) const;
  // The names of the figures the runs of `benchmark_id` have.
  std::vector<std::string> metric_names(const std::string& benchmark_id) const;
  int schema_version() const;
  const std::filesystem::path& path() const { return path_; }

  Database(Database&&) noexcept;
  Database& operator=(Database&&) noexcept;
  ~Database();

 private:
  struct Closer {
    void operator()(sqlite3* db) const;
  };
  Database(std::unique_ptr<sqlite3, Closer> db, std::filesystem::path path);
  // Opens the file at `path` as it is, creating it there when it does not exist (open() makes a
  // new one beside it first).
  static Database open_file(const std::filesystem::path& path);
  friend Rebuilt rebuild(const std::filesystem::path& folder);
  friend std::optional<struct Synced> open_synced(const std::filesystem::path& folder);

  std::unique_ptr<sqlite3, Closer> db_;
  std::filesystem::path path_;
};

// What `rebuild` did.
struct Rebuilt {
  std::filesystem::path database;
  std::size_t recorded = 0;
  std::vector<std::string> skipped;  // one line per results file left out: the file and why
};

// Makes <folder>/robotperf.db again from every results file directly in `folder`: built in a
// temporary file beside it, then renamed over it, so that a reader sees the old database or the
// new one. Throws report::ReportError when `folder` does not exist, DatabaseError when the
// database cannot be written.
Rebuilt rebuild(const std::filesystem::path& folder);

// History's figures of the runs `database.listed_runs()` gives, from its metrics table (one query
// per figure asked for). The database must outlive the source.
report::MetricSource metric_source(const Database& database);

// A folder's database brought up to date with the folder's results files, for reading many runs
// without reading every file.
struct Synced {
  Database database;
  std::vector<std::string> skipped;  // results files that could not be recorded, and why
};

// Opens <folder>/robotperf.db and brings it up to date with the results files directly in
// `folder`, matched by name: files it does not hold yet (copied in, or written when the database
// could not take them) and runs recorded before the schema kept whole documents are recorded from
// their files; rows whose file is gone are removed. nullopt when the folder has no database, or
// it cannot be opened or written: the caller reads the files.
std::optional<Synced> open_synced(const std::filesystem::path& folder);

}  // namespace robotperf::results_db
