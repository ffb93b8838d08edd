#include "robotperf/results_db/results_db.hpp"

#include <sqlite3.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <iterator>
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
                   "INSERT INTO metrics (run_id, name, value, unit, low, high) "
                   "VALUES (?, ?, ?, ?, ?, ?)");
  for (const detail::Metric& m : rows.metrics) {
    metric.integer(1, id).text(2, m.name).real(3, m.value).text(4, m.unit).real(5, m.low);
    metric.real(6, m.high).execute();
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
              "SELECT name, value, unit, low, high FROM metrics WHERE run_id = ? ORDER BY name");
  s.integer(1, run);
  std::vector<MetricRow> out;
  while (s.step())
    out.push_back({s.text(0), s.real(1), s.text(2), s.optional_real(3), s.optional_real(4)});
  return out;
}

std::optional<MetricRow> Database::metric(std::int64_t run, const std::string& name) const {
  Statement s(db_.get(), path_,
              "SELECT name, value, unit, low, high FROM metrics WHERE run_id = ? AND name = ?");
  s.integer(1, run).text(2, name);
  if (!s.step()) return std::nullopt;
  return MetricRow{s.text(0), s.real(1), s.text(2), s.optional_real(3), s.optional_real(4)};
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

}  // namespace robotperf::results_db
