// rosbag2 sqlite3 storage: tables topics(id, name, type, serialization_format,
// offered_qos_profiles[, type_description_hash]) and messages(id, topic_id,
// timestamp, data); schema 3 (Humble) adds schema and metadata tables, schema 4
// (Iron, Jazzy) adds type_description_hash and message_definitions.
#include <fcntl.h>
#include <sqlite3.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <map>
#include <set>
#include <string_view>

#include "robotperf/bag/bag.hpp"
#include "robotperf/bag/qos.hpp"

namespace robotperf::bag {
namespace {

namespace fs = std::filesystem;

class Statement {
 public:
  Statement(sqlite3* db, const std::string& sql, const fs::path& file) : db_(db), file_(file) {
    if (sqlite3_prepare_v2(db, sql.c_str(), -1, &stmt_, nullptr) != SQLITE_OK) fail();
  }
  ~Statement() { sqlite3_finalize(stmt_); }
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;

  // True while a row is available.
  bool step() {
    const int rc = sqlite3_step(stmt_);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) return false;
    fail();
  }
  void reset() {
    sqlite3_reset(stmt_);
    sqlite3_clear_bindings(stmt_);
  }
  void bind(int i, int64_t v) { check(sqlite3_bind_int64(stmt_, i, v)); }
  void bind(int i, const std::string& s) {
    check(sqlite3_bind_text(stmt_, i, s.data(), static_cast<int>(s.size()), SQLITE_TRANSIENT));
  }
  void bind_blob(int i, std::span<const uint8_t> data) {
    check(sqlite3_bind_blob64(stmt_, i, data.data(), data.size(), SQLITE_STATIC));
  }
  int64_t integer(int col) const { return sqlite3_column_int64(stmt_, col); }
  std::string text(int col) const {
    const unsigned char* s = sqlite3_column_text(stmt_, col);
    return s ? std::string(reinterpret_cast<const char*>(s),
                           static_cast<std::size_t>(sqlite3_column_bytes(stmt_, col)))
             : std::string();
  }
  std::span<const uint8_t> blob(int col) const {
    const auto* p = static_cast<const uint8_t*>(sqlite3_column_blob(stmt_, col));
    return {p, static_cast<std::size_t>(sqlite3_column_bytes(stmt_, col))};
  }

 private:
  void check(int rc) {
    if (rc != SQLITE_OK) fail();
  }
  [[noreturn]] void fail() { throw BagError(file_.string() + ": sqlite3: " + sqlite3_errmsg(db_)); }
  sqlite3* db_;
  sqlite3_stmt* stmt_ = nullptr;
  fs::path file_;
};

class Database {
 public:
  Database(const fs::path& file, int flags) : file_(file) {
    if (sqlite3_open_v2(file.c_str(), &db_, flags, nullptr) != SQLITE_OK) {
      const std::string why = db_ ? sqlite3_errmsg(db_) : "out of memory";
      sqlite3_close(db_);
      throw BagError(file.string() + ": cannot open as sqlite3: " + why);
    }
  }
  ~Database() { sqlite3_close(db_); }
  Database(const Database&) = delete;
  Database& operator=(const Database&) = delete;

  sqlite3* get() const { return db_; }
  void exec(const std::string& sql) {
    char* err = nullptr;
    if (sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, &err) != SQLITE_OK) {
      const std::string why = err ? err : sqlite3_errmsg(db_);
      sqlite3_free(err);
      throw BagError(file_.string() + ": sqlite3: " + why);
    }
  }

 private:
  sqlite3* db_ = nullptr;
  fs::path file_;
};

// The service a service type is derived from ("pkg/srv/Name" for pkg/srv/Name_Event, _Request or
// _Response), or "" for other types. Jazzy stores the definition of a service event topic's type
// under the service's name, as its .srv text, from which the derived types are built.
std::string service_of(const std::string& type) {
  if (type.find("/srv/") == std::string::npos) return "";
  for (const std::string_view suffix : {"_Event", "_Request", "_Response"}) {
    if (type.size() > suffix.size() && type.ends_with(suffix))
      return type.substr(0, type.size() - suffix.size());
  }
  return "";
}

class SqliteReader final : public StorageReader {
 public:
  SqliteReader(const fs::path& file, const ReadOptions& options)
      : file_(file), db_(file, SQLITE_OPEN_READONLY) {
    if (!fs::is_regular_file(file)) throw BagError(file.string() + ": no such file");
    // Blobs of images span hundreds of pages: reading them through a memory
    // map saves a read() call and a copy per page (sqlite caps the size).
    db_.exec("PRAGMA mmap_size=1099511627776");
    std::set<std::string> tables;
    try {
      Statement q(db_.get(), "SELECT name FROM sqlite_master WHERE type='table'", file);
      while (q.step()) tables.insert(q.text(0));
    } catch (const BagError&) {
      throw BagError(file.string() + ": not an sqlite3 database (" + sqlite3_errmsg(db_.get()) +
                     ")");
    }
    if (!tables.contains("topics") || !tables.contains("messages")) {
      throw BagError(file.string() +
                     ": an sqlite3 database but not a rosbag2 bag (no topics and messages tables)");
    }
    std::set<std::string> topic_columns;
    {
      Statement q(db_.get(), "PRAGMA table_info(topics)", file);
      while (q.step()) topic_columns.insert(q.text(1));
    }
    std::map<std::string, std::pair<std::string, std::string>> definitions;
    if (tables.contains("message_definitions")) {
      Statement q(db_.get(),
                  "SELECT topic_type, encoding, encoded_message_definition FROM "
                  "message_definitions",
                  file);
      while (q.step()) definitions[q.text(0)] = {q.text(1), q.text(2)};
    }
    const bool has_qos = topic_columns.contains("offered_qos_profiles");
    const bool has_hash = topic_columns.contains("type_description_hash");
    Statement q(db_.get(),
                std::string("SELECT id, name, type, serialization_format, ") +
                    (has_qos ? "offered_qos_profiles" : "''") + ", " +
                    (has_hash ? "type_description_hash" : "''") + " FROM topics ORDER BY id",
                file);
    while (q.step()) {
      TopicInfo t;
      const int64_t id = q.integer(0);
      t.name = q.text(1);
      t.type = q.text(2);
      t.serialization_format = q.text(3);
      t.offered_qos_profiles = q.text(4);
      t.type_description_hash = q.text(5);
      auto it = definitions.find(t.type);
      if (const std::string service = service_of(t.type);
          it == definitions.end() && !service.empty())
        it = definitions.find(service);
      if (it != definitions.end() && it->second.first != "unknown") {
        t.definition_encoding = it->second.first;
        t.definition = it->second.second;
      }
      index_of_id_[id] = topics_.size();
      topics_.push_back(std::move(t));
    }
    {
      Statement c(db_.get(),
                  "SELECT topic_id, COUNT(*), MIN(timestamp), MAX(timestamp) FROM messages "
                  "GROUP BY topic_id",
                  file);
      bool first = true;
      while (c.step()) {
        auto it = index_of_id_.find(c.integer(0));
        if (it == index_of_id_.end()) {
          throw BagError(file.string() + ": messages refer to topic id " +
                         std::to_string(c.integer(0)) + ", which the topics table lacks");
        }
        topics_[it->second].message_count = static_cast<uint64_t>(c.integer(1));
        start_ = first ? c.integer(2) : std::min(start_, c.integer(2));
        end_ = first ? c.integer(3) : std::max(end_, c.integer(3));
        first = false;
      }
    }
    std::string sql = "SELECT topic_id, timestamp, data FROM messages WHERE 1";
    if (!options.topics.empty()) {
      std::string ids;
      for (const auto& [id, index] : index_of_id_) {
        if (options.topics.contains(topics_[index].name))
          ids += (ids.empty() ? "" : ",") + std::to_string(id);
      }
      sql += " AND topic_id IN (" + ids + ")";
    }
    if (options.start_time_ns) sql += " AND timestamp >= " + std::to_string(*options.start_time_ns);
    if (options.end_time_ns) sql += " AND timestamp <= " + std::to_string(*options.end_time_ns);
    sql += " ORDER BY timestamp, id";
    messages_ = std::make_unique<Statement>(db_.get(), sql, file);
  }

  const std::vector<TopicInfo>& topics() const override { return topics_; }
  int64_t start_time_ns() const override { return start_; }
  int64_t end_time_ns() const override { return end_; }

  bool next(Message& out) override {
    if (!messages_->step()) return false;
    out.topic = index_of_id_.at(messages_->integer(0));
    out.timestamp_ns = messages_->integer(1);
    const auto data = messages_->blob(2);
    out.data.assign(data.begin(), data.end());
    return true;
  }

 private:
  fs::path file_;
  Database db_;
  std::vector<TopicInfo> topics_;
  std::map<int64_t, std::size_t> index_of_id_;
  int64_t start_ = 0;
  int64_t end_ = 0;
  std::unique_ptr<Statement> messages_;
};

// Schema 4, Iron's and Jazzy's layout: topics with type_description_hash, and message_definitions
// holding each type's definition, which Iron and later read back (from schema 4 on). Humble's
// plug-in selects the tables and columns it knows by name and ignores the others.
// Makes `file` as a new empty file, never through a link or over another file (SQLite's own
// create follows links and writes into an existing file), and returns it.
const fs::path& created_exclusively(const fs::path& file) {
  const int fd = open(file.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
  if (fd < 0) {
    throw BagError(
        file.string() + ": cannot create the storage file: " + std::strerror(errno) +
        (errno == EEXIST ? " (something is already there; choose a new bag directory)" : ""));
  }
  close(fd);
  return file;
}

class SqliteWriter final : public StorageWriter {
 public:
  // SQLITE_OPEN_NOFOLLOW: the file made just before is not swapped for a link in between.
  explicit SqliteWriter(const fs::path& file)
      : file_(file), db_(created_exclusively(file), SQLITE_OPEN_READWRITE | SQLITE_OPEN_NOFOLLOW) {
    db_.exec(
        "PRAGMA journal_mode=MEMORY; PRAGMA synchronous=OFF; PRAGMA page_size=4096;"
        "CREATE TABLE schema(schema_version INTEGER PRIMARY KEY,ros_distro TEXT NOT NULL);"
        "INSERT INTO schema VALUES(4,'jazzy');"
        "CREATE TABLE metadata(id INTEGER PRIMARY KEY,metadata_version INTEGER NOT NULL,"
        "metadata TEXT NOT NULL);"
        "CREATE TABLE topics(id INTEGER PRIMARY KEY,name TEXT NOT NULL,type TEXT NOT NULL,"
        "serialization_format TEXT NOT NULL,offered_qos_profiles TEXT NOT NULL,"
        "type_description_hash TEXT NOT NULL);"
        "CREATE TABLE message_definitions(id INTEGER PRIMARY KEY,topic_type TEXT NOT NULL,"
        "encoding TEXT NOT NULL,encoded_message_definition TEXT NOT NULL,"
        "type_description_hash TEXT NOT NULL);"
        "CREATE TABLE messages(id INTEGER PRIMARY KEY,topic_id INTEGER NOT NULL,"
        "timestamp INTEGER NOT NULL, data BLOB NOT NULL);"
        "CREATE INDEX timestamp_idx ON messages (timestamp ASC);"
        "BEGIN TRANSACTION;");
    insert_topic_ = std::make_unique<Statement>(
        db_.get(),
        "INSERT INTO topics (id, name, type, serialization_format, offered_qos_profiles, "
        "type_description_hash) VALUES (?, ?, ?, ?, ?, ?)",
        file);
    insert_definition_ = std::make_unique<Statement>(
        db_.get(),
        "INSERT INTO message_definitions (topic_type, encoding, encoded_message_definition, "
        "type_description_hash) VALUES (?, ?, ?, ?)",
        file);
    insert_message_ = std::make_unique<Statement>(
        db_.get(), "INSERT INTO messages (topic_id, timestamp, data) VALUES (?, ?, ?)", file);
  }
  ~SqliteWriter() override {
    try {
      close();
    } catch (const BagError&) {  // destructors must not throw; close() reports errors
    }
  }

  void add_topic(std::size_t id, const TopicInfo& t) override {
    insert_topic_->bind(1, static_cast<int64_t>(id) + 1);
    insert_topic_->bind(2, t.name);
    insert_topic_->bind(3, t.type);
    insert_topic_->bind(4, t.serialization_format);
    insert_topic_->bind(5, qos_with_integer_enums(t.offered_qos_profiles));
    insert_topic_->bind(6, t.type_description_hash);
    insert_topic_->step();
    insert_topic_->reset();
    // One row per type; an encoding with an empty text is a definition too (std_msgs/msg/Empty).
    if (!t.definition_encoding.empty() && t.definition_encoding != "unknown" &&
        defined_types_.insert(t.type).second) {
      insert_definition_->bind(1, t.type);
      insert_definition_->bind(2, t.definition_encoding);
      insert_definition_->bind(3, t.definition);
      insert_definition_->bind(4, t.type_description_hash);
      insert_definition_->step();
      insert_definition_->reset();
    }
  }

  void write(std::size_t topic, int64_t timestamp_ns, std::span<const uint8_t> data) override {
    insert_message_->bind(1, static_cast<int64_t>(topic) + 1);
    insert_message_->bind(2, timestamp_ns);
    insert_message_->bind_blob(3, data);
    insert_message_->step();
    insert_message_->reset();
    bytes_ += data.size() + 32;  // payload plus row and index overhead, roughly
    // Commit in batches: one transaction per message would be very slow.
    if (++pending_ >= 1000 || bytes_ - committed_bytes_ > (64u << 20)) commit();
  }

  uint64_t bytes_written() const override { return bytes_; }

  void close() override {
    if (closed_) return;
    closed_ = true;
    insert_topic_.reset();
    insert_definition_.reset();
    insert_message_.reset();
    db_.exec("COMMIT;");
  }

 private:
  void commit() {
    db_.exec("COMMIT; BEGIN TRANSACTION;");
    pending_ = 0;
    committed_bytes_ = bytes_;
  }

  fs::path file_;
  Database db_;
  std::unique_ptr<Statement> insert_topic_;
  std::unique_ptr<Statement> insert_definition_;
  std::unique_ptr<Statement> insert_message_;
  std::set<std::string> defined_types_;
  uint64_t bytes_ = 0;
  uint64_t committed_bytes_ = 0;
  std::size_t pending_ = 0;
  bool closed_ = false;
};

}  // namespace

std::unique_ptr<StorageReader> open_sqlite3(const fs::path& file, const ReadOptions& options) {
  if (!fs::is_regular_file(file)) throw BagError(file.string() + ": no such file");
  return std::make_unique<SqliteReader>(file, options);
}

std::unique_ptr<StorageWriter> create_sqlite3(const fs::path& file) {
  if (fs::exists(file)) throw BagError(file.string() + ": already exists; not overwriting it");
  return std::make_unique<SqliteWriter>(file);
}

}  // namespace robotperf::bag
