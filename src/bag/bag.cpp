// Bags as directories (metadata.yaml + storage files) and single storage files.
#include "robotperf/bag/bag.hpp"

#include <fcntl.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>
#include <zstd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <utility>

#include "mcap_format.hpp"
#include "robotperf/bag/qos.hpp"
#include "robotperf/files/atomic_file.hpp"
#include "robotperf/files/yaml_scalar.hpp"

namespace robotperf::bag {
namespace {

namespace fs = std::filesystem;

constexpr const char* kMetadataFile = "metadata.yaml";

// What a storage file is, from its first bytes (the extension can lie).
Storage sniff_storage(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw BagError(file.string() + ": cannot open");
  char head[16] = {};
  in.read(head, sizeof(head));
  const auto n = static_cast<std::size_t>(in.gcount());
  if (n >= 5 && std::memcmp(head, "\x89MCAP", 5) == 0) return Storage::kMcap;
  if (n == 16 && std::memcmp(head, "SQLite format 3\0", 16) == 0) return Storage::kSqlite3;
  throw BagError(file.string() + ": neither an sqlite3 database nor an MCAP file (wrong magic)");
}

std::unique_ptr<StorageReader> open_storage(const fs::path& file, const ReadOptions& options) {
  if (!fs::is_regular_file(file)) throw BagError(file.string() + ": no such file");
  return sniff_storage(file) == Storage::kMcap ? open_mcap(file, options)
                                               : open_sqlite3(file, options);
}

template <class T>
T get(const YAML::Node& node, const char* key, const T& fallback, const fs::path& file) {
  const YAML::Node v = node[key];
  if (!v || v.IsNull()) return fallback;
  try {
    return v.as<T>();
  } catch (const YAML::Exception&) {
    throw BagError(file.string() + ": line " + std::to_string(v.Mark().line + 1) + ": '" + key +
                   "' has the wrong type");
  }
}

int64_t nested_ns(const YAML::Node& node, const char* key, const char* inner,
                  const fs::path& file) {
  const YAML::Node v = node[key];
  if (!v || !v.IsMap()) return 0;
  return get<int64_t>(v, inner, 0, file);
}

// offered_qos_profiles: a YAML string (versions 4 to 8) or, from version 9, the
// sequence itself; kept as text either way.
std::string qos_text(const YAML::Node& node, const fs::path& file) {
  if (!node || node.IsNull()) return "";
  if (node.IsScalar()) return node.as<std::string>();
  try {
    YAML::Emitter out;
    out << node;
    return qos_profiles_to_yaml(parse_qos_profiles(out.c_str()));
  } catch (const std::invalid_argument& e) {
    throw BagError(file.string() + ": line " + std::to_string(node.Mark().line + 1) + ": " +
                   e.what());
  }
}

BagInfo read_metadata(const fs::path& dir) {
  const fs::path file = dir / kMetadataFile;
  YAML::Node root;
  try {
    root = YAML::LoadFile(file.string());
  } catch (const YAML::BadFile&) {
    throw BagError(file.string() + ": cannot read");
  } catch (const YAML::Exception& e) {
    throw BagError(file.string() + ": line " + std::to_string(e.mark.line + 1) +
                   ": malformed YAML: " + e.msg);
  }
  const YAML::Node m = root["rosbag2_bagfile_information"];
  if (!m || !m.IsMap())
    throw BagError(file.string() + ": no rosbag2_bagfile_information: not a rosbag2 metadata file");
  BagInfo info;
  info.path = dir;
  info.metadata_version = get<int>(m, "version", 0, file);
  if (info.metadata_version < 1 || info.metadata_version > 9) {
    throw BagError(file.string() + ": metadata version " + std::to_string(info.metadata_version) +
                   " is not supported (robotperf reads versions 1 to 9)");
  }
  const std::string storage = get<std::string>(m, "storage_identifier", "", file);
  if (storage == "sqlite3") {
    info.storage = Storage::kSqlite3;
  } else if (storage == "mcap") {
    info.storage = Storage::kMcap;
  } else {
    throw BagError(file.string() + ": storage_identifier '" + storage +
                   "' is not supported (sqlite3, mcap)");
  }
  info.ros_distro = get<std::string>(m, "ros_distro", "", file);
  info.compression_format = get<std::string>(m, "compression_format", "", file);
  info.compression_mode = get<std::string>(m, "compression_mode", "", file);
  info.starting_time_ns = nested_ns(m, "starting_time", "nanoseconds_since_epoch", file);
  info.duration_ns = nested_ns(m, "duration", "nanoseconds", file);
  info.message_count = get<uint64_t>(m, "message_count", 0, file);
  if (const YAML::Node topics = m["topics_with_message_count"]; topics && topics.IsSequence()) {
    for (const auto& entry : topics) {
      const YAML::Node t = entry.IsMap() ? entry["topic_metadata"] : YAML::Node();
      if (!t || !t.IsMap()) {
        throw BagError(file.string() + ": line " + std::to_string(entry.Mark().line + 1) +
                       ": topic entry without topic_metadata");
      }
      TopicInfo topic;
      topic.name = get<std::string>(t, "name", "", file);
      topic.type = get<std::string>(t, "type", "", file);
      topic.serialization_format = get<std::string>(t, "serialization_format", "cdr", file);
      topic.offered_qos_profiles = qos_text(t["offered_qos_profiles"], file);
      topic.type_description_hash = get<std::string>(t, "type_description_hash", "", file);
      topic.message_count = get<uint64_t>(entry, "message_count", 0, file);
      info.topics.push_back(std::move(topic));
    }
  }
  std::vector<std::string> paths;
  if (const YAML::Node p = m["relative_file_paths"]; p && p.IsSequence()) {
    for (const auto& e : p) {
      if (!e.IsScalar()) {
        throw BagError(file.string() + ": line " + std::to_string(e.Mark().line + 1) +
                       ": an entry of 'relative_file_paths' is not a file name; list each "
                       "storage file by its path in the bag directory");
      }
      paths.push_back(e.Scalar());
    }
  }
  std::map<std::string, FileInfo> file_details;
  if (const YAML::Node f = m["files"]; f && f.IsSequence()) {
    for (const auto& e : f) {
      if (!e.IsMap()) {
        throw BagError(file.string() + ": line " + std::to_string(e.Mark().line + 1) +
                       ": an entry of 'files' is not a map of path, starting_time, duration "
                       "and message_count");
      }
      FileInfo fi;
      fi.path = get<std::string>(e, "path", "", file);
      fi.starting_time_ns = nested_ns(e, "starting_time", "nanoseconds_since_epoch", file);
      fi.duration_ns = nested_ns(e, "duration", "nanoseconds", file);
      fi.message_count = get<uint64_t>(e, "message_count", 0, file);
      file_details[fi.path.string()] = fi;
    }
  }
  if (paths.empty()) throw BagError(file.string() + ": relative_file_paths lists no storage file");
  for (const auto& p : paths) {
    // Older versions list paths with the bag directory's name in front.
    fs::path rel = p;
    if (!fs::exists(dir / rel) && fs::exists(dir / rel.filename())) rel = rel.filename();
    FileInfo fi = file_details.contains(p) ? file_details[p] : FileInfo{};
    fi.path = rel;
    info.files.push_back(fi);
  }
  return info;
}

// File-level compression ("file" mode) is undone into a temporary copy;
// message-level compression per message in Reader::next.
void check_compression(const BagInfo& info) {
  if (info.compression_format.empty()) return;
  if (info.compression_format != "zstd") {
    throw BagError((info.path / kMetadataFile).string() + ": compression_format '" +
                   info.compression_format + "' is unknown (rosbag2 compresses with zstd)");
  }
  if (info.compression_mode != "message" && info.compression_mode != "file" &&
      info.compression_mode != "MESSAGE" && info.compression_mode != "FILE") {
    throw BagError((info.path / kMetadataFile).string() + ": compression_mode '" +
                   info.compression_mode + "' is unknown (file, message)");
  }
}

bool message_compressed(const BagInfo& info) {
  return info.compression_format == "zstd" &&
         (info.compression_mode == "message" || info.compression_mode == "MESSAGE");
}

bool file_compressed(const BagInfo& info) {
  return info.compression_format == "zstd" &&
         (info.compression_mode == "file" || info.compression_mode == "FILE");
}

// Decompresses a zstd-compressed storage file into a temporary file of its own: two readers in
// one process, of one bag or of two bags whose files share a name, must not write each other's.
// The file is written through the descriptor mkstemp opened, never reopened by its name (which
// another process could have replaced with a link in the meantime).
fs::path decompress_file(const fs::path& compressed) {
  std::ifstream in(compressed, std::ios::binary);
  if (!in) throw BagError(compressed.string() + ": cannot open");
  std::string name = (fs::temp_directory_path() /
                      ("robotperf-" + compressed.stem().filename().string() + "-XXXXXX"))
                         .string();
  const int fd = ::mkstemp(name.data());
  if (fd < 0) throw BagError(name + ": cannot create a temporary file: " + std::strerror(errno));
  const fs::path out_path = name;
  // Removed on every way out but the last.
  struct Output {
    std::FILE* file;
    fs::path path;
    ~Output() {
      if (file != nullptr) std::fclose(file);
      if (!path.empty()) fs::remove(path);
    }
  } out{::fdopen(fd, "wb"), out_path};
  if (out.file == nullptr) {
    ::close(fd);
    throw BagError(out_path.string() + ": cannot write a temporary file");
  }
  const std::unique_ptr<ZSTD_DCtx, decltype(&ZSTD_freeDCtx)> ctx(ZSTD_createDCtx(), ZSTD_freeDCtx);
  std::vector<char> src(ZSTD_DStreamInSize()), dst(ZSTD_DStreamOutSize());
  std::size_t last = 0;
  bool written = true;
  while (in && written) {
    in.read(src.data(), static_cast<std::streamsize>(src.size()));
    ZSTD_inBuffer input{src.data(), static_cast<std::size_t>(in.gcount()), 0};
    while (input.pos < input.size && written) {
      ZSTD_outBuffer output{dst.data(), dst.size(), 0};
      last = ZSTD_decompressStream(ctx.get(), &output, &input);
      if (ZSTD_isError(last))
        throw BagError(compressed.string() + ": zstd: " + ZSTD_getErrorName(last));
      written = std::fwrite(dst.data(), 1, output.pos, out.file) == output.pos;
    }
  }
  if (written && last != 0) throw BagError(compressed.string() + ": truncated zstd file");
  const int closed = std::fclose(std::exchange(out.file, nullptr));
  if (!written || closed != 0)
    throw BagError(out_path.string() + ": cannot write a temporary file (is the disk full?)");
  out.path.clear();
  return out_path;
}

// Storage file names in metadata.yaml of file-compressed bags carry ".zstd".
fs::path storage_path(const BagInfo& info, const FileInfo& f) {
  return info.path / f.path;
}

}  // namespace

std::string to_string(Storage storage) {
  return storage == Storage::kMcap ? "mcap" : "sqlite3";
}

Storage storage_from_string(const std::string& name) {
  if (name == "sqlite3") return Storage::kSqlite3;
  if (name == "mcap") return Storage::kMcap;
  throw BagError("unknown storage '" + name + "' (sqlite3, mcap)");
}

std::string to_string(Compression compression) {
  switch (compression) {
    case Compression::kZstd:
      return "zstd";
    case Compression::kLz4:
      return "lz4";
    case Compression::kNone:
      break;
  }
  return "none";
}

Compression compression_from_string(const std::string& name) {
  if (name == "zstd") return Compression::kZstd;
  if (name == "lz4") return Compression::kLz4;
  if (name == "none" || name.empty()) return Compression::kNone;
  throw BagError("unknown compression '" + name + "' (zstd, lz4, none)");
}

BagInfo read_info(const fs::path& path) {
  if (fs::is_directory(path)) {
    if (!fs::exists(path / kMetadataFile)) {
      throw BagError(path.string() +
                     ": no metadata.yaml, so not a rosbag2 bag directory (pass a "
                     ".db3 or .mcap file to read one storage file alone, or write one from the "
                     "storage files with 'robotperf bag reindex')");
    }
    BagInfo info = read_metadata(path);
    check_compression(info);
    for (const auto& f : info.files) {
      if (!fs::is_regular_file(info.path / f.path)) {
        throw BagError((info.path / f.path).string() +
                       ": listed in metadata.yaml but missing from the bag directory");
      }
      info.bytes += fs::file_size(info.path / f.path);
    }
    return info;
  }
  if (!fs::exists(path)) throw BagError(path.string() + ": no such file or directory");
  BagInfo info;
  info.path = path.parent_path();
  info.storage = sniff_storage(path);
  info.bytes = fs::file_size(path);
  const auto reader = open_storage(path, {});
  info.topics = reader->topics();
  for (const auto& t : info.topics) info.message_count += t.message_count;
  if (info.message_count) {
    info.starting_time_ns = reader->start_time_ns();
    info.duration_ns = reader->end_time_ns() - reader->start_time_ns();
  }
  info.files.push_back(
      {path.filename(), info.starting_time_ns, info.duration_ns, info.message_count});
  return info;
}

Reader::Reader(const fs::path& path, ReadOptions options)
    : info_(read_info(path)), options_(std::move(options)) {
  for (const auto& f : info_.files) files_.push_back(storage_path(info_, f));
  // The first file is opened now, decompressed if need be, so that its definitions, hashes and
  // QoS complete metadata.yaml's topics before anyone asks for them.
  if (info_.metadata_version > 0) {
    try {
      open_next_file();
    } catch (...) {
      close_file();  // no destructor runs after a throwing constructor
      throw;
    }
  }
}

Reader::~Reader() {
  close_file();
}

void Reader::close_file() {
  current_.reset();
  if (!decompressed_.empty()) {
    std::error_code ec;
    fs::remove(decompressed_, ec);
    decompressed_.clear();
  }
}

bool Reader::open_next_file() {
  close_file();
  if (next_file_ >= files_.size()) return false;
  fs::path file = files_[next_file_++];
  if (file_compressed(info_)) {
    decompressed_ = decompress_file(file);
    file = decompressed_;
  }
  current_ = open_storage(file, options_);
  topic_map_.clear();
  for (const auto& t : current_->topics()) {
    auto it = std::find_if(info_.topics.begin(), info_.topics.end(),
                           [&](const TopicInfo& m) { return m.name == t.name; });
    if (it == info_.topics.end()) {
      info_.topics.push_back(t);
      it = info_.topics.end() - 1;
    }
    // Definitions, hashes and QoS come from the storage where metadata.yaml lacks them.
    if (it->definition.empty()) {
      it->definition = t.definition;
      it->definition_encoding = t.definition_encoding;
    }
    if (it->type_description_hash.empty()) it->type_description_hash = t.type_description_hash;
    if (it->offered_qos_profiles.empty()) it->offered_qos_profiles = t.offered_qos_profiles;
    topic_map_.push_back(static_cast<std::size_t>(it - info_.topics.begin()));
  }
  return true;
}

bool Reader::next(Message& out) {
  while (!current_ || !current_->next(out)) {
    if (!open_next_file()) return false;
  }
  out.topic = topic_map_.at(out.topic);
  if (message_compressed(info_)) {
    // rosbag2 compresses each message as one zstd frame that says its size.
    const auto where = [&] {
      return files_[next_file_ - 1].string() + ": a message on " + info_.topics[out.topic].name;
    };
    const unsigned long long size = ZSTD_getFrameContentSize(out.data.data(), out.data.size());
    if (size == ZSTD_CONTENTSIZE_ERROR || size == ZSTD_CONTENTSIZE_UNKNOWN)
      throw BagError(where() + " is not a zstd frame that says its size");
    std::vector<uint8_t> plain;
    try {
      mcap::decompress("zstd", out.data, size, plain);
    } catch (const mcap::FormatError& e) {
      throw BagError(where() + " does not decompress: " + e.what());
    }
    out.data = std::move(plain);
  }
  return true;
}

namespace {

// The topic's QoS in the integer encoding Humble reads; text that is not QoS profiles is the bag's
// error, naming `where` and the topic.
std::string integer_qos(const TopicInfo& topic, const fs::path& where) {
  try {
    return qos_with_integer_enums(topic.offered_qos_profiles);
  } catch (const std::invalid_argument& e) {
    throw BagError(where.string() + ": topic " + topic.name + ": " + e.what());
  }
}

// Makes what was written to a file, or which entries a directory has, reach the disk.
void sync_to_disk(const fs::path& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw BagError(path.string() + ": cannot open to sync: " + std::strerror(errno));
  const int result = ::fsync(fd);
  const int error = errno;
  ::close(fd);
  // EINVAL: a file system that cannot sync directories; there is nothing more to do.
  if (result != 0 && error != EINVAL)
    throw BagError(path.string() + ": cannot sync to the disk: " + std::strerror(error));
}

// metadata.yaml version 5: the fields ROS 2 Humble reads; Iron and Jazzy read it too. Written
// beside, synced and renamed: a crash never leaves a half-written metadata.yaml.
void write_metadata_file(const fs::path& dir, Storage storage, const std::vector<TopicInfo>& topics,
                         const std::vector<FileInfo>& files) {
  const fs::path target = dir / kMetadataFile;
  int64_t start = 0;
  int64_t end = 0;
  uint64_t count = 0;
  for (const auto& f : files) {
    if (f.message_count == 0) continue;
    start = count ? std::min(start, f.starting_time_ns) : f.starting_time_ns;
    end = count ? std::max(end, f.starting_time_ns + f.duration_ns)
                : f.starting_time_ns + f.duration_ns;
    count += f.message_count;
  }
  std::ostringstream y;
  y << "rosbag2_bagfile_information:\n"
    << "  version: 5\n"
    << "  storage_identifier: " << to_string(storage) << "\n"
    << "  duration:\n    nanoseconds: " << (end - start) << "\n"
    << "  starting_time:\n    nanoseconds_since_epoch: " << start << "\n"
    << "  message_count: " << count << "\n"
    << "  topics_with_message_count:\n";
  for (const auto& t : topics) {
    y << "    - topic_metadata:\n"
      << "        name: " << files::yaml_double_quoted(t.name) << "\n"
      << "        type: " << files::yaml_double_quoted(t.type) << "\n"
      << "        serialization_format: " << files::yaml_double_quoted(t.serialization_format)
      << "\n"
      << "        offered_qos_profiles: " << files::yaml_double_quoted(integer_qos(t, target))
      << "\n"
      << "      message_count: " << t.message_count << "\n";
  }
  y << "  compression_format: \"\"\n"
    << "  compression_mode: \"\"\n"
    << "  relative_file_paths:\n";
  for (const auto& f : files) y << "    - " << files::yaml_double_quoted(f.path.string()) << "\n";
  y << "  files:\n";
  for (const auto& f : files) {
    y << "    - path: " << files::yaml_double_quoted(f.path.string()) << "\n"
      << "      starting_time:\n        nanoseconds_since_epoch: " << f.starting_time_ns << "\n"
      << "      duration:\n        nanoseconds: " << f.duration_ns << "\n"
      << "      message_count: " << f.message_count << "\n";
  }
  // A temporary file of its own, never a fixed name: one planted in the folder (a link to
  // another file) is not written through.
  try {
    files::write_file_atomically(target, y.str());
  } catch (const std::runtime_error& e) {
    throw BagError(e.what());
  }
}

}  // namespace

class Writer::Impl {
 public:
  Impl(const fs::path& dir, WriteOptions options) : dir_(dir), options_(options) {
    if (fs::exists(dir) && !(fs::is_directory(dir) && fs::is_empty(dir)))
      throw BagError(dir.string() +
                     ": already exists and is not empty; choose a new bag directory");
    // The folders this writer makes, innermost first: discard() removes them again.
    for (fs::path p = dir; !p.empty() && !fs::exists(p); p = p.parent_path()) created_.push_back(p);
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec) throw BagError(dir.string() + ": cannot create: " + ec.message());
    try {
      open_file();
    } catch (...) {
      discard();
      throw;
    }
  }

  std::size_t add_topic(const TopicInfo& topic) {
    // metadata.yaml will need the QoS in Humble's encoding: bad QoS is refused now, not at close.
    integer_qos(topic, dir_);
    TopicInfo t = topic;
    t.message_count = 0;
    current_->add_topic(topics_.size(), t);
    topics_.push_back(std::move(t));
    return topics_.size() - 1;
  }

  void write(std::size_t topic, int64_t timestamp_ns, std::span<const uint8_t> data) {
    if (topic >= topics_.size()) throw BagError(dir_.string() + ": write to an unknown topic");
    if (options_.max_file_bytes && files_.back().message_count > 0 &&
        current_->bytes_written() >= options_.max_file_bytes) {
      current_->close();
      open_file();
      for (std::size_t i = 0; i < topics_.size(); ++i) current_->add_topic(i, topics_[i]);
    }
    current_->write(topic, timestamp_ns, data);
    ++topics_[topic].message_count;
    FileInfo& f = files_.back();
    if (f.message_count == 0) {
      f.starting_time_ns = timestamp_ns;
      file_end_ns_ = timestamp_ns;
    }
    f.starting_time_ns = std::min(f.starting_time_ns, timestamp_ns);
    file_end_ns_ = std::max(file_end_ns_, timestamp_ns);
    f.duration_ns = file_end_ns_ - f.starting_time_ns;
    ++f.message_count;
  }

  void close() {
    if (closed_) return;
    closed_ = true;
    current_->close();
    // The storage files reach the disk before the metadata.yaml that says they are whole.
    for (const auto& f : files_) sync_to_disk(dir_ / f.path);
    write_metadata();
    complete_ = true;
  }

  // For ~Writer: finishes the bag, unless an exception is unwinding the stack through it (a
  // conversion that failed half-way). Then, or when finishing fails, what was written goes: a
  // bag that looks complete but is not would mislead.
  void finish() noexcept {
    if (std::uncaught_exceptions() == exceptions_at_start_) {
      try {
        close();
      } catch (...) {  // destructors must not throw; close() reports errors to its callers
      }
    }
    if (!complete_) discard();
  }

 private:
  // Removes the files this writer wrote and the folders it made (a folder that was there before
  // stays, empty, as it was).
  void discard() noexcept {
    current_.reset();
    std::error_code ec;
    for (const auto& f : files_) fs::remove(dir_ / f.path, ec);
    fs::remove(dir_ / kMetadataFile, ec);
    for (const auto& d : created_) fs::remove(d, ec);  // only while empty
  }

  void open_file() {
    const std::string ext = options_.storage == Storage::kMcap ? ".mcap" : ".db3";
    // Named after the bag's folder, as rosbag2 names them; "out/" and "." name their folder too.
    const fs::path folder = fs::absolute(dir_).lexically_normal();
    std::string name = (folder.has_filename() ? folder : folder.parent_path()).filename().string();
    if (name.empty()) name = "bag";
    FileInfo f;
    f.path = name + "_" + std::to_string(files_.size()) + ext;
    const fs::path full = dir_ / f.path;
    current_ = options_.storage == Storage::kMcap
                   ? create_mcap(full, options_.compression, options_.chunk_size)
                   : create_sqlite3(full);
    files_.push_back(f);
  }

  void write_metadata() { write_metadata_file(dir_, options_.storage, topics_, files_); }

  fs::path dir_;
  WriteOptions options_;
  std::vector<TopicInfo> topics_;
  std::vector<FileInfo> files_;
  int64_t file_end_ns_ = 0;
  std::unique_ptr<StorageWriter> current_;
  std::vector<fs::path> created_;
  const int exceptions_at_start_ = std::uncaught_exceptions();
  bool closed_ = false;
  bool complete_ = false;  // closed, and metadata.yaml written
};

Writer::Writer(const fs::path& dir, WriteOptions options)
    : impl_(std::make_unique<Impl>(dir, options)) {}

Writer::~Writer() {
  impl_->finish();
}

std::size_t Writer::add_topic(const TopicInfo& topic) {
  return impl_->add_topic(topic);
}

void Writer::write(std::size_t topic, int64_t timestamp_ns, std::span<const uint8_t> data) {
  impl_->write(topic, timestamp_ns, data);
}

void Writer::close() {
  impl_->close();
}

BagInfo reindex(const fs::path& dir) {
  if (!fs::is_directory(dir)) throw BagError(dir.string() + ": not a directory");
  if (fs::exists(dir / kMetadataFile)) {
    throw BagError((dir / kMetadataFile).string() +
                   ": the bag has one already; remove it to index the storage files again");
  }
  // The storage files, in the order of their split index (<name>_<n>.<ext>), then by name.
  std::vector<std::pair<long, fs::path>> found;
  for (const auto& e : fs::directory_iterator(dir)) {
    const auto ext = e.path().extension();
    if (!e.is_regular_file()) continue;
    if (ext == ".zstd") {
      throw BagError(e.path().string() +
                     ": a file-compressed bag cannot be indexed (its metadata.yaml says how it was "
                     "compressed); decompress its files first");
    }
    if (ext != ".db3" && ext != ".mcap") continue;
    const std::string stem = e.path().stem().string();
    const auto underscore = stem.rfind('_');
    long index = -1;
    if (underscore != std::string::npos && underscore + 1 < stem.size() &&
        stem.find_first_not_of("0123456789", underscore + 1) == std::string::npos) {
      index = std::stol(stem.substr(underscore + 1));
    }
    found.emplace_back(index, e.path());
  }
  if (found.empty()) throw BagError(dir.string() + ": no .db3 or .mcap file to index");
  std::sort(found.begin(), found.end());

  BagInfo info;
  info.path = dir;
  info.storage = sniff_storage(found.front().second);
  std::map<std::string, std::size_t> topic_index;
  for (const auto& [index, file] : found) {
    if (sniff_storage(file) != info.storage) {
      throw BagError(file.string() + ": is " + to_string(sniff_storage(file)) + " but " +
                     found.front().second.filename().string() + " is " + to_string(info.storage) +
                     "; a bag has one storage");
    }
    const auto reader = open_storage(file, {});
    FileInfo f;
    f.path = file.filename();
    for (const auto& t : reader->topics()) {
      f.message_count += t.message_count;
      auto [it, added] = topic_index.try_emplace(t.name, info.topics.size());
      if (added) {
        info.topics.push_back(t);
        continue;
      }
      TopicInfo& known = info.topics[it->second];
      if (known.type != t.type) {
        throw BagError(file.string() + ": topic " + t.name + " holds " + t.type + ", but " +
                       known.type + " in an earlier file");
      }
      known.message_count += t.message_count;
    }
    if (f.message_count) {
      f.starting_time_ns = reader->start_time_ns();
      f.duration_ns = reader->end_time_ns() - reader->start_time_ns();
    }
    info.message_count += f.message_count;
    info.bytes += fs::file_size(file);
    info.files.push_back(f);
  }
  write_metadata_file(dir, info.storage, info.topics, info.files);
  return read_info(dir);
}

uint64_t convert(const fs::path& in, const fs::path& out, const WriteOptions& options,
                 const std::function<void(TopicInfo&)>& complete) {
  Reader reader(in);
  Writer writer(out, options);
  std::vector<std::size_t> ids;
  const auto add = [&](TopicInfo topic) {
    if (complete) complete(topic);
    ids.push_back(writer.add_topic(topic));
  };
  for (const auto& t : reader.topics()) add(t);
  uint64_t n = 0;
  Message m;
  while (reader.next(m)) {
    // Topics first seen in a later file of a split bag.
    while (ids.size() < reader.topics().size()) add(reader.topics()[ids.size()]);
    writer.write(ids.at(m.topic), m.timestamp_ns, m.data);
    ++n;
  }
  writer.close();
  return n;
}

}  // namespace robotperf::bag
