// Bad input gives one clear line naming the file and the problem.
#include <sqlite3.h>

#include <cstring>

#include "allocation_limit.hpp"
#include "bag_test_util.hpp"
#include "mcap_format.hpp"

namespace robotperf::bag {
namespace {

using namespace testing;

// Reads the whole bag; returns the error text ("" when it read fine).
std::string error_of(const fs::path& path) {
  try {
    read_all(path);
  } catch (const BagError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.find('\n'), std::string::npos) << "not one line: " << what;
    return what;
  }
  return "";
}

void expect_error(const fs::path& path, const std::string& names, const std::string& says) {
  const std::string what = error_of(path);
  EXPECT_NE(what.find(names), std::string::npos) << "'" << what << "' does not name " << names;
  EXPECT_NE(what.find(says), std::string::npos) << "'" << what << "' does not say " << says;
}

std::vector<uint8_t> talker() {
  return read_file(reference_bag("mcap_talker") / "talker.mcap");
}

// The only chunk of talker.mcap starts at offset 45: prefix (9), start and
// end times (16), uncompressed size (8), then the crc (4) and the compression.
constexpr std::size_t kChunk = 45;
constexpr std::size_t kChunkUncompressedSize = kChunk + 9 + 16;
constexpr std::size_t kChunkCrc = kChunk + 9 + 24;
constexpr std::size_t kChunkCompression = kChunkCrc + 4 + 4;

TEST(BagErrors, TruncatedMcap) {
  ScratchDir dir;
  auto bytes = talker();
  bytes.resize(bytes.size() / 2);
  write_file(dir / "t.mcap", bytes);
  expect_error(dir / "t.mcap", "t.mcap", "truncated");
}

TEST(BagErrors, TruncatedMcapRecordInLinearScan) {
  ScratchDir dir;
  auto bytes = talker();
  // Keep the footer (no summary) but cut the data section short.
  std::vector<uint8_t> cut(bytes.begin(), bytes.begin() + 2000);
  cut.insert(cut.end(), bytes.end() - 37, bytes.end());
  std::memset(cut.data() + cut.size() - 37 + 9, 0, 20);
  write_file(dir / "t.mcap", cut);
  expect_error(dir / "t.mcap", "t.mcap", "truncated");
}

TEST(BagErrors, ChunkCrcMismatch) {
  ScratchDir dir;
  auto bytes = talker();
  ASSERT_EQ(std::memcmp(bytes.data() + kChunkCompression, "zstd", 4), 0);
  bytes[kChunkCrc] ^= 0xFF;
  write_file(dir / "crc.mcap", bytes);
  expect_error(dir / "crc.mcap", "crc.mcap", "CRC mismatch");
  // Without verification the messages still come out.
  ReadOptions no_crc;
  no_crc.verify_crc = false;
  EXPECT_EQ(read_all(dir / "crc.mcap", no_crc).size(), 20u);
}

TEST(BagErrors, CorruptPayloadInAnUncompressedChunk) {
  ScratchDir dir;
  convert(reference_bag("mcap_talker"), dir / "plain", {Storage::kMcap, Compression::kNone});
  auto bytes = read_file(dir / "plain" / "plain_0.mcap");
  // Flip a character of a "Hello, world!" inside the chunk.
  const char needle[] = "Hello, world! 3";
  auto it = std::search(bytes.begin(), bytes.end(), needle, needle + sizeof(needle) - 1);
  ASSERT_NE(it, bytes.end());
  *it ^= 0x20;
  write_file(dir / "plain" / "plain_0.mcap", bytes);
  expect_error(dir / "plain", "plain_0.mcap", "CRC mismatch");
}

TEST(BagErrors, WrongMagic) {
  ScratchDir dir;
  auto bytes = talker();
  bytes[1] = 'X';
  write_file(dir / "m.mcap", bytes);
  expect_error(dir / "m.mcap", "m.mcap", "magic");
  write_file(dir / "text.db3", {'h', 'e', 'l', 'l', 'o', '\n'});
  expect_error(dir / "text.db3", "text.db3", "wrong magic");
}

TEST(BagErrors, UnknownChunkCompression) {
  ScratchDir dir;
  auto bytes = talker();
  std::memcpy(bytes.data() + kChunkCompression, "zxxd", 4);
  write_file(dir / "c.mcap", bytes);
  expect_error(dir / "c.mcap", "c.mcap", "unknown compression 'zxxd'");
}

// A forged uncompressed size must not make the reader allocate it: more than the zstd frame
// can hold is refused up front.
TEST(BagErrors, ChunkClaimsMoreThanItsFrameHolds) {
  ScratchDir dir;
  auto bytes = talker();
  const uint64_t claim = uint64_t{1} << 40;
  std::memcpy(bytes.data() + kChunkUncompressedSize, &claim, sizeof(claim));
  write_file(dir / "bomb.mcap", bytes);
  expect_error(dir / "bomb.mcap", "bomb.mcap", "claims 1099511627776 uncompressed bytes");
}

// A zstd frame whose header claims `claimed` bytes, single segment, but whose one block (raw,
// the last) holds a single byte.
std::vector<uint8_t> lying_zstd_frame(uint64_t claimed) {
  std::vector<uint8_t> frame = {0x28, 0xb5, 0x2f, 0xfd, 0xe0};
  for (int i = 0; i < 8; ++i) frame.push_back(static_cast<uint8_t>(claimed >> (8 * i)));
  frame.insert(frame.end(), {0x09, 0x00, 0x00, 0x00});
  return frame;
}

// An MCAP file, without summary, of one std_msgs/String channel and one zstd chunk holding
// `compressed` and claiming `uncompressed_size` bytes.
std::vector<uint8_t> one_chunk_mcap(const std::vector<uint8_t>& compressed,
                                    uint64_t uncompressed_size) {
  mcap::Builder b;
  b.raw(mcap::kMagic, sizeof(mcap::kMagic));
  b.begin_record(mcap::kHeader);
  b.string("ros2");
  b.string("test");
  b.finish_record();
  b.begin_record(mcap::kSchema);
  b.u16(1);
  b.string("std_msgs/msg/String");
  b.string("ros2msg");
  b.string("string data\n");
  b.finish_record();
  b.begin_record(mcap::kChannel);
  b.u16(1);
  b.u16(1);
  b.string("/t");
  b.string("cdr");
  b.string_map({});
  b.finish_record();
  b.begin_record(mcap::kChunk);
  b.u64(1);
  b.u64(1);
  b.u64(uncompressed_size);
  b.u32(0);
  b.string("zstd");
  b.u64(compressed.size());
  b.raw(compressed.data(), compressed.size());
  b.finish_record();
  b.begin_record(mcap::kDataEnd);
  b.u32(0);
  b.finish_record();
  b.begin_record(mcap::kFooter);
  b.u64(0);
  b.u64(0);
  b.u32(0);
  b.finish_record();
  b.raw(mcap::kMagic, sizeof(mcap::kMagic));
  return b.bytes();
}

// Sizes a frame header claims, each refused in its own way: decoded to the frame's end (100 MiB),
// past the window zstd accepts (4 and 6 GiB), beyond any memory (1 TiB).
constexpr uint64_t kClaims[] = {uint64_t{100} << 20, uint64_t{4} << 30, uint64_t{6} << 30,
                                uint64_t{1} << 40};

// A chunk that claims what its zstd frame header claims passes the size check; reading it must
// still not allocate the claim before the bytes come (zstd finds the frame short only at its
// end): the reader's own error, not bad_alloc nor gigabytes of zeros.
TEST(BagErrors, ChunkWhoseZstdFrameClaimsGigabytesItDoesNotHold) {
  ScratchDir dir;
  for (const uint64_t claim : kClaims) {
    SCOPED_TRACE(claim);
    write_file(dir / "bomb.mcap", one_chunk_mcap(lying_zstd_frame(claim), claim));
    const robotperf::testing::AllocationLimit limit(16 << 20);
    expect_error(dir / "bomb.mcap", "bomb.mcap", "zstd");
  }
}

// rosbag2's message compression: each message one zstd frame, whose header says its size.
TEST(BagErrors, CompressedMessageWhoseFrameClaimsGigabytesItDoesNotHold) {
  ScratchDir dir;
  for (const uint64_t claim : kClaims) {
    SCOPED_TRACE(claim);
    const fs::path bag = dir / std::to_string(claim);
    {
      Writer w(bag, {Storage::kSqlite3, Compression::kNone});
      TopicInfo topic;
      topic.name = "/t";
      topic.type = "std_msgs/msg/String";
      w.write(w.add_topic(topic), 5, lying_zstd_frame(claim));
    }
    const auto yaml = read_file(bag / "metadata.yaml");
    std::string text(yaml.begin(), yaml.end());
    for (const std::string key : {"compression_format: ", "compression_mode: "}) {
      const auto at = text.find(key + "\"\"");
      ASSERT_NE(at, std::string::npos) << key;
      text.replace(at, key.size() + 2, key + (key == "compression_format: " ? "zstd" : "message"));
    }
    write_file(bag / "metadata.yaml", {text.begin(), text.end()});
    const robotperf::testing::AllocationLimit limit(16 << 20);
    expect_error(bag, std::to_string(claim) + "_0.db3", "a message on /t does not decompress");
  }
}

TEST(BagErrors, MissingMetadataYaml) {
  ScratchDir dir;
  fs::create_directories(dir / "bag");
  expect_error(dir / "bag", "bag", "no metadata.yaml");
  expect_error(dir / "nothing", "nothing", "no such file");
}

TEST(BagErrors, MalformedMetadataYaml) {
  ScratchDir dir;
  fs::create_directories(dir / "bag");
  write_file(dir / "bag" / "metadata.yaml",
             {'r', 'o', 's', 'b', 'a', 'g', ':', ' ', '[', 'x', '\n'});
  expect_error(dir / "bag", "metadata.yaml", "malformed YAML");
}

// An entry of the wrong kind in one of metadata.yaml's lists is one line naming the file and
// the line, as a field of the wrong type is.
TEST(BagErrors, MetadataListEntryOfTheWrongKind) {
  ScratchDir dir;
  const auto reference = read_file(reference_bag("sqlite3_cdr_test") / "metadata.yaml");
  const std::string original(reference.begin(), reference.end());
  struct WrongEntry {
    std::string list, entry, says;
  };
  const WrongEntry entries[] = {
      {"relative_file_paths:\n", "    - {a: b}\n", "line 27: an entry of 'relative_file_paths'"},
      {"files:\n", "    - cdr_test_0.db3\n", "line 29: an entry of 'files'"},
      {"topics_with_message_count:\n", "    - /test_topic\n", "line 10: topic entry without"}};
  for (const auto& [list, entry, says] : entries) {
    SCOPED_TRACE(list);
    const fs::path bag = dir / list.substr(0, list.find(':'));
    fs::create_directories(bag);
    fs::copy_file(reference_bag("sqlite3_cdr_test") / "cdr_test_0.db3", bag / "cdr_test_0.db3");
    std::string text = original;
    text.insert(text.find(list) + list.size(), entry);
    write_file(bag / "metadata.yaml", {text.begin(), text.end()});
    expect_error(bag, "metadata.yaml", says);
  }
}

TEST(BagErrors, MetadataListsAMissingFile) {
  ScratchDir dir;
  fs::create_directories(dir / "bag");
  fs::copy_file(reference_bag("sqlite3_cdr_test") / "metadata.yaml", dir / "bag" / "metadata.yaml");
  expect_error(dir / "bag", "cdr_test_0.db3", "missing");
}

TEST(BagErrors, UnknownBagCompressionInMetadata) {
  ScratchDir dir;
  convert(reference_bag("sqlite3_cdr_test"), dir / "bag", {Storage::kSqlite3, Compression::kNone});
  auto yaml = read_file(dir / "bag" / "metadata.yaml");
  std::string text(yaml.begin(), yaml.end());
  const std::string empty = "compression_format: \"\"";
  text.replace(text.find(empty), empty.size(), "compression_format: brotli");
  write_file(dir / "bag" / "metadata.yaml", {text.begin(), text.end()});
  expect_error(dir / "bag", "metadata.yaml", "'brotli' is unknown");
}

TEST(BagErrors, SqliteFileThatIsNotABag) {
  ScratchDir dir;
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open((dir / "other.db3").c_str(), &db), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(db, "CREATE TABLE people(name TEXT)", nullptr, nullptr, nullptr),
            SQLITE_OK);
  sqlite3_close(db);
  expect_error(dir / "other.db3", "other.db3", "not a rosbag2 bag");
}

TEST(BagErrors, TruncatedSqliteFile) {
  ScratchDir dir;
  auto bytes = read_file(reference_bag("sqlite3_cdr_test") / "cdr_test_0.db3");
  bytes.resize(5000);
  write_file(dir / "cut.db3", bytes);
  const std::string what = error_of(dir / "cut.db3");
  EXPECT_NE(what.find("cut.db3"), std::string::npos) << what;
  EXPECT_FALSE(what.empty());
}

}  // namespace
}  // namespace robotperf::bag
