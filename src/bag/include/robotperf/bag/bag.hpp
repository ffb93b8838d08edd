// rosbag2 bags: a directory with metadata.yaml and one or more storage files
// (sqlite3 `.db3` or MCAP `.mcap`), or a single storage file on its own.
//
// Reading streams: messages come one at a time in timestamp order and only the
// current chunk (MCAP, plus a bounded number decompressed ahead: ReadOptions::chunk_threads)
// or row (sqlite3) is held in memory, so a bag larger than memory can be inspected or
// converted.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <set>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace robotperf::bag {

// Every problem with a bag's files: one line naming the file and what is wrong.
class BagError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct TopicInfo {
  std::string name;  // "/camera/image_raw"
  std::string type;  // "sensor_msgs/msg/Image"
  std::string serialization_format = "cdr";
  // The offered QoS profiles as YAML text (a sequence of profiles), as rosbag2
  // stores them in metadata.yaml, the sqlite3 topics table and MCAP channels.
  std::string offered_qos_profiles;
  std::string type_description_hash;  // "RIHS01_..." (Iron and later), or empty
  // The message definition the bag carries ("ros2msg": the .msg text followed by
  // the definitions it depends on), or empty when the bag has none.
  std::string definition_encoding;
  std::string definition;
  uint64_t message_count = 0;
};

struct Message {
  std::size_t topic = 0;      // index into the reader's topics()
  int64_t timestamp_ns = 0;   // reception time (rosbag2's timestamp, MCAP log_time)
  std::vector<uint8_t> data;  // the serialized payload (CDR with its 4-byte header)
};

enum class Storage { kSqlite3, kMcap };
// "sqlite3" / "mcap"; from_string throws BagError naming the choices.
std::string to_string(Storage storage);
Storage storage_from_string(const std::string& name);

enum class Compression { kNone, kZstd, kLz4 };
std::string to_string(Compression compression);
Compression compression_from_string(const std::string& name);

struct FileInfo {
  std::filesystem::path path;  // relative to the bag directory
  int64_t starting_time_ns = 0;
  int64_t duration_ns = 0;
  uint64_t message_count = 0;
};

// What `ros2 bag info` shows, from metadata.yaml when there is one, else from
// the storage files themselves.
struct BagInfo {
  std::filesystem::path path;
  Storage storage = Storage::kSqlite3;
  int metadata_version = 0;  // 0 when the bag has no metadata.yaml
  std::string ros_distro;
  std::string compression_format;  // rosbag2 file/message compression ("" = none)
  std::string compression_mode;
  int64_t starting_time_ns = 0;
  int64_t duration_ns = 0;
  uint64_t message_count = 0;
  uint64_t bytes = 0;  // size of the storage files
  std::vector<TopicInfo> topics;
  std::vector<FileInfo> files;
};

struct ReadOptions {
  std::set<std::string> topics;          // empty: all topics
  std::optional<int64_t> start_time_ns;  // inclusive
  std::optional<int64_t> end_time_ns;    // inclusive
  bool verify_crc = true;                // MCAP chunk and summary CRCs
  // MCAP: threads that decompress and check chunks ahead of the reading, each on its own chunk,
  // with one chunk more in flight than threads (memory: about twice that many chunks, whatever
  // the bag's size). Messages come in the same order whatever the number. 0: one per online CPU;
  // 1: no thread, each chunk decompressed on the reading thread when its turn comes.
  std::size_t chunk_threads = 0;
};

// One storage file.
class StorageReader {
 public:
  virtual ~StorageReader() = default;
  virtual const std::vector<TopicInfo>& topics() const = 0;
  // Start and end of the messages in the file (0, 0 when empty).
  virtual int64_t start_time_ns() const = 0;
  virtual int64_t end_time_ns() const = 0;
  // The next message in timestamp order; false at the end.
  virtual bool next(Message& out) = 0;
};

std::unique_ptr<StorageReader> open_sqlite3(const std::filesystem::path& file,
                                            const ReadOptions& options = {});
std::unique_ptr<StorageReader> open_mcap(const std::filesystem::path& file,
                                         const ReadOptions& options = {});

// A whole bag (all of its files in order). `path` is a bag directory with a
// metadata.yaml, or a single .db3 / .mcap file.
class Reader {
 public:
  explicit Reader(const std::filesystem::path& path, ReadOptions options = {});
  ~Reader();
  Reader(const Reader&) = delete;
  Reader& operator=(const Reader&) = delete;

  const BagInfo& info() const { return info_; }
  const std::vector<TopicInfo>& topics() const { return info_.topics; }
  bool next(Message& out);

 private:
  bool open_next_file();
  void close_file();  // and removes its decompressed copy

  BagInfo info_;
  ReadOptions options_;
  std::vector<std::filesystem::path> files_;  // absolute
  std::size_t next_file_ = 0;
  std::unique_ptr<StorageReader> current_;
  std::vector<std::size_t> topic_map_;  // current file's topic index -> info_.topics index
  std::filesystem::path decompressed_;  // temporary copy of a zstd file-compressed storage file
};

// Reads the bag's metadata without reading messages (counts come from
// metadata.yaml or the storage's own summary).
BagInfo read_info(const std::filesystem::path& path);

// Reads every message of the bag and compares what its storage holds with what read_info()
// states (metadata.yaml, or a lone storage file's summary): each topic's message count, the
// total, and the times of the first and last messages. Returns one line per disagreement, none
// when they agree; a storage that cannot be read to its end is one line, naming the file and the
// problem.
std::vector<std::string> verify(const std::filesystem::path& path);

struct WriteOptions {
  Storage storage = Storage::kSqlite3;
  Compression compression = Compression::kZstd;  // MCAP chunk compression
  std::size_t chunk_size = 4 * 1024 * 1024;      // MCAP: uncompressed bytes per chunk
  uint64_t max_file_bytes = 0;  // split into files of about this size; 0 = one file
};

// Writes a bag directory: `<dir>/<dir name>_<n>.<ext>` and metadata.yaml
// (version 5, what ROS 2 Humble reads; Iron and Jazzy read it too). The
// directory must not exist yet or be empty. Files are complete only after
// close(), which the destructor calls too (swallowing its errors). A writer
// destroyed by an exception, or whose close() failed, removes what it wrote
// and the directory if it made it: no half-written bag is left looking whole.
class Writer {
 public:
  Writer(const std::filesystem::path& dir, WriteOptions options);
  ~Writer();
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;

  // Returns the topic's index for write(). Topics keep their QoS and definition;
  // QoS text that is not QoS profiles is a BagError naming the topic.
  std::size_t add_topic(const TopicInfo& topic);
  void write(std::size_t topic, int64_t timestamp_ns, std::span<const uint8_t> data);
  void close();

 private:
  class Impl;
  std::unique_ptr<Impl> impl_;
};

// Writes <dir>/metadata.yaml for a bag directory that has none, from its storage
// files (as `ros2 bag reindex`), and returns the bag's info read back. Throws
// BagError when the directory already has one, holds no storage file, mixes
// storages, or gives one topic two types.
BagInfo reindex(const std::filesystem::path& dir);

// Copies every message, topic, QoS and definition of the bag at `in` into a
// new bag at `out`; returns the number of messages copied. `complete`, when
// given, sees each topic before it is written (to add a missing definition).
// When it fails, `out` is left as it was (see Writer).
uint64_t convert(const std::filesystem::path& in, const std::filesystem::path& out,
                 const WriteOptions& options, const std::function<void(TopicInfo&)>& complete = {});

// One storage file being written.
class StorageWriter {
 public:
  virtual ~StorageWriter() = default;
  virtual void add_topic(std::size_t id, const TopicInfo& topic) = 0;
  virtual void write(std::size_t topic, int64_t timestamp_ns, std::span<const uint8_t> data) = 0;
  virtual uint64_t bytes_written() const = 0;
  virtual void close() = 0;
};

std::unique_ptr<StorageWriter> create_sqlite3(const std::filesystem::path& file);
std::unique_ptr<StorageWriter> create_mcap(const std::filesystem::path& file,
                                           Compression compression, std::size_t chunk_size);

}  // namespace robotperf::bag
