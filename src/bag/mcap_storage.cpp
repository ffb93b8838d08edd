// MCAP storage (https://mcap.dev/spec) with the ros2 profile: one channel per
// topic (message_encoding "cdr", QoS in the channel metadata), one "ros2msg"
// schema per type, messages in optionally compressed chunks.
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <map>
#include <memory>
#include <span>
#include <tuple>

#include "mcap_format.hpp"
#include "read_ahead.hpp"
#include "robotperf/bag/bag.hpp"
#include "robotperf/build_info.hpp"

namespace robotperf::bag {
namespace {

namespace fs = std::filesystem;
using mcap::Cursor;
using mcap::FormatError;

// The file, mapped read-only: chunks are parsed (and uncompressed messages
// copied out) straight from the page cache, with no read() copy in between.
class File {
 public:
  explicit File(const fs::path& path) : path_(path) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) throw BagError(path.string() + ": cannot open: " + std::strerror(errno));
    struct stat st {};
    if (::fstat(fd, &st) != 0) {
      const int e = errno;
      ::close(fd);
      throw BagError(path.string() + ": cannot stat: " + std::strerror(e));
    }
    size_ = static_cast<uint64_t>(st.st_size);
    if (size_ > 0) {
      void* map = ::mmap(nullptr, size_, PROT_READ, MAP_PRIVATE, fd, 0);
      if (map == MAP_FAILED) {
        const int e = errno;
        ::close(fd);
        throw BagError(path.string() + ": cannot map: " + std::strerror(e));
      }
      ::madvise(map, size_, MADV_SEQUENTIAL);
      data_ = static_cast<const uint8_t*>(map);
    }
    ::close(fd);
  }
  ~File() {
    if (data_ != nullptr) ::munmap(const_cast<uint8_t*>(data_), size_);
  }
  File(const File&) = delete;
  File& operator=(const File&) = delete;

  uint64_t size() const { return size_; }

  // `n` bytes at `offset`, valid as long as the File.
  std::span<const uint8_t> view(uint64_t offset, uint64_t n) const {
    if (offset > size_ || n > size_ - offset) {
      throw BagError(path_.string() + ": truncated: " + std::to_string(n) + " bytes at offset " +
                     std::to_string(offset) + " lie past the end of the " + std::to_string(size_) +
                     "-byte file");
    }
    return {data_ + offset, static_cast<std::size_t>(n)};
  }

  void read(uint64_t offset, uint64_t n, std::vector<uint8_t>& out) const {
    const auto bytes = view(offset, n);
    out.assign(bytes.begin(), bytes.end());
  }

 private:
  fs::path path_;
  const uint8_t* data_ = nullptr;
  uint64_t size_ = 0;
};

struct Schema {
  std::string name;
  std::string encoding;
  std::string data;
};

struct Channel {
  uint16_t schema_id = 0;
  std::string topic;
  std::string message_encoding;
  std::map<std::string, std::string> metadata;
};

// Something that holds messages: a chunk or a message outside any chunk.
struct Unit {
  uint64_t start_time = 0;
  uint64_t offset = 0;  // of the record
  uint64_t length = 0;  // of the whole record, prefix included
  bool chunk = true;
};

// A message waiting in the merge heap. Its bytes stay in the buffer of the
// chunk (or record) they came from until next() copies them out.
struct Pending {
  uint64_t log_time;
  std::size_t unit;
  std::size_t position;
  std::size_t topic;
  std::shared_ptr<std::vector<uint8_t>> buffer;
  std::span<const uint8_t> data;
};

// Min-heap order: earliest log_time first; ties in file order.
bool later(const Pending& a, const Pending& b) {
  return std::tie(a.log_time, a.unit, a.position) > std::tie(b.log_time, b.unit, b.position);
}

class McapReader final : public StorageReader {
 public:
  McapReader(const fs::path& path, const ReadOptions& options)
      : path_(path), file_(path), options_(options) {
    try {
      open();
    } catch (const FormatError& e) {
      fail(e.what());
    }
  }

  const std::vector<TopicInfo>& topics() const override { return topics_; }
  int64_t start_time_ns() const override { return static_cast<int64_t>(start_); }
  int64_t end_time_ns() const override { return static_cast<int64_t>(end_); }

  bool next(Message& out) override {
    if (!read_ahead_) start_read_ahead();
    try {
      while (next_unit_ < units_.size() &&
             (heap_.empty() || units_[next_unit_].start_time <= heap_.front().log_time)) {
        load_unit(next_unit_++);
      }
    } catch (const FormatError& e) {
      fail(e.what());
    }
    if (heap_.empty()) return false;
    std::pop_heap(heap_.begin(), heap_.end(), later);
    Pending& p = heap_.back();
    out.topic = p.topic;
    out.timestamp_ns = static_cast<int64_t>(p.log_time);
    // Into the caller's buffer, whose capacity is reused from message to message.
    out.data.assign(p.data.begin(), p.data.end());
    // The last message of a buffer hands it back for a later chunk.
    if (p.buffer.use_count() == 1) read_ahead_->give_back(std::move(p.buffer));
    heap_.pop_back();
    return true;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw BagError(path_.string() + ": " + what);
  }

  void open() {
    const uint64_t size = file_.size();
    if (size < sizeof(mcap::kMagic))
      fail("too short to be an MCAP file (" + std::to_string(size) + " bytes)");
    file_.read(0, sizeof(mcap::kMagic), buffer_);
    if (std::memcmp(buffer_.data(), mcap::kMagic, sizeof(mcap::kMagic)) != 0)
      fail("wrong magic: not an MCAP file");
    const uint64_t tail = mcap::kFooterRecordSize + sizeof(mcap::kMagic);
    bool finished = false;
    if (size >= sizeof(mcap::kMagic) + tail) {
      file_.read(size - tail, tail, buffer_);
      finished = std::memcmp(buffer_.data() + mcap::kFooterRecordSize, mcap::kMagic,
                             sizeof(mcap::kMagic)) == 0 &&
                 buffer_[0] == mcap::kFooter;
    }
    if (!finished) {
      fail("truncated: no footer and closing magic at the end (was the recording cut short?)");
    }
    footer_offset_ = size - tail;
    Cursor footer(std::span<const uint8_t>(buffer_).subspan(mcap::kRecordPrefix));
    const uint64_t summary_start = footer.u64();
    footer.u64();  // summary_offset_start: the summary is read whole, no need to jump
    const uint32_t summary_crc = footer.u32();
    bool indexed = false;
    if (summary_start != 0) {
      if (summary_start < sizeof(mcap::kMagic) || summary_start > footer_offset_)
        fail("footer points to a summary section outside the file");
      indexed = read_summary(summary_start, summary_crc);
    }
    if (!indexed) scan_data_section();
    build_topics();
  }

  // Reads schemas, channels, statistics and chunk indexes. False when the
  // summary cannot locate every message (no chunk indexes) or, without
  // statistics, cannot count them (no message indexes), so a linear scan is
  // needed.
  bool read_summary(uint64_t summary_start, uint32_t summary_crc) {
    // The CRC covers the summary and the footer up to its crc field.
    file_.read(summary_start, footer_offset_ + mcap::kFooterRecordSize - 4 - summary_start,
               buffer_);
    if (options_.verify_crc && summary_crc != 0 && mcap::crc32(buffer_) != summary_crc)
      fail("summary section CRC mismatch (file corrupt)");
    Cursor records(std::span<const uint8_t>(buffer_).first(footer_offset_ - summary_start));
    bool have_statistics = false;
    uint64_t statistics_messages = 0;
    std::vector<uint64_t> message_indexes;  // offsets of the message index records of all chunks
    bool every_chunk_indexed = true;
    while (!records.done()) {
      const uint8_t op = records.u8();
      Cursor r(records.bytes64());
      switch (op) {
        case mcap::kSchema:
          read_schema(r);
          break;
        case mcap::kChannel:
          read_channel(r);
          break;
        case mcap::kStatistics: {
          have_statistics = true;
          statistics_messages = r.u64();
          r.u16();  // schema_count
          r.u32();  // channel_count
          r.u32();  // attachment_count
          r.u32();  // metadata_count
          r.u32();  // chunk_count
          start_ = r.u64();
          end_ = r.u64();
          Cursor counts(r.bytes32());
          while (!counts.done()) {
            const uint16_t channel = counts.u16();
            counts_[channel] = counts.u64();
          }
          break;
        }
        case mcap::kChunkIndex: {
          Unit u;
          u.start_time = r.u64();
          const uint64_t end_time = r.u64();
          u.offset = r.u64();
          u.length = r.u64();
          // Which channels the chunk holds: skip it when none is selected.
          Cursor channels(r.bytes32());
          every_chunk_indexed = every_chunk_indexed && !channels.done();
          bool wanted = false;
          while (!channels.done()) {
            const uint16_t channel = channels.u16();
            message_indexes.push_back(channels.u64());
            wanted = wanted || channel_selected_by_name(channel);
          }
          if (!wanted || outside_window(u.start_time, end_time)) break;
          if (u.offset < sizeof(mcap::kMagic) || u.offset > footer_offset_ ||
              u.length > footer_offset_ - u.offset)
            fail("chunk index points outside the data section");
          units_.push_back(u);
          break;
        }
        default:
          break;  // other summary records are not needed to read messages
      }
    }
    std::stable_sort(units_.begin(), units_.end(),
                     [](const Unit& a, const Unit& b) { return a.start_time < b.start_time; });
    if (units_.empty() && !(have_statistics && statistics_messages == 0)) return false;
    if (!have_statistics) {
      if (!every_chunk_indexed) return false;
      count_indexed_messages(message_indexes);
    }
    return true;
  }

  // Without a Statistics record (it is optional): the counts and the first and
  // last log times from the message index records, which list every message of
  // their chunk with its log time.
  void count_indexed_messages(const std::vector<uint64_t>& message_indexes) {
    bool first = true;
    for (const uint64_t offset : message_indexes) {
      if (offset > footer_offset_ || footer_offset_ - offset < mcap::kRecordPrefix)
        fail("chunk index points to a message index outside the data section");
      Cursor prefix(file_.view(offset, mcap::kRecordPrefix));
      const uint8_t op = prefix.u8();
      const uint64_t length = prefix.u64();
      if (op != mcap::kMessageIndex) {
        fail("chunk index points to a record of opcode " + std::to_string(op) + " at offset " +
             std::to_string(offset) + ", not a message index");
      }
      Cursor r(file_.view(offset + mcap::kRecordPrefix, length));
      const uint16_t channel = r.u16();
      Cursor entries(r.bytes32());
      while (!entries.done()) {
        const uint64_t log_time = entries.u64();
        entries.u64();  // offset of the message in the chunk
        ++counts_[channel];
        start_ = first ? log_time : std::min(start_, log_time);
        end_ = first ? log_time : std::max(end_, log_time);
        first = false;
      }
    }
  }

  // Without a usable summary: walk every record of the data section, reading
  // schemas and channels (also inside chunks) and counting messages.
  void scan_data_section() {
    units_.clear();
    counts_.clear();
    bool first = true;
    uint64_t offset = sizeof(mcap::kMagic);
    std::vector<uint8_t> record;
    while (offset < footer_offset_) {
      if (footer_offset_ - offset < mcap::kRecordPrefix)
        fail("truncated record at offset " + std::to_string(offset));
      file_.read(offset, mcap::kRecordPrefix, record);
      const uint8_t op = record[0];
      uint64_t length;
      std::memcpy(&length, record.data() + 1, 8);
      if (length > footer_offset_ - offset - mcap::kRecordPrefix) {
        fail("truncated: record at offset " + std::to_string(offset) + " (opcode " +
             std::to_string(op) + ") claims " + std::to_string(length) +
             " bytes, more than the file holds");
      }
      if (op == mcap::kDataEnd) break;
      const Unit unit{0, offset, mcap::kRecordPrefix + length, op == mcap::kChunk};
      if (op == mcap::kSchema || op == mcap::kChannel || op == mcap::kMessage ||
          op == mcap::kChunk) {
        file_.read(offset + mcap::kRecordPrefix, length, record);
        Cursor r(record);
        if (op == mcap::kSchema) read_schema(r);
        if (op == mcap::kChannel) read_channel(r);
        if (op == mcap::kMessage || op == mcap::kChunk) {
          uint64_t unit_start = UINT64_MAX;
          auto count = [&](uint16_t channel, uint64_t log_time) {
            ++counts_[channel];
            start_ = first ? log_time : std::min(start_, log_time);
            end_ = first ? log_time : std::max(end_, log_time);
            first = false;
            unit_start = std::min(unit_start, log_time);
          };
          if (op == mcap::kMessage) {
            const uint16_t channel = r.u16();
            r.u32();
            count(channel, r.u64());
          } else {
            for_each_chunk_record(offset, r, [&](uint8_t inner, Cursor& c) {
              if (inner == mcap::kSchema) read_schema(c);
              if (inner == mcap::kChannel) read_channel(c);
              if (inner == mcap::kMessage) {
                const uint16_t channel = c.u16();
                c.u32();
                count(channel, c.u64());
              }
            });
          }
          if (unit_start != UINT64_MAX) {
            Unit u = unit;
            u.start_time = unit_start;
            units_.push_back(u);
          }
        }
      }
      offset += mcap::kRecordPrefix + length;
    }
    std::stable_sort(units_.begin(), units_.end(),
                     [](const Unit& a, const Unit& b) { return a.start_time < b.start_time; });
  }

  void read_schema(Cursor& r) {
    const uint16_t id = r.u16();
    Schema s;
    s.name = r.string();
    s.encoding = r.string();
    const auto data = r.bytes32();
    s.data.assign(reinterpret_cast<const char*>(data.data()), data.size());
    schemas_[id] = std::move(s);
  }

  void read_channel(Cursor& r) {
    const uint16_t id = r.u16();
    Channel c;
    c.schema_id = r.u16();
    c.topic = r.string();
    c.message_encoding = r.string();
    c.metadata = r.string_map();
    channels_[id] = std::move(c);
  }

  bool channel_selected_by_name(uint16_t channel) const {
    if (options_.topics.empty()) return true;
    auto it = channels_.find(channel);
    return it != channels_.end() && options_.topics.contains(it->second.topic);
  }

  bool outside_window(uint64_t first, uint64_t last) const {
    return (options_.end_time_ns && first > static_cast<uint64_t>(*options_.end_time_ns)) ||
           (options_.start_time_ns && last < static_cast<uint64_t>(*options_.start_time_ns));
  }

  void build_topics() {
    for (const auto& [id, c] : channels_) {
      TopicInfo t;
      t.name = c.topic;
      t.serialization_format = c.message_encoding;
      if (c.schema_id != 0) {
        auto s = schemas_.find(c.schema_id);
        if (s == schemas_.end()) {
          fail("channel " + std::to_string(id) + " (" + c.topic + ") refers to schema " +
               std::to_string(c.schema_id) + ", which the file lacks");
        }
        t.type = s->second.name;
        if (s->second.encoding != "unknown") {
          t.definition_encoding = s->second.encoding;
          t.definition = s->second.data;
        }
      }
      if (auto q = c.metadata.find("offered_qos_profiles"); q != c.metadata.end())
        t.offered_qos_profiles = q->second;
      if (auto h = c.metadata.find("topic_type_hash"); h != c.metadata.end())
        t.type_description_hash = h->second;
      if (auto n = counts_.find(id); n != counts_.end()) t.message_count = n->second;
      topic_of_channel_[id] = topics_.size();
      topics_.push_back(std::move(t));
    }
  }

  // The records of the chunk record `r`: in place when uncompressed, else
  // decompressed into `plain`. Checks the CRC of the uncompressed records.
  std::span<const uint8_t> chunk_records(uint64_t offset, Cursor& r,
                                         std::vector<uint8_t>& plain) const {
    r.u64();  // message_start_time
    r.u64();  // message_end_time
    const uint64_t uncompressed_size = r.u64();
    const uint32_t uncompressed_crc = r.u32();
    const std::string compression = r.string();
    const auto compressed = r.bytes64();
    std::span<const uint8_t> records = compressed;
    const bool check = options_.verify_crc && uncompressed_crc != 0;
    uint32_t actual_crc = 0;
    try {
      if (compression.empty()) {
        if (compressed.size() != uncompressed_size) {
          throw FormatError("uncompressed chunk holds " + std::to_string(compressed.size()) +
                            " bytes but declares " + std::to_string(uncompressed_size));
        }
        if (check) actual_crc = mcap::crc32(records);
      } else {
        mcap::decompress(compression, compressed, uncompressed_size, plain,
                         check ? &actual_crc : nullptr);
        records = plain;
      }
    } catch (const FormatError& e) {
      fail("chunk at offset " + std::to_string(offset) + ": " + e.what());
    }
    if (check && actual_crc != uncompressed_crc)
      fail("chunk at offset " + std::to_string(offset) + ": CRC mismatch (file corrupt)");
    return records;
  }

  // Calls fn(opcode, cursor) for each record inside the chunk record `r`.
  template <class Fn>
  void for_each_chunk_record(uint64_t offset, Cursor& r, Fn&& fn) {
    Cursor records(chunk_records(offset, r, chunk_));
    while (!records.done()) {
      const uint8_t op = records.u8();
      Cursor c(records.bytes64());
      fn(op, c);
    }
  }

  // Started on the first message, not on opening: a reader opened for its topics alone starts
  // no thread.
  void start_read_ahead() {
    const std::size_t threads =
        options_.chunk_threads == 0 ? online_cpus() : options_.chunk_threads;
    // One thread: everything on the reading thread, as without read-ahead. One chunk in flight
    // per worker and one more, ready for the reader while the workers start the next ones: each
    // buffer more is a chunk of fresh pages to fault in, and bought nothing measurable.
    const std::size_t workers = threads == 1 ? 0 : threads;
    read_ahead_ = std::make_unique<ReadAhead>(
        units_.size(), workers, workers + 1, [this](std::size_t unit, std::vector<uint8_t>& plain) {
          return unit_records(unit, plain);
        });
  }

  // What the read-ahead does for each unit, on any thread: a chunk's records, decompressed and
  // checked. Throws what load_unit() would throw there.
  std::span<const uint8_t> unit_records(std::size_t index, std::vector<uint8_t>& plain) const {
    const Unit& u = units_[index];
    Cursor record(file_.view(u.offset, u.length));
    const uint8_t op = record.u8();
    Cursor r(record.bytes64());
    if (op != mcap::kChunk) return {};
    return chunk_records(u.offset, r, plain);
  }

  void load_unit(std::size_t index) {
    // Units are taken in order, so this one is the read-ahead's next.
    ReadAhead::Prepared prepared = read_ahead_->take();
    const Unit& u = units_[index];
    Cursor record(file_.view(u.offset, u.length));
    const uint8_t op = record.u8();
    Cursor r(record.bytes64());
    std::size_t position = 0;
    // Messages point into the mapped file, or into `holder` when their chunk
    // had to be decompressed.
    ReadAhead::Buffer holder;
    auto take_message = [&](Cursor& c) {
      const uint16_t channel = c.u16();
      c.u32();  // sequence
      const uint64_t log_time = c.u64();
      c.u64();  // publish_time
      const auto data = c.rest();
      auto topic = topic_of_channel_.find(channel);
      if (topic == topic_of_channel_.end()) {
        fail("message at log time " + std::to_string(log_time) + " on channel " +
             std::to_string(channel) + ", which the file never defines");
      }
      if (!channel_selected_by_name(channel) || outside_window(log_time, log_time)) return;
      heap_.push_back({log_time, index, position++, topic->second, holder, data});
      std::push_heap(heap_.begin(), heap_.end(), later);
    };
    if (op == mcap::kMessage) {
      take_message(r);
    } else if (op == mcap::kChunk) {
      holder = prepared.buffer;
      Cursor records(prepared.bytes);
      while (!records.done()) {
        const uint8_t inner = records.u8();
        Cursor c(records.bytes64());
        if (inner == mcap::kMessage) take_message(c);
      }
      // No message pointed into it: back for a later chunk.
      holder.reset();
      if (prepared.buffer.use_count() == 1) read_ahead_->give_back(std::move(prepared.buffer));
    } else {
      fail("chunk index points to a record of opcode " + std::to_string(op) + " at offset " +
           std::to_string(u.offset) + ", not a chunk");
    }
  }

  fs::path path_;
  File file_;
  ReadOptions options_;
  uint64_t footer_offset_ = 0;
  std::map<uint16_t, Schema> schemas_;
  std::map<uint16_t, Channel> channels_;
  std::map<uint16_t, uint64_t> counts_;
  std::map<uint16_t, std::size_t> topic_of_channel_;
  std::vector<TopicInfo> topics_;
  uint64_t start_ = 0;
  uint64_t end_ = 0;
  std::vector<Unit> units_;
  std::size_t next_unit_ = 0;
  std::vector<Pending> heap_;
  std::vector<uint8_t> buffer_;  // magic, footer and summary being read
  std::vector<uint8_t> chunk_;   // the decompressed records of a chunk (scanning)
  // Last: its workers, which read the file and the units, stop before those go.
  std::unique_ptr<ReadAhead> read_ahead_;
};

class McapWriter final : public StorageWriter {
 public:
  McapWriter(const fs::path& path, Compression compression, std::size_t chunk_size)
      : path_(path), chunk_size_(chunk_size) {
    compression_ = compression == Compression::kNone ? "" : to_string(compression);
    out_ = std::fopen(path.c_str(), "wbx");
    if (!out_) throw BagError(path.string() + ": cannot create: " + std::strerror(errno));
    std::setvbuf(out_, nullptr, _IOFBF, 1 << 20);
    emit(std::span<const uint8_t>(mcap::kMagic, sizeof(mcap::kMagic)));
    b_.clear();
    b_.begin_record(mcap::kHeader);
    b_.string("ros2");
    b_.string(std::string("robotperf ") + build_info::kVersion);
    b_.finish_record();
    emit(b_.bytes());
  }
  ~McapWriter() override {
    try {
      close();
    } catch (const BagError&) {  // destructors must not throw; close() reports errors
    }
    if (out_) std::fclose(out_);
  }

  void add_topic(std::size_t id, const TopicInfo& t) override {
    if (id >= 0xFFFF) throw BagError(path_.string() + ": too many topics for MCAP");
    uint16_t schema_id = 0;
    if (!t.type.empty()) {
      auto it = schema_ids_.find(t.type);
      if (it == schema_ids_.end()) {
        schema_id = static_cast<uint16_t>(schemas_.size() + 1);
        schema_ids_[t.type] = schema_id;
        b_.clear();
        b_.begin_record(mcap::kSchema);
        b_.u16(schema_id);
        b_.string(t.type);
        // rosbag2's mark of a type whose definition it could not find: "unknown", no data (an
        // empty "ros2msg" would claim a type without fields).
        b_.string(t.definition_encoding.empty() ? "unknown" : t.definition_encoding);
        b_.bytes32({reinterpret_cast<const uint8_t*>(t.definition.data()), t.definition.size()});
        b_.finish_record();
        schemas_.push_back(b_.bytes());
        emit(b_.bytes());
      } else {
        schema_id = it->second;
      }
    }
    const auto channel_id = static_cast<uint16_t>(id + 1);
    std::map<std::string, std::string> metadata{{"offered_qos_profiles", t.offered_qos_profiles}};
    if (!t.type_description_hash.empty()) metadata["topic_type_hash"] = t.type_description_hash;
    b_.clear();
    b_.begin_record(mcap::kChannel);
    b_.u16(channel_id);
    b_.u16(schema_id);
    b_.string(t.name);
    b_.string(t.serialization_format);
    b_.string_map(metadata);
    b_.finish_record();
    channels_.push_back(b_.bytes());
    emit(b_.bytes());
    message_counts_[channel_id] = 0;
    sequences_[channel_id] = 0;
  }

  void write(std::size_t topic, int64_t timestamp_ns, std::span<const uint8_t> data) override {
    const auto channel = static_cast<uint16_t>(topic + 1);
    const auto time = static_cast<uint64_t>(timestamp_ns);
    if (chunk_records_.bytes().empty()) {
      chunk_start_ = time;
      chunk_end_ = time;
    }
    chunk_start_ = std::min(chunk_start_, time);
    chunk_end_ = std::max(chunk_end_, time);
    message_start_ = message_count_ ? std::min(message_start_, time) : time;
    message_end_ = message_count_ ? std::max(message_end_, time) : time;
    chunk_index_[channel].emplace_back(time, chunk_records_.bytes().size());
    chunk_records_.begin_record(mcap::kMessage);
    chunk_records_.u16(channel);
    chunk_records_.u32(sequences_[channel]++);
    chunk_records_.u64(time);
    chunk_records_.u64(time);  // publish_time: rosbag2 stores the reception time in both
    chunk_records_.raw(data.data(), data.size());
    chunk_records_.finish_record();
    ++message_counts_[channel];
    ++message_count_;
    if (chunk_records_.bytes().size() >= chunk_size_) flush_chunk();
  }

  uint64_t bytes_written() const override { return offset_ + chunk_records_.bytes().size(); }

  void close() override {
    if (closed_ || !out_) return;
    closed_ = true;
    flush_chunk();
    const uint32_t data_crc = crc_;
    b_.clear();
    b_.begin_record(mcap::kDataEnd);
    b_.u32(data_crc);
    b_.finish_record();
    emit(b_.bytes());

    // Summary: schema, channel, statistics and chunk index groups, then one
    // summary offset per group.
    const uint64_t summary_start = offset_;
    crc_ = 0;
    struct Group {
      uint8_t opcode;
      uint64_t start;
      uint64_t length;
    };
    std::vector<Group> groups;
    auto group = [&](uint8_t opcode, const std::vector<std::vector<uint8_t>>& records) {
      if (records.empty()) return;
      const uint64_t start = offset_;
      for (const auto& r : records) emit(r);
      groups.push_back({opcode, start, offset_ - start});
    };
    group(mcap::kSchema, schemas_);
    group(mcap::kChannel, channels_);
    b_.clear();
    b_.begin_record(mcap::kStatistics);
    b_.u64(message_count_);
    b_.u16(static_cast<uint16_t>(schemas_.size()));
    b_.u32(static_cast<uint32_t>(channels_.size()));
    b_.u32(0);  // attachments
    b_.u32(0);  // metadata
    b_.u32(static_cast<uint32_t>(chunk_indexes_.size()));
    b_.u64(message_start_);
    b_.u64(message_end_);
    b_.u32(static_cast<uint32_t>(message_counts_.size() * 10));
    for (const auto& [channel, n] : message_counts_) {
      b_.u16(channel);
      b_.u64(n);
    }
    b_.finish_record();
    group(mcap::kStatistics, {b_.bytes()});
    group(mcap::kChunkIndex, chunk_indexes_);
    const uint64_t summary_offset_start = offset_;
    for (const Group& g : groups) {
      b_.clear();
      b_.begin_record(mcap::kSummaryOffset);
      b_.u8(g.opcode);
      b_.u64(g.start);
      b_.u64(g.length);
      b_.finish_record();
      emit(b_.bytes());
    }
    b_.clear();
    b_.begin_record(mcap::kFooter);
    b_.u64(summary_start);
    b_.u64(summary_offset_start);
    b_.finish_record();
    // The length counts the crc that follows.
    const uint64_t footer_length = 20;
    std::memcpy(b_.bytes().data() + 1, &footer_length, 8);
    emit(b_.bytes());
    const uint32_t summary_crc = crc_;
    emit(std::span<const uint8_t>(reinterpret_cast<const uint8_t*>(&summary_crc), 4));
    emit(std::span<const uint8_t>(mcap::kMagic, sizeof(mcap::kMagic)));
    if (std::fflush(out_) != 0 || std::fclose(out_) != 0) {
      out_ = nullptr;
      throw BagError(path_.string() + ": write failed: " + std::strerror(errno));
    }
    out_ = nullptr;
  }

 private:
  void emit(std::span<const uint8_t> bytes) {
    if (std::fwrite(bytes.data(), 1, bytes.size(), out_) != bytes.size())
      throw BagError(path_.string() + ": write failed: " + std::strerror(errno));
    crc_ = mcap::crc32(bytes, crc_);
    offset_ += bytes.size();
  }

  void flush_chunk() {
    const std::vector<uint8_t>& records = chunk_records_.bytes();
    if (records.empty()) return;
    std::span<const uint8_t> payload = records;
    if (!compression_.empty()) {
      mcap::compress(compression_, records, compressed_);
      payload = compressed_;
    }
    const uint64_t chunk_start_offset = offset_;
    b_.clear();
    b_.begin_record(mcap::kChunk);
    b_.u64(chunk_start_);
    b_.u64(chunk_end_);
    b_.u64(records.size());
    b_.u32(mcap::crc32(records));
    b_.string(compression_);
    b_.u64(payload.size());
    // The payload is emitted directly, without copying it into the builder.
    const uint64_t length = b_.bytes().size() - mcap::kRecordPrefix + payload.size();
    std::memcpy(b_.bytes().data() + 1, &length, 8);
    emit(b_.bytes());
    emit(payload);
    const uint64_t chunk_length = offset_ - chunk_start_offset;

    std::map<uint16_t, uint64_t> index_offsets;
    const uint64_t index_start = offset_;
    for (const auto& [channel, entries] : chunk_index_) {
      index_offsets[channel] = offset_;
      b_.clear();
      b_.begin_record(mcap::kMessageIndex);
      b_.u16(channel);
      b_.u32(static_cast<uint32_t>(entries.size() * 16));
      for (const auto& [time, at] : entries) {
        b_.u64(time);
        b_.u64(at);
      }
      b_.finish_record();
      emit(b_.bytes());
    }
    b_.clear();
    b_.begin_record(mcap::kChunkIndex);
    b_.u64(chunk_start_);
    b_.u64(chunk_end_);
    b_.u64(chunk_start_offset);
    b_.u64(chunk_length);
    b_.u32(static_cast<uint32_t>(index_offsets.size() * 10));
    for (const auto& [channel, at] : index_offsets) {
      b_.u16(channel);
      b_.u64(at);
    }
    b_.u64(offset_ - index_start);
    b_.string(compression_);
    b_.u64(payload.size());
    b_.u64(records.size());
    b_.finish_record();
    chunk_indexes_.push_back(b_.bytes());
    chunk_records_.clear();
    chunk_index_.clear();
  }

  fs::path path_;
  std::string compression_;
  std::size_t chunk_size_;
  std::FILE* out_ = nullptr;
  uint64_t offset_ = 0;
  uint32_t crc_ = 0;  // of the data section, later of the summary
  bool closed_ = false;
  mcap::Builder b_;
  mcap::Builder chunk_records_;
  std::vector<uint8_t> compressed_;
  std::map<std::string, uint16_t> schema_ids_;
  std::vector<std::vector<uint8_t>> schemas_;
  std::vector<std::vector<uint8_t>> channels_;
  std::vector<std::vector<uint8_t>> chunk_indexes_;
  std::map<uint16_t, std::vector<std::pair<uint64_t, uint64_t>>> chunk_index_;
  std::map<uint16_t, uint64_t> message_counts_;
  std::map<uint16_t, uint32_t> sequences_;
  uint64_t message_count_ = 0;
  uint64_t message_start_ = 0;
  uint64_t message_end_ = 0;
  uint64_t chunk_start_ = 0;
  uint64_t chunk_end_ = 0;
};

}  // namespace

std::unique_ptr<StorageReader> open_mcap(const fs::path& file, const ReadOptions& options) {
  if (!fs::is_regular_file(file)) throw BagError(file.string() + ": no such file");
  return std::make_unique<McapReader>(file, options);
}

std::unique_ptr<StorageWriter> create_mcap(const fs::path& file, Compression compression,
                                           std::size_t chunk_size) {
  return std::make_unique<McapWriter>(file, compression, chunk_size);
}

}  // namespace robotperf::bag
