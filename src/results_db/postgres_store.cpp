#include "robotperf/results_db/postgres_store.hpp"

#include <libpq-fe.h>
#include <openssl/evp.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <iterator>
#include <optional>
#include <stdexcept>
#include <tuple>
#include <type_traits>
#include <variant>

#include "run_rows.hpp"

namespace robotperf::results_db {

namespace {

using nlohmann::json;

// kPostgresMigrations[v] takes a database from schema version v to v + 1 (version 0: no tables).
// A released migration never changes; a schema change is a new one at the end. The tables are the
// SQLite database's (results_db.cpp), in PostgreSQL's types, with the run's identity and its
// whole document.
constexpr const char* kPostgresMigrations[] = {R"sql(
CREATE TABLE runs (
  id BIGINT GENERATED ALWAYS AS IDENTITY PRIMARY KEY,
  file TEXT NOT NULL,
  document_sha256 TEXT NOT NULL,
  benchmark_id TEXT NOT NULL,
  benchmark_name TEXT NOT NULL,
  category TEXT NOT NULL,
  started_utc TEXT NOT NULL,
  valid BOOLEAN NOT NULL,
  invalid_reasons TEXT NOT NULL,
  functional TEXT NOT NULL,
  mode TEXT NOT NULL,
  rmw TEXT NOT NULL,
  processes TEXT NOT NULL,
  backend TEXT NOT NULL,
  arrivals TEXT NOT NULL,
  monitor_wait TEXT NOT NULL,
  rate_hz DOUBLE PRECISION,
  throughput_kind TEXT NOT NULL,
  dataset TEXT NOT NULL,
  hardware TEXT NOT NULL,
  hardware_category TEXT NOT NULL,
  robotperf_version TEXT NOT NULL,
  git_revision TEXT NOT NULL,
  machine JSONB NOT NULL,
  software JSONB NOT NULL,
  configuration JSONB NOT NULL,
  configuration_key TEXT NOT NULL,
  samples_source TEXT NOT NULL,
  warnings JSONB NOT NULL,
  document JSONB NOT NULL,
  UNIQUE (file, document_sha256)
);
CREATE INDEX runs_by_benchmark_and_time ON runs (benchmark_id, started_utc);
CREATE INDEX runs_by_configuration ON runs (configuration_key, started_utc);
CREATE INDEX runs_by_time ON runs (started_utc);
CREATE TABLE metrics (
  run_id BIGINT NOT NULL REFERENCES runs (id) ON DELETE CASCADE,
  name TEXT NOT NULL,
  value DOUBLE PRECISION NOT NULL,
  unit TEXT NOT NULL,
  low DOUBLE PRECISION,
  high DOUBLE PRECISION,
  better TEXT,
  PRIMARY KEY (run_id, name)
);
CREATE INDEX metrics_by_name ON metrics (name, run_id);
CREATE TABLE labels (
  run_id BIGINT NOT NULL REFERENCES runs (id) ON DELETE CASCADE,
  key TEXT NOT NULL,
  value TEXT NOT NULL,
  PRIMARY KEY (run_id, key)
);
CREATE INDEX labels_by_key_and_value ON labels (key, value);
CREATE TABLE samples (
  run_id BIGINT NOT NULL REFERENCES runs (id) ON DELETE CASCADE,
  seq BIGINT NOT NULL,
  latency_ns BIGINT NOT NULL,
  PRIMARY KEY (run_id, seq)
);
CREATE TABLE histogram (
  run_id BIGINT NOT NULL REFERENCES runs (id) ON DELETE CASCADE,
  lower_ns DOUBLE PRECISION,
  upper_ns DOUBLE PRECISION NOT NULL,
  count BIGINT NOT NULL,
  PRIMARY KEY (run_id, upper_ns)
);
)sql"};
static_assert(std::size(kPostgresMigrations) == kPostgresSchemaVersion);

// The advisory lock that migrations take, one per database ("robotper" in ASCII).
constexpr const char* kMigrationLock = "SELECT pg_advisory_xact_lock(8246204055208191346)";

// libpq's messages end in a newline and may run over several lines (a hint, the address tried):
// as one line, white space folded.
std::string one_line(const char* message) {
  std::string out;
  for (const char* c = message ? message : ""; *c; ++c) {
    if (std::isspace(static_cast<unsigned char>(*c))) {
      if (!out.empty() && out.back() != ' ') out += ' ';
    } else {
      out += *c;
    }
  }
  while (!out.empty() && out.back() == ' ') out.pop_back();
  return out;
}

struct ResultCloser {
  void operator()(PGresult* result) const { PQclear(result); }
};
using Result = std::unique_ptr<PGresult, ResultCloser>;

struct OptionsCloser {
  void operator()(PQconninfoOption* options) const { PQconninfoFree(options); }
};

// The first line of a statement, for messages.
std::string statement_name(const std::string& sql) {
  const std::size_t start = sql.find_first_not_of('\n');
  return sql.substr(start, sql.find('\n', start) - start);
}

// Runs `sql` with text parameters (nullopt: NULL); throws DatabaseError naming `target`. Without
// parameters it may be several statements (a migration).
Result exec(PGconn* c, const std::string& target, const std::string& sql,
            const std::vector<std::optional<std::string>>& parameters = {}) {
  std::vector<const char*> values;
  for (const auto& p : parameters) values.push_back(p ? p->c_str() : nullptr);
  Result r(values.empty() ? PQexec(c, sql.c_str())
                          : PQexecParams(c, sql.c_str(), static_cast<int>(values.size()), nullptr,
                                         values.data(), nullptr, nullptr, 0));
  const ExecStatusType status = PQresultStatus(r.get());
  if (status != PGRES_COMMAND_OK && status != PGRES_TUPLES_OK)
    throw DatabaseError(target + ": cannot run \"" + statement_name(sql) +
                        "\": " + one_line(r ? PQresultErrorMessage(r.get()) : PQerrorMessage(c)));
  return r;
}

std::string value(const Result& r, int row, int column) {
  return PQgetisnull(r.get(), row, column) ? "" : PQgetvalue(r.get(), row, column);
}

// Sends `rows` (COPY's text format) to `copy`, a COPY ... FROM STDIN.
void copy_in(PGconn* c, const std::string& target, const std::string& copy,
             const std::string& rows) {
  if (rows.empty()) return;
  Result started(PQexec(c, copy.c_str()));
  if (PQresultStatus(started.get()) != PGRES_COPY_IN)
    throw DatabaseError(target + ": cannot run \"" + copy + "\": " + one_line(PQerrorMessage(c)));
  if (PQputCopyData(c, rows.data(), static_cast<int>(rows.size())) != 1 ||
      PQputCopyEnd(c, nullptr) != 1)
    throw DatabaseError(target + ": cannot send the rows of \"" + copy +
                        "\": " + one_line(PQerrorMessage(c)));
  std::string error;
  while (Result r{PQgetResult(c)}) {
    if (PQresultStatus(r.get()) != PGRES_COMMAND_OK && error.empty())
      error = one_line(PQresultErrorMessage(r.get()));
  }
  if (!error.empty()) throw DatabaseError(target + ": cannot run \"" + copy + "\": " + error);
}

// A transaction that rolls back unless committed.
class Transaction {
 public:
  Transaction(PGconn* c, const std::string& target) : c_(c), target_(target) {
    exec(c, target, "BEGIN");
  }
  ~Transaction() {
    if (!committed_) Result(PQexec(c_, "ROLLBACK"));
  }
  Transaction(const Transaction&) = delete;
  Transaction& operator=(const Transaction&) = delete;
  void commit() {
    exec(c_, target_, "COMMIT");
    committed_ = true;
  }

 private:
  PGconn* c_;
  const std::string& target_;
  bool committed_ = false;
};

// The database as messages name it: a URL with the user, host, port and database the connection
// used, and no credentials. A Unix socket's folder is the host, percent-encoded as a URL has it.
std::string target_of(PGconn* c) {
  std::string host;
  for (const char* h = PQhost(c); h && *h; ++h)
    host += *h == '/' ? std::string("%2F") : std::string(1, *h);
  const std::string user = PQuser(c) ? PQuser(c) : "";
  const std::string port = PQport(c) ? PQport(c) : "";
  return "postgresql://" + (user.empty() ? "" : user + "@") + host +
         (port.empty() ? "" : ":" + port) + "/" + (PQdb(c) ? PQdb(c) : "");
}

int stored_version(PGconn* c, const std::string& target) {
  if (value(exec(c, target, "SELECT to_regclass('schema_version') IS NOT NULL"), 0, 0) != "t")
    return 0;
  const std::string version =
      value(exec(c, target, "SELECT coalesce(max(version), 0) FROM schema_version"), 0, 0);
  return std::stoi(version);
}

void refuse_unknown(int version, const std::string& target) {
  if (version >= 0 && version <= kPostgresSchemaVersion) return;
  throw DatabaseError(target + ": schema version " + std::to_string(version) +
                      " is not one this robotperf knows (up to " +
                      std::to_string(kPostgresSchemaVersion) +
                      "): push and read it with a newer robotperf");
}

void migrate(PGconn* c, const std::string& target) {
  // A database at the current version is only read: a role that may not create tables can read.
  int version = stored_version(c, target);
  refuse_unknown(version, target);
  if (version == kPostgresSchemaVersion) return;
  Transaction t(c, target);
  exec(c, target, kMigrationLock);
  exec(c, target, "CREATE TABLE IF NOT EXISTS schema_version (version INTEGER NOT NULL)");
  // Another process may have migrated it while this one waited for the lock.
  version = stored_version(c, target);
  refuse_unknown(version, target);
  if (version == kPostgresSchemaVersion) return;
  for (; version < kPostgresSchemaVersion; ++version) exec(c, target, kPostgresMigrations[version]);
  exec(c, target, "DELETE FROM schema_version");
  exec(c, target, "INSERT INTO schema_version (version) VALUES ($1)",
       {std::to_string(kPostgresSchemaVersion)});
  t.commit();
}

std::string sha256_hex(const std::string& text) {
  std::array<unsigned char, EVP_MAX_MD_SIZE> digest{};
  unsigned int size = 0;
  if (EVP_Digest(text.data(), text.size(), digest.data(), &size, EVP_sha256(), nullptr) != 1)
    throw DatabaseError("cannot compute a SHA-256 digest");
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  for (unsigned int i = 0; i < size; ++i) {
    out += kHex[digest[i] >> 4];
    out += kHex[digest[i] & 0xf];
  }
  return out;
}

// A real as PostgreSQL reads it back exactly (the shortest text that round-trips); nullopt for
// NaN and the infinities, which are no value.
std::optional<std::string> real_text(double v) {
  if (!std::isfinite(v)) return std::nullopt;
  std::array<char, 32> buffer{};
  const auto end = std::to_chars(buffer.data(), buffer.data() + buffer.size(), v).ptr;
  return std::string(buffer.data(), end);
}

std::optional<std::string> parameter(const detail::Column& column) {
  return std::visit(
      [](const auto& v) -> std::optional<std::string> {
        using T = std::decay_t<decltype(v)>;
        if constexpr (std::is_same_v<T, std::string>)
          return v;
        else if constexpr (std::is_same_v<T, std::int64_t>)
          return std::to_string(v);
        else if constexpr (std::is_same_v<T, double>)
          return real_text(v);
        else
          return v.text;
      },
      column.value);
}

// COPY's text format: fields separated by tabs, \N for NULL, backslash escapes.
class CopyRows {
 public:
  CopyRows& field(const std::string& text) {
    separate();
    for (char c : text) {
      switch (c) {
        case '\\':
          rows_ += "\\\\";
          break;
        case '\t':
          rows_ += "\\t";
          break;
        case '\n':
          rows_ += "\\n";
          break;
        case '\r':
          rows_ += "\\r";
          break;
        default:
          rows_ += c;
      }
    }
    return *this;
  }
  CopyRows& field(const std::optional<std::string>& text) {
    if (text) return field(*text);
    separate();
    rows_ += "\\N";
    return *this;
  }
  CopyRows& field(std::int64_t n) { return field(std::to_string(n)); }
  void end_row() {
    rows_ += '\n';
    first_ = true;
  }
  const std::string& text() const { return rows_; }

 private:
  void separate() {
    if (!first_) rows_ += '\t';
    first_ = false;
  }
  std::string rows_;
  bool first_ = true;
};

// A run to push: its identity, and where it is in push's list.
struct PushKey {
  std::string file, sha256;
  std::size_t index;
};

// One transaction: the batch's runs upserted in key order (so that two pushes of the same runs
// lock them in one order, and never deadlock), their old rows of the other tables dropped, and
// the new ones copied in.
void push_batch(PGconn* c, const std::string& target, const std::vector<PushKey>& keys,
                const std::vector<detail::RunRows>& rows) {
  std::string columns = "file, document_sha256", placeholders = "$1, $2", updates;
  int n = 2;
  for (const detail::Column& column : rows.front().run) {
    columns += std::string(", ") + column.name;
    placeholders += ", $" + std::to_string(++n);
    updates +=
        std::string(updates.empty() ? "" : ", ") + column.name + " = EXCLUDED." + column.name;
  }
  const std::string upsert = "INSERT INTO runs (" + columns + ") VALUES (" + placeholders +
                             ") ON CONFLICT (file, document_sha256) DO UPDATE SET " + updates +
                             " RETURNING id";
  Transaction t(c, target);
  std::vector<std::string> ids;
  for (std::size_t i = 0; i < keys.size(); ++i) {
    std::vector<std::optional<std::string>> parameters = {keys[i].file, keys[i].sha256};
    for (const detail::Column& column : rows[i].run) parameters.push_back(parameter(column));
    ids.push_back(value(exec(c, target, upsert, parameters), 0, 0));
  }
  std::string id_array = "{";
  for (const std::string& id : ids) id_array += (id_array.size() > 1 ? "," : "") + id;
  id_array += "}";
  for (const char* table : {"metrics", "labels", "samples", "histogram"})
    exec(c, target, std::string("DELETE FROM ") + table + " WHERE run_id = ANY($1::BIGINT[])",
         {id_array});

  CopyRows metrics, labels, samples, histogram;
  for (std::size_t i = 0; i < ids.size(); ++i) {
    const std::string& id = ids[i];
    for (const detail::Metric& m : rows[i].metrics) {
      metrics.field(id).field(m.name).field(real_text(m.value)).field(m.unit);
      const std::string better = report::better_text(m.better);
      metrics.field(real_text(m.low)).field(real_text(m.high));
      metrics.field(better.empty() ? std::nullopt : std::optional(better)).end_row();
    }
    for (const auto& [key, label] : rows[i].labels)
      labels.field(id).field(key).field(label).end_row();
    for (std::size_t seq = 0; seq < rows[i].samples_ns.size(); ++seq) {
      samples.field(id).field(static_cast<std::int64_t>(seq)).field(rows[i].samples_ns[seq]);
      samples.end_row();
    }
    for (const HistogramBin& b : rows[i].histogram) {
      histogram.field(id).field(b.lower_ns ? real_text(*b.lower_ns) : std::nullopt);
      histogram.field(real_text(b.upper_ns)).field(b.count).end_row();
    }
  }
  copy_in(c, target, "COPY metrics (run_id, name, value, unit, low, high, better) FROM STDIN",
          metrics.text());
  copy_in(c, target, "COPY labels (run_id, key, value) FROM STDIN", labels.text());
  copy_in(c, target, "COPY samples (run_id, seq, latency_ns) FROM STDIN", samples.text());
  copy_in(c, target, "COPY histogram (run_id, lower_ns, upper_ns, count) FROM STDIN",
          histogram.text());
  t.commit();
}

bool contains_password_text(const std::string& url) {
  // user:password@ in the authority, or a password= (sslpassword=) parameter.
  const std::size_t start = url.find("://") + 3;
  const std::size_t authority_end = url.find_first_of("/?", start);
  const std::string authority = url.substr(start, authority_end - start);
  const std::size_t at = authority.rfind('@');
  if (at != std::string::npos && authority.substr(0, at).find(':') != std::string::npos)
    return true;
  std::string lower = url;
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
  return lower.find("password=") != std::string::npos ||
         lower.find("password%3d") != std::string::npos;
}

}  // namespace

std::string checked_url(const std::string& url, const std::string& source) {
  if (!url.starts_with("postgresql://") && !url.starts_with("postgres://"))
    throw std::invalid_argument(source +
                                " takes a postgresql:// URL, such as "
                                "postgresql://robotperf@db.lab.example/robotperf");
  // The URL itself is never repeated here: it may hold the very password refused.
  const std::string refusal =
      source +
      " holds a password: give it with PGPASSWORD or a password file (~/.pgpass, or the file "
      "PGPASSFILE names), never in the URL";
  if (contains_password_text(url)) throw std::invalid_argument(refusal);
  char* error = nullptr;
  std::unique_ptr<PQconninfoOption, OptionsCloser> options(PQconninfoParse(url.c_str(), &error));
  if (!options) {
    const std::string why = one_line(error);
    PQfreemem(error);
    throw std::invalid_argument(source + " is not a URL libpq can read: " + why);
  }
  for (const PQconninfoOption* o = options.get(); o->keyword; ++o) {
    if ((std::string(o->keyword) == "password" || std::string(o->keyword) == "sslpassword") &&
        o->val)
      throw std::invalid_argument(refusal);
  }
  return url;
}

void PostgresStore::Closer::operator()(pg_conn* connection) const {
  PQfinish(connection);
}

PostgresStore::PostgresStore(std::unique_ptr<pg_conn, Closer> connection, std::string target)
    : connection_(std::move(connection)), target_(std::move(target)) {}
PostgresStore::PostgresStore(PostgresStore&&) noexcept = default;
PostgresStore& PostgresStore::operator=(PostgresStore&&) noexcept = default;
PostgresStore::~PostgresStore() = default;

PostgresStore PostgresStore::connect(const std::string& url) {
  std::unique_ptr<pg_conn, Closer> connection(PQconnectdb(url.c_str()));
  PGconn* c = connection.get();
  if (c == nullptr) throw ConnectionError("cannot connect to the results database: out of memory");
  std::string target = target_of(c);
  if (PQstatus(c) != CONNECTION_OK)
    throw ConnectionError(target + ": cannot connect: " + one_line(PQerrorMessage(c)));
  // The server's notices ("relation already exists, skipping") are no news for the user.
  PQsetNoticeProcessor(
      c, [](void*, const char*) {}, nullptr);
  if (PQsetClientEncoding(c, "UTF8") != 0)
    throw DatabaseError(target + ": cannot use UTF-8: " + one_line(PQerrorMessage(c)));
  migrate(c, target);
  return PostgresStore(std::move(connection), std::move(target));
}

Pushed PostgresStore::push(const std::vector<report::StoredRun>& runs) {
  Pushed out;
  std::vector<PushKey> keys;
  for (std::size_t i = 0; i < runs.size(); ++i)
    keys.push_back(
        {runs[i].path.filename().string(), sha256_hex(detail::json_text(runs[i].json)), i});
  std::ranges::sort(keys, {}, [](const PushKey& k) { return std::tie(k.file, k.sha256); });
  // A run named twice (its folder and its file) is pushed once.
  const auto repeated =
      std::ranges::unique(keys, {}, [](const PushKey& k) { return std::tie(k.file, k.sha256); });
  keys.erase(repeated.begin(), repeated.end());

  for (std::size_t start = 0; start < keys.size(); start += kPushBatch) {
    std::vector<PushKey> batch;
    std::vector<detail::RunRows> rows;
    for (std::size_t i = start; i < std::min(keys.size(), start + kPushBatch); ++i) {
      const report::StoredRun& run = runs[keys[i].index];
      try {
        rows.push_back(detail::rows_of(run));
        batch.push_back(keys[i]);
      } catch (const report::ReportError& e) {
        out.skipped.push_back(run.path.string() + ": " + e.what());
      }
    }
    if (batch.empty()) continue;
    push_batch(connection_.get(), target_, batch, rows);
    out.pushed += batch.size();
  }
  return out;
}

report::RunScan PostgresStore::runs() const {
  const Result r = exec(connection_.get(), target_, "SELECT file, document::TEXT FROM runs");
  report::RunScan scan;
  for (int row = 0; row < PQntuples(r.get()); ++row) {
    const std::string file = value(r, row, 0);
    try {
      report::StoredRun run = report::run_from_json(json::parse(value(r, row, 1)), file);
      // Its samples are in the database, not in a .latencies.csv beside a file.
      run.csv_path.reset();
      scan.runs.push_back(std::move(run));
    } catch (const report::ReportError& e) {
      scan.skipped.push_back(target_ + ": " + e.what());
    } catch (const json::exception& e) {
      scan.skipped.push_back(target_ + ": " + file + ": its document is not JSON (" + e.what() +
                             ")");
    }
  }
  std::ranges::stable_sort(scan.runs, {}, [](const report::StoredRun& run) {
    return std::tie(run.started_utc, run.path);
  });
  return scan;
}

int PostgresStore::schema_version() const {
  return stored_version(connection_.get(), target_);
}

}  // namespace robotperf::results_db
