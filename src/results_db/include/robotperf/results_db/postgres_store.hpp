// The results database a lab shares: runs from many machines pushed into one PostgreSQL database,
// with the SQLite database's tables, and read back as the results files they came from
// (docs/design.md §8, docs/guides/lab-database.md).
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "robotperf/report/run_store.hpp"
#include "robotperf/results_db/results_db.hpp"

struct pg_conn;

namespace robotperf::results_db {

// The schema this robotperf writes (the schema_version table); older ones are migrated on connect.
inline constexpr int kPostgresSchemaVersion = 1;
// The environment variable that names the database when the command line names none.
inline constexpr const char* kResultsUrlVariable = "ROBOTPERF_RESULTS_URL";
// Runs pushed in one transaction.
inline constexpr std::size_t kPushBatch = 100;

// A database that cannot be reached (down, no such database, refused credentials): the message
// names it without credentials, with libpq's reason, on one line.
class ConnectionError : public DatabaseError {
 public:
  using DatabaseError::DatabaseError;
};

// A postgresql:// (or postgres://) URL as libpq reads it. Throws std::invalid_argument, naming
// `source` ("--to", "ROBOTPERF_RESULTS_URL"), for another text, one libpq cannot read, or one
// holding a password: credentials come from libpq's own sources (PGPASSWORD, ~/.pgpass or
// PGPASSFILE, a service file), never from a URL that a process list or a log shows.
std::string checked_url(const std::string& url, const std::string& source);

// What `push` did.
struct Pushed {
  std::size_t pushed = 0;
  std::vector<std::string> skipped;  // one line per run left out: the file and why
};

class PostgresStore {
 public:
  // Connects to `url` (checked_url's), creating the schema or migrating it from an older one under
  // an advisory lock, so that processes connecting at once to a new database do it once. Throws
  // ConnectionError, or DatabaseError for a schema it cannot use.
  static PostgresStore connect(const std::string& url);

  // Records `runs`, kPushBatch to a transaction. A run's identity is its file name and its
  // document's SHA-256, so that runs of two machines never collide and pushing a run again
  // replaces its rows. A run whose .latencies.csv cannot be read is skipped.
  Pushed push(const std::vector<report::StoredRun>& runs);

  // Every run, read back from its document as its results file would be read, sorted as
  // report::scan_results sorts a folder; runs this robotperf cannot read are skipped lines.
  report::RunScan runs() const;

  int schema_version() const;
  // The database as messages name it: a URL without credentials.
  const std::string& target() const { return target_; }

  PostgresStore(PostgresStore&&) noexcept;
  PostgresStore& operator=(PostgresStore&&) noexcept;
  ~PostgresStore();

 private:
  struct Closer {
    void operator()(pg_conn* connection) const;
  };
  PostgresStore(std::unique_ptr<pg_conn, Closer> connection, std::string target);

  std::unique_ptr<pg_conn, Closer> connection_;
  std::string target_;
};

}  // namespace robotperf::results_db
