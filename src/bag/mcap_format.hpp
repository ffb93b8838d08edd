// Private to the bag piece: MCAP record layout (https://mcap.dev/spec), the
// little-endian primitives it is made of, and chunk (de)compression (which
// rosbag2's per-message compression shares).
#pragma once

#include <cstdint>
#include <cstring>
#include <map>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace robotperf::bag::mcap {

inline constexpr uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', 0x30, '\r', '\n'};

enum Opcode : uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kAttachment = 0x09,
  kAttachmentIndex = 0x0A,
  kStatistics = 0x0B,
  kMetadata = 0x0C,
  kMetadataIndex = 0x0D,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

// opcode (1) + record length (8)
inline constexpr std::size_t kRecordPrefix = 9;
// Footer record: prefix + summary_start (8) + summary_offset_start (8) + summary_crc (4).
inline constexpr std::size_t kFooterRecordSize = kRecordPrefix + 20;

// Thrown by Cursor when a field runs past its record; callers add the file name.
class FormatError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Reads MCAP primitives from a byte range, bounds-checked.
class Cursor {
 public:
  explicit Cursor(std::span<const uint8_t> bytes) : bytes_(bytes) {}

  std::size_t offset() const { return pos_; }
  std::size_t remaining() const { return bytes_.size() - pos_; }
  bool done() const { return pos_ == bytes_.size(); }

  uint8_t u8() { return fixed<uint8_t>(); }
  uint16_t u16() { return fixed<uint16_t>(); }
  uint32_t u32() { return fixed<uint32_t>(); }
  uint64_t u64() { return fixed<uint64_t>(); }
  std::string string() {
    const auto b = take(u32());
    return {reinterpret_cast<const char*>(b.data()), b.size()};
  }
  std::span<const uint8_t> bytes32() { return take(u32()); }
  std::span<const uint8_t> bytes64() { return take(u64()); }
  std::span<const uint8_t> rest() { return take(remaining()); }
  std::map<std::string, std::string> string_map() {
    Cursor m(bytes32());
    std::map<std::string, std::string> out;
    while (!m.done()) {
      std::string k = m.string();
      out[std::move(k)] = m.string();
    }
    return out;
  }
  std::span<const uint8_t> take(uint64_t n) {
    if (n > remaining()) {
      throw FormatError("field of " + std::to_string(n) + " bytes runs past the end of its record");
    }
    auto out = bytes_.subspan(pos_, static_cast<std::size_t>(n));
    pos_ += static_cast<std::size_t>(n);
    return out;
  }

 private:
  template <class T>
  T fixed() {
    T v;
    std::memcpy(&v, take(sizeof(T)).data(), sizeof(T));
    return v;
  }
  std::span<const uint8_t> bytes_;
  std::size_t pos_ = 0;
};

// Appends MCAP primitives to a byte vector.
class Builder {
 public:
  std::vector<uint8_t>& bytes() { return out_; }
  const std::vector<uint8_t>& bytes() const { return out_; }
  void clear() { out_.clear(); }

  void u8(uint8_t v) { fixed(v); }
  void u16(uint16_t v) { fixed(v); }
  void u32(uint32_t v) { fixed(v); }
  void u64(uint64_t v) { fixed(v); }
  void string(const std::string& s) {
    u32(static_cast<uint32_t>(s.size()));
    raw(s.data(), s.size());
  }
  void bytes32(std::span<const uint8_t> b) {
    u32(static_cast<uint32_t>(b.size()));
    raw(b.data(), b.size());
  }
  void string_map(const std::map<std::string, std::string>& m) {
    std::size_t n = 0;
    for (const auto& [k, v] : m) n += 8 + k.size() + v.size();
    u32(static_cast<uint32_t>(n));
    for (const auto& [k, v] : m) {
      string(k);
      string(v);
    }
  }
  void raw(const void* p, std::size_t n) {
    const auto* b = static_cast<const uint8_t*>(p);
    out_.insert(out_.end(), b, b + n);
  }
  // Starts a record; finish_record() fills in its length.
  void begin_record(Opcode op) {
    u8(op);
    record_start_ = out_.size();
    u64(0);
  }
  void finish_record() {
    const uint64_t n = out_.size() - record_start_ - 8;
    std::memcpy(out_.data() + record_start_, &n, 8);
  }

 private:
  template <class T>
  void fixed(T v) {
    raw(&v, sizeof(T));
  }
  std::vector<uint8_t> out_;
  std::size_t record_start_ = 0;
};

uint32_t crc32(std::span<const uint8_t> bytes, uint32_t crc = 0);

// Decompresses a chunk's records (or a rosbag2 message compressed on its own), which must come
// to exactly `uncompressed_size` bytes; throws FormatError for an unknown compression or corrupt
// data. Memory grows with the bytes actually decoded, never to a size only claimed beyond 64
// bytes per compressed byte. With `crc`, also returns the CRC-32 of the output there, computed
// piece by piece while each piece is still in cache.
void decompress(const std::string& compression, std::span<const uint8_t> in,
                uint64_t uncompressed_size, std::vector<uint8_t>& out, uint32_t* crc = nullptr);
// Compresses `in` with "zstd" or "lz4" (frame format).
void compress(const std::string& compression, std::span<const uint8_t> in,
              std::vector<uint8_t>& out);

}  // namespace robotperf::bag::mcap
