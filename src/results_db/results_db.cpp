#include "robotperf/results_db/results_db.hpp"

#include <sqlite3.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <iterator>
#include <set>
#include <type_traits>
#include <variant>

#include "robotperf/report/run_metrics.hpp"
#include "robotperf/report/run_store.hpp"
#include "run_rows.hpp"

namespace robotperf::results_db {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// How long a writer waits for another process's transaction before it gives up: a run records
// in milliseconds, so only a stuck process makes anyone wait this long.
constexpr int kBusyTimeoutMs = 10'000;

// kMigrations[v] takes a database from schema version v to v + 1 (version 0: a new, empty file).
// A released migration never changes; a schema change is a new one at the end. 1: the tables;
// 2: the whole results document, so that a run reads back as its file (NULL for runs recorded
// before).
constexpr const char* kMigrations[] = {R"sql(
CREATE TABLE runs (
  id INTEGER PRIMARY KEY,
  file TEXT NOT NULL UNIQUE,
  benchmark_id TEXT NOT NULL,
  benchmark_name TEXT NOT NULL,
  category TEXT NOT NULL,
  started_utc TEXT NOT NULL,
  valid INTEGER NOT NULL,
  invalid_reasons TEXT NOT NULL,
  functional TEXT NOT NULL,
  mode TEXT NOT NULL,
  rmw TEXT NOT NULL,
  processes TEXT NOT NULL,
  backend TEXT NOT NULL,
  arrivals TEXT NOT NULL,
  monitor_wait TEXT NOT NULL,
  rate_hz REAL,
  throughput_kind TEXT NOT NULL,
  dataset TEXT NOT NULL,
  hardware TEXT NOT NULL,
  hardware_category TEXT NOT NULL,
  robotperf_version TEXT NOT NULL,
  git_revision TEXT NOT NULL,
  machine TEXT NOT NULL,
  software TEXT NOT NULL,
  configuration TEXT NOT NULL,
  configuration_key TEXT NOT NULL,
  samples_source TEXT NOT NULL
);
CREATE INDEX runs_by_benchmark_and_time ON runs (benchmark_id, started_utc);
CREATE INDEX runs_by_configuration ON runs (configuration_key, started_utc);
CREATE INDEX runs_by_time ON runs (started_utc);
CREATE TABLE metrics (
  run_id INTEGER NOT NULL REFERENCES runs (id) ON DELETE CASCADE,
  name TEXT NOT NULL,
  value REAL NOT NULL,
  unit TEXT NOT NULL,
  low REAL,
  high REAL,
  PRIMARY KEY (run_id, name)
) WITHOUT ROWID;
CREATE INDEX metrics_by_name ON metrics (name, run_id);
CREATE TABLE labels (
  run_id INTEGER NOT NULL REFERENCES runs (id) ON DELETE CASCADE,
  key TEXT NOT NULL,
  value TEXT NOT NULL,
  PRIMARY KEY (run_id, key)
) WITHOUT ROWID;
CREATE INDEX labels_by_key_and_value ON labels (key, value);
CREATE TABLE samples (
  run_id INTEGER NOT NULL REFERENCES runs (id) ON DELETE CASCADE,
  seq INTEGER NOT NULL,
  latency_ns INTEGER NOT NULL,
  PRIMARY KEY (run_id, seq)
) WITHOUT ROWID;
CREATE TABLE histogram (
  run_id INTEGER NOT NULL REFERENCES runs (id) ON DELETE CASCADE,
  lower_ns REAL,
  upper_ns REAL NOT NULL,
  count INTEGER NOT NULL,
  PRIMARY KEY (run_id, upper_ns)
) WITHOUT ROWID;
)sql",
                                       R"sql(
ALTER TABLE runs ADD COLUMN document TEXT;
ALTER TABLE runs ADD COLUMN warnings TEXT;
ALTER TABLE metrics ADD COLUMN better TEXT;
)sql"};
static_assert(std::size(kMigrations) == kSchemaVersion);

[[noreturn]] void fail(sqlite3* db, const fs::path& path, const std::string& doing) {
  throw DatabaseError(path.string() + ": " + doing + ": " + sqlite3_errmsg(db));
}

void exec(sqlite3* db, const fs::path& path, const std::string& sql) {
  if (sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr) != SQLITE_OK)
    fail(db, path, "cannot run \"" + sql.substr(0, sql.find('\n', 1)) + "\"");
}

class Statement {
 public:
  Statement(sqlite3* db, const fs::path& path, const std::string& sql) : db_(db), path_(path) {
    if (sqlite3_prepare_v2(db, sql.c_str(), -1, &statement_, nullptr) != SQLITE_OK)
      fail(db, path, "cannot prepare \"" + sql + "\"");
  }
  ~Statement() { sqlite3_finalize(statement_); }
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;

  Statement& text(int i, const std::string& v) {
    return check(
        sqlite3_bind_text(statement_, i, v.data(), static_cast<int>(v.size()), SQLITE_TRANSIENT));
  }
  Statement& integer(int i, std::int64_t v) { return check(sqlite3_bind_int64(statement_, i, v)); }
  Statement& null(int i) { return check(sqlite3_bind_null(statement_, i)); }
  // NaN and infinities are no value: NULL.
  Statement& real(int i, double v) {
    return check(std::isfinite(v) ? sqlite3_bind_double(statement_, i, v)
                                  : sqlite3_bind_null(statement_, i));
  }

  // True while there is a row to read.
  bool step() {
    const int rc = sqlite3_step(statement_);
    if (rc == SQLITE_ROW) return true;
    if (rc != SQLITE_DONE) fail(db_, path_, "cannot execute \"" + std::string(sql()) + "\"");
    return false;
  }
  // Executes a statement that returns no rows, and readies it for the next values.
  void execute() {
    step();
    sqlite3_reset(statement_);
    sqlite3_clear_bindings(statement_);
  }

  std::string text(int column) const {
    const auto* t = sqlite3_column_text(statement_, column);
    return t ? reinterpret_cast<const char*>(t) : "";
  }
  std::int64_t integer(int column) const { return sqlite3_column_int64(statement_, column); }
  double real(int column) const { return sqlite3_column_double(statement_, column); }
  std::optional<double> optional_real(int column) const {
    if (sqlite3_column_type(statement_, column) == SQLITE_NULL) return std::nullopt;
    return real(column);
  }

 private:
  const char* sql() const { return sqlite3_sql(statement_); }
  Statement& check(int rc) {
    if (rc != SQLITE_OK) fail(db_, path_, "cannot bind a value to \"" + std::string(sql()) + "\"");
    return *this;
  }
  sqlite3* db_;
  const fs::path& path_;
  sqlite3_stmt* statement_ = nullptr;
};

// A transaction that rolls back unless committed. BEGIN IMMEDIATE takes the write lock at once,
// waiting for it under the busy timeout; a deferred transaction that reads first could fail at
// its first write without waiting, when another process wrote in between.
class Transaction {
 public:
  Transaction(sqlite3* db, const fs::path& path) : db_(db), path_(path) {
    exec(db, path, "BEGIN IMMEDIATE");
  }
  ~Transaction() {
    if (!committed_) sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
  }
  Transaction(const Transaction&) = delete;
  Transaction& operator=(const Transaction&) = delete;
  void commit() {
    exec(db_, path_, "COMMIT");
    committed_ = true;
  }

 private:
  sqlite3* db_;
  const fs::path& path_;
  bool committed_ = false;
};

int user_version(sqlite3* db, const fs::path& path) {
  Statement s(db, path, "PRAGMA user_version");
  if (!s.step()) fail(db, path, "cannot read the schema version");
  return static_cast<int>(s.integer(0));
}

void refuse_unknown(int version, const fs::path& path) {
  if (version >= 0 && version <= kSchemaVersion) return;
  throw DatabaseError(path.string() + ": schema version " + std::to_string(version) +
                      " is not one this robotperf knows (up to " + std::to_string(kSchemaVersion) +
                      "): robotperf results rebuild-db " + path.parent_path().string() +
                      " makes it again from the results files");
}

void migrate(sqlite3* db, const fs::path& path) {
  int version = user_version(db, path);
  refuse_unknown(version, path);
  if (version == kSchemaVersion) return;
  Transaction t(db, path);
  // Another process may have migrated it while this one waited for the lock.
  version = user_version(db, path);
  refuse_unknown(version, path);
  for (; version < kSchemaVersion; ++version) exec(db, path, kMigrations[version]);
  exec(db, path, "PRAGMA user_version = " + std::to_string(kSchemaVersion));
  t.commit();
}

// A database file and the log files SQLite may keep beside it.
void remove_with_logs(const fs::path& path) {
  std::error_code ignored;
  for (const char* suffix : {"", "-wal", "-shm", "-journal"})
    fs::remove(path.string() + suffix, ignored);
}

// Where the results file is, as the runs table keeps it: relative to the database's folder when
// it is inside it (the folder can move), else absolute.
std::string file_column(const fs::path& database, const fs::path& file) {
  const fs::path folder = fs::absolute(database).parent_path().lexically_normal();
  const fs::path absolute = fs::absolute(file).lexically_normal();
  const fs::path relative = absolute.lexically_relative(folder);
  if (relative.empty() || *relative.begin() == "..") return absolute.string();
  return relative.string();
}

// The run's rows, inside the caller's transaction.
void insert_run(sqlite3* db, const fs::path& path, const fs::path& json_file,
                const detail::RunRows& rows) {
  const std::string file = file_column(path, json_file);
  Statement remove(db, path, "DELETE FROM runs WHERE file = ?");
  remove.text(1, file).execute();
  std::string columns = "file", values = "?";
  for (const detail::Column& c : rows.run) {
    columns += std::string(", ") + c.name;
    values += ", ?";
  }
  Statement insert(db, path, "INSERT INTO runs (" + columns + ") VALUES (" + values + ")");
  insert.text(1, file);
  for (std::size_t i = 0; i < rows.run.size(); ++i) {
    const int index = static_cast<int>(i) + 2;
    std::visit(
        [&](const auto& v) {
          using T = std::decay_t<decltype(v)>;
          if constexpr (std::is_same_v<T, std::string>)
            insert.text(index, v);
          else if constexpr (std::is_same_v<T, std::int64_t>)
            insert.integer(index, v);
          else if constexpr (std::is_same_v<T, double>)
            insert.real(index, v);
          else
            insert.text(index, v.text);
        },
        rows.run[i].value);
  }
  insert.execute();
  const std::int64_t id = sqlite3_last_insert_rowid(db);

  Statement metric(db, path,
                   "INSERT INTO metrics (run_id, name, value, unit, low, high, better) "
                   "VALUES (?, ?, ?, ?, ?, ?, ?)");
  for (const detail::Metric& m : rows.metrics) {
    metric.integer(1, id).text(2, m.name).real(3, m.value).text(4, m.unit).real(5, m.low);
    metric.real(6, m.high);
    if (const std::string better = report::better_text(m.better); better.empty())
      metric.null(7);
    else
      metric.text(7, better);
    metric.execute();
  }
  Statement label(db, path, "INSERT INTO labels (run_id, key, value) VALUES (?, ?, ?)");
  for (const auto& [key, value] : rows.labels)
    label.integer(1, id).text(2, key).text(3, value).execute();
  Statement sample(db, path, "INSERT INTO samples (run_id, seq, latency_ns) VALUES (?, ?, ?)");
  for (std::size_t i = 0; i < rows.samples_ns.size(); ++i)
    sample.integer(1, id)
        .integer(2, static_cast<std::int64_t>(i))
        .integer(3, rows.samples_ns[i])
        .execute();
  Statement bin(db, path,
                "INSERT INTO histogram (run_id, lower_ns, upper_ns, count) VALUES (?, ?, ?, ?)");
  for (const HistogramBin& b : rows.histogram)
    bin.integer(1, id)
        .real(2, b.lower_ns.value_or(std::nan("")))
        .real(3, b.upper_ns)
        .integer(4, b.count)
        .execute();
}

}  // namespace

void Database::Closer::operator()(sqlite3* db) const {
  sqlite3_close_v2(db);
}

Database::Database(std::unique_ptr<sqlite3, Closer> db, fs::path path)
    : db_(std::move(db)), path_(std::move(path)) {}
Database::Database(Database&&) noexcept = default;
Database& Database::operator=(Database&&) noexcept = default;
Database::~Database() = default;

Database Database::open(const fs::path& path) {
  // A new database is made whole (schema, WAL mode) in a file of this process's own, then linked
  // into place. Processes that start together thus never switch one new file to WAL at once,
  // which SQLite may refuse at once, busy timeout or not (each holds a read lock and wants the
  // file to itself).
  if (!fs::exists(path)) {
    const fs::path fresh = path.string() + "." + std::to_string(getpid()) + ".new";
    remove_with_logs(fresh);
    open_file(fresh);  // closed at once: its log files go with its last connection
    // Not linked: another process's was linked first (EEXIST), and it is the one used; or the file
    // system has no hard links, and open_file makes the database in place.
    [[maybe_unused]] const int linked = ::link(fresh.c_str(), path.c_str());
    remove_with_logs(fresh);
  }
  return open_file(path);
}

Database Database::open_file(const fs::path& path) {
  sqlite3* raw = nullptr;
  const int rc =
      sqlite3_open_v2(path.c_str(), &raw, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, nullptr);
  std::unique_ptr<sqlite3, Closer> db(raw);
  if (rc != SQLITE_OK)
    throw DatabaseError(path.string() + ": cannot open the results database: " +
                        (raw ? sqlite3_errmsg(raw) : sqlite3_errstr(rc)));
  sqlite3_busy_timeout(raw, kBusyTimeoutMs);
  exec(raw, path, "PRAGMA foreign_keys = ON");
  {
    // Readers do not block the writer nor it them; the mode is kept in the file. (A block: the
    // statement is finished before migrate's transaction, which it would keep from committing.)
    Statement mode(raw, path, "PRAGMA journal_mode = WAL");
    if (!mode.step() || mode.text(0) != "wal")
      throw DatabaseError(path.string() + ": cannot use write-ahead logging (journal mode " +
                          mode.text(0) + ")");
  }
  migrate(raw, path);
  return Database(std::move(db), path);
}

void Database::record(const json& result, const fs::path& json_file) {
  // Read as the file's text reads (NaN as null, odd bytes replaced), so that recording and
  // rebuilding from the file give the same rows.
  const report::StoredRun run =
      report::run_from_json(json::parse(detail::json_text(result)), json_file);
  const detail::RunRows rows = detail::rows_of(run);
  Transaction t(db_.get(), path_);
  insert_run(db_.get(), path_, json_file, rows);
  t.commit();
}

std::vector<RunRow> Database::runs(const RunQuery& query) const {
  std::string sql =
      "SELECT id, file, benchmark_id, benchmark_name, category, started_utc, valid, mode, rmw, "
      "processes, backend, arrivals, monitor_wait, rate_hz, hardware, configuration_key, "
      "robotperf_version, git_revision, samples_source FROM runs WHERE 1";
  std::vector<std::string> values;
  auto where = [&](const std::string& value, const char* condition) {
    if (value.empty()) return;
    sql += condition;
    values.push_back(value);
  };
  where(query.benchmark_id, " AND benchmark_id = ?");
  where(query.configuration_key, " AND configuration_key = ?");
  where(query.since_utc, " AND started_utc >= ?");
  where(query.until_utc, " AND started_utc < ?");
  for (const auto& [key, value] : query.labels) {
    sql += " AND EXISTS (SELECT 1 FROM labels WHERE run_id = runs.id AND key = ? AND value = ?)";
    values.push_back(key);
    values.push_back(value);
  }
  sql += " ORDER BY started_utc, file";
  Statement s(db_.get(), path_, sql);
  for (std::size_t i = 0; i < values.size(); ++i) s.text(static_cast<int>(i) + 1, values[i]);
  std::vector<RunRow> out;
  while (s.step()) {
    RunRow r;
    r.id = s.integer(0);
    r.file = s.text(1);
    r.benchmark_id = s.text(2);
    r.benchmark_name = s.text(3);
    r.category = s.text(4);
    r.started_utc = s.text(5);
    r.valid = s.integer(6) != 0;
    r.mode = s.text(7);
    r.rmw = s.text(8);
    r.processes = s.text(9);
    r.backend = s.text(10);
    r.arrivals = s.text(11);
    r.monitor_wait = s.text(12);
    r.rate_hz = s.optional_real(13);
    r.hardware = s.text(14);
    r.configuration_key = s.text(15);
    r.robotperf_version = s.text(16);
    r.git_revision = s.text(17);
    r.samples_source = s.text(18);
    out.push_back(std::move(r));
  }
  return out;
}

std::vector<MetricRow> Database::metrics(std::int64_t run) const {
  Statement s(db_.get(), path_,
              "SELECT name, value, unit, low, high, better FROM metrics WHERE run_id = ? ORDER BY "
              "name");
  s.integer(1, run);
  std::vector<MetricRow> out;
  while (s.step())
    out.push_back(
        {s.text(0), s.real(1), s.text(2), s.optional_real(3), s.optional_real(4), s.text(5)});
  return out;
}

std::optional<MetricRow> Database::metric(std::int64_t run, const std::string& name) const {
  Statement s(db_.get(), path_,
              "SELECT name, value, unit, low, high, better FROM metrics WHERE run_id = ? AND "
              "name = ?");
  s.integer(1, run).text(2, name);
  if (!s.step()) return std::nullopt;
  return MetricRow{s.text(0),          s.real(1),          s.text(2),
                   s.optional_real(3), s.optional_real(4), s.text(5)};
}

std::vector<std::int64_t> Database::samples_ns(std::int64_t run) const {
  Statement s(db_.get(), path_, "SELECT latency_ns FROM samples WHERE run_id = ? ORDER BY seq");
  s.integer(1, run);
  std::vector<std::int64_t> out;
  while (s.step()) out.push_back(s.integer(0));
  return out;
}

std::vector<HistogramBin> Database::histogram(std::int64_t run) const {
  Statement s(db_.get(), path_,
              "SELECT lower_ns, upper_ns, count FROM histogram WHERE run_id = ? ORDER BY upper_ns");
  s.integer(1, run);
  std::vector<HistogramBin> out;
  while (s.step()) out.push_back({s.optional_real(0), s.real(1), s.integer(2)});
  return out;
}

std::map<std::string, std::string> Database::labels(std::int64_t run) const {
  Statement s(db_.get(), path_, "SELECT key, value FROM labels WHERE run_id = ?");
  s.integer(1, run);
  std::map<std::string, std::string> out;
  while (s.step()) out.emplace(s.text(0), s.text(1));
  return out;
}

std::vector<report::StoredRun> Database::listed_runs() const {
  const fs::path folder = path_.parent_path();
  std::vector<report::StoredRun> out;
  std::map<std::int64_t, std::size_t> index;  // run id -> its place in out
  {
    // An INVALID run's reasons come from its document, exactly as the file has them: the column
    // joins them with "; ", which a reason may hold itself.
    Statement s(db_.get(), path_,
                "SELECT id, file, benchmark_id, benchmark_name, category, started_utc, valid, "
                "CASE WHEN valid THEN NULL ELSE json_extract(document, '$.validity.reasons') END, "
                "functional, mode, rmw, processes, backend, arrivals, monitor_wait, rate_hz, "
                "throughput_kind, dataset, hardware, hardware_category, robotperf_version, "
                "git_revision, warnings FROM runs ORDER BY started_utc, file");
    while (s.step()) {
      report::StoredRun r;
      r.path = folder / s.text(1);
      r.benchmark_id = s.text(2);
      r.benchmark_name = s.text(3);
      r.category = s.text(4);
      r.started_utc = s.text(5);
      r.valid = s.integer(6) != 0;
      if (!r.valid) {
        const json reasons = json::parse(s.text(7), nullptr, false);
        if (reasons.is_array()) {
          for (const auto& reason : reasons) {
            if (reason.is_string()) r.invalid_reasons.push_back(reason.get<std::string>());
          }
        }
      }
      r.functional = s.text(8);
      r.type = s.text(9);
      r.rmw = s.text(10);
      r.processes = s.text(11);
      r.backend = s.text(12) == "cpu" ? "" : s.text(12);
      r.timeline = s.text(13);
      r.monitor_wait = s.text(14);
      r.rate_hz = s.optional_real(15).value_or(report::kNoValue);
      r.throughput_kind = s.text(16);
      r.dataset = s.text(17);
      r.hardware = s.text(18);
      r.hardware_category = s.text(19);
      r.robotperf_version = s.text(20);
      r.git_revision = s.text(21);
      const json warnings = json::parse(s.text(22), nullptr, false);
      if (warnings.is_array()) {
        for (const auto& w : warnings) {
          if (w.is_string()) r.warnings.push_back(w.get<std::string>());
        }
      }
      index.emplace(s.integer(0), out.size());
      out.push_back(std::move(r));
    }
  }
  // The figures the list shows, into the fields the results file fills.
  Statement m(db_.get(), path_,
              "SELECT run_id, name, value, low, high FROM metrics WHERE name IN ('latency.min', "
              "'latency.mean', 'latency.rms', 'latency.stddev', 'latency.p50', 'latency.p90', "
              "'latency.p99', 'latency.p999', 'latency.max', 'count.measured', 'count.matched', "
              "'count.lost', 'count.unobserved', 'loss', 'throughput', 'throughput.offered', "
              "'power', 'energy', 'cpu', 'peak_rss', 'control.update_rate')");
  while (m.step()) {
    const auto at = index.find(m.integer(0));
    if (at == index.end()) continue;
    report::StoredRun& r = out[at->second];
    const std::string name = m.text(1);
    const double v = m.real(2);
    auto count = [v] { return static_cast<std::size_t>(std::llround(v)); };
    report::LatencySummary& l = r.latency;
    if (name == "latency.p50") {
      l.p50 = v;
      l.p50_lower = m.optional_real(3).value_or(report::kNoValue);
      l.p50_upper = m.optional_real(4).value_or(report::kNoValue);
    } else if (name.starts_with("latency.")) {
      const std::string stat = name.substr(8);
      double* field = stat == "min"      ? &l.min
                      : stat == "mean"   ? &l.mean
                      : stat == "rms"    ? &l.rms
                      : stat == "stddev" ? &l.stddev
                      : stat == "p90"    ? &l.p90
                      : stat == "p99"    ? &l.p99
                      : stat == "p999"   ? &l.p999
                                         : &l.max;
      *field = v;
    } else if (name == "count.measured") {
      r.measured = count();
    } else if (name == "count.matched") {
      r.matched = count();
    } else if (name == "count.lost") {
      r.lost = count();
    } else if (name == "count.unobserved") {
      r.unobserved = count();
    } else if (name == "loss") {
      r.loss_percent = v;
    } else if (name == "throughput") {
      r.throughput_hz = v;
    } else if (name == "throughput.offered") {
      r.offered_hz = v;
    } else if (name == "power") {
      r.power_w = v;
    } else if (name == "energy") {
      r.energy_j = v;
    } else if (name == "cpu") {
      r.cpu_percent = v;
    } else if (name == "peak_rss") {
      r.peak_rss_mib = v;
    } else {
      r.update_rate_hz = v;
    }
  }
  Statement l(db_.get(), path_, "SELECT run_id, key, value FROM labels");
  while (l.step()) {
    const auto at = index.find(l.integer(0));
    if (at != index.end()) out[at->second].labels.emplace(l.text(1), l.text(2));
  }
  return out;
}

std::map<fs::path, MetricRow> Database::metric_of_runs(const std::string& name) const {
  Statement s(db_.get(), path_,
              "SELECT runs.file, metrics.name, metrics.value, metrics.unit, metrics.low, "
              "metrics.high, metrics.better FROM metrics JOIN runs ON runs.id = metrics.run_id "
              "WHERE metrics.name = ?");
  s.text(1, name);
  std::map<fs::path, MetricRow> out;
  const fs::path folder = path_.parent_path();
  while (s.step())
    out.emplace(folder / s.text(0), MetricRow{s.text(1), s.real(2), s.text(3), s.optional_real(4),
                                              s.optional_real(5), s.text(6)});
  return out;
}

std::vector<std::string> Database::metric_names(const std::string& benchmark_id) const {
  Statement s(db_.get(), path_,
              "SELECT DISTINCT metrics.name FROM metrics JOIN runs ON runs.id = metrics.run_id "
              "WHERE runs.benchmark_id = ? ORDER BY metrics.name");
  s.text(1, benchmark_id);
  std::vector<std::string> out;
  while (s.step()) out.push_back(s.text(0));
  return out;
}

int Database::schema_version() const {
  return user_version(db_.get(), path_);
}

Rebuilt rebuild(const fs::path& folder) {
  report::RunScan scan = report::scan_results(folder);
  Rebuilt out{folder / kDatabaseFile, 0, std::move(scan.skipped)};
  const fs::path temporary =
      folder / ("." + std::string(kDatabaseFile) + "." + std::to_string(getpid()) + ".tmp");
  remove_with_logs(temporary);
  try {
    {
      Database db = Database::open_file(temporary);
      Transaction all(db.db_.get(), temporary);
      for (const report::StoredRun& run : scan.runs) {
        detail::RunRows rows;
        try {
          rows = detail::rows_of(run);
        } catch (const report::ReportError& e) {
          out.skipped.push_back(run.path.string() + ": " + e.what());
          continue;
        }
        insert_run(db.db_.get(), temporary, run.path, rows);
        ++out.recorded;
      }
      all.commit();
    }
    // The database is closed: its log files are gone and the file holds everything. The old
    // database's log would be replayed into the new file: it goes first.
    for (const char* suffix : {"-wal", "-shm"}) fs::remove(out.database.string() + suffix);
    fs::rename(temporary, out.database);
  } catch (const fs::filesystem_error& e) {
    remove_with_logs(temporary);
    throw DatabaseError(out.database.string() +
                        ": cannot put the rebuilt database in place: " + e.what());
  } catch (...) {
    remove_with_logs(temporary);
    throw;
  }
  return out;
}

report::MetricSource metric_source(const Database& database) {
  auto by_name = std::make_shared<std::map<std::string, std::map<fs::path, MetricRow>>>();
  return {
      [&database, by_name](const report::StoredRun& run,
                           const std::string& name) -> std::optional<report::RunMetric> {
        auto rows = by_name->find(name);
        if (rows == by_name->end())
          rows = by_name->emplace(name, database.metric_of_runs(name)).first;
        const auto row = rows->second.find(run.path);
        if (row == rows->second.end()) return std::nullopt;
        const MetricRow& m = row->second;
        return report::RunMetric{m.name,
                                 m.value,
                                 m.unit,
                                 m.low.value_or(report::kNoValue),
                                 m.high.value_or(report::kNoValue),
                                 report::better_from_text(m.better)};
      },
      [&database](const std::string& benchmark_id) { return database.metric_names(benchmark_id); }};
}

std::optional<Synced> open_synced(const fs::path& folder) {
  const fs::path path = folder / kDatabaseFile;
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return std::nullopt;
  try {
    Synced out{Database::open_file(path), {}};
    sqlite3* db = out.database.db_.get();
    // What the database holds, and which of it needs its file read again.
    std::map<std::string, bool> recorded;  // file -> whole (document and warnings kept)
    {
      Statement s(db, path, "SELECT file, document IS NOT NULL AND warnings IS NOT NULL FROM runs");
      while (s.step()) recorded.emplace(s.text(0), s.integer(1) != 0);
    }
    std::vector<fs::path> to_record;
    std::set<std::string> present;
    // The files a scan of the folder reads (report::scan_results), and what it skips.
    for (const auto& entry : fs::directory_iterator(folder)) {
      if (!report::may_be_run_file(entry.path()) ||
          !report::is_regular_file_or_skip(entry, out.skipped))
        continue;
      const std::string file = file_column(path, entry.path());
      present.insert(file);
      const auto it = recorded.find(file);
      if (it == recorded.end() || !it->second) to_record.push_back(entry.path());
    }
    std::vector<std::string> gone;
    for (const auto& [file, whole] : recorded) {
      if (!present.contains(file)) gone.push_back(file);
    }
    // Files are read before the transaction, so that a slow disk holds no lock.
    std::vector<std::pair<fs::path, detail::RunRows>> rows;
    std::ranges::sort(to_record);
    for (const fs::path& file : to_record) {
      try {
        rows.emplace_back(file, detail::rows_of(report::load_run(file)));
      } catch (const report::ReportError& e) {
        out.skipped.push_back(e.what());
      }
    }
    if (rows.empty() && gone.empty()) return out;
    Transaction t(db, path);
    Statement remove(db, path, "DELETE FROM runs WHERE file = ?");
    for (const std::string& file : gone) remove.text(1, file).execute();
    for (const auto& [file, run_rows] : rows) insert_run(db, path, file, run_rows);
    t.commit();
    return out;
  } catch (const DatabaseError&) {
    return std::nullopt;  // a locked, damaged or read-only database: the files are read instead
  } catch (const fs::filesystem_error&) {
    return std::nullopt;
  }
}

}  // namespace robotperf::results_db
