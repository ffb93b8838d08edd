// MCAP chunks decompressed ahead of the reading on worker threads: the same messages in the same
// order as on the reading thread alone, the same errors at the same point, a bounded read-ahead,
// and no thread left behind by a reader destroyed halfway.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstring>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "bag_test_util.hpp"
#include "mcap_format.hpp"
#include "read_ahead.hpp"

namespace robotperf::bag {
namespace {

using namespace testing;

std::size_t thread_count() {
  return static_cast<std::size_t>(
      std::distance(fs::directory_iterator("/proc/self/task"), fs::directory_iterator()));
}

// join() returns once a thread has finished, a moment before the kernel removes it from
// /proc/self/task: waits for that, however long a loaded machine takes, up to a minute.
std::size_t thread_count_once_down_to(std::size_t expected) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(1);
  std::size_t n = thread_count();
  while (n > expected && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::yield();
    n = thread_count();
  }
  return n;
}

// Two topics of messages of 1 to 12 KiB, compressible but each its own, with log times that
// step back now and then so that chunks overlap in time; small chunks, so hundreds of them.
void write_chunky_bag(const fs::path& dir, Compression compression, int messages) {
  WriteOptions options{Storage::kMcap, compression};
  options.chunk_size = 32 * 1024;
  Writer writer(dir, options);
  TopicInfo image;
  image.name = "/image";
  image.type = "sensor_msgs/msg/Image";
  TopicInfo info = image;
  info.name = "/info";
  const std::size_t topics[] = {writer.add_topic(image), writer.add_topic(info)};
  for (int i = 0; i < messages; ++i) {
    std::vector<uint8_t> data(1024 + static_cast<std::size_t>(i * 977 % (11 * 1024)));
    for (std::size_t j = 0; j < data.size(); ++j)
      data[j] = static_cast<uint8_t>(i * 31 + static_cast<int>(j / 64));
    const int64_t time = 1'000'000 + int64_t{i} * 1000 - (i % 5 == 0 ? 2500 : 0);
    writer.write(topics[i % 2], time, data);
  }
  writer.close();
}

fs::path storage_file(const fs::path& dir) {
  return dir / (dir.filename().string() + "_0.mcap");
}

std::vector<Recorded> read_with(const fs::path& bag, std::size_t threads,
                                ReadOptions options = {}) {
  options.chunk_threads = threads;
  return read_all(bag, options);
}

// Offsets of the chunk records of an MCAP file, in file order.
std::vector<std::size_t> chunk_offsets(const std::vector<uint8_t>& file) {
  std::vector<std::size_t> out;
  std::size_t at = sizeof(mcap::kMagic);
  while (at + mcap::kRecordPrefix <= file.size() && file[at] != mcap::kDataEnd) {
    uint64_t length;
    std::memcpy(&length, file.data() + at + 1, sizeof(length));
    if (file[at] == mcap::kChunk) out.push_back(at);
    at += mcap::kRecordPrefix + length;
  }
  return out;
}

struct PartialRead {
  std::vector<Recorded> messages;
  std::string error;
};

PartialRead read_until_error(const fs::path& bag, std::size_t threads) {
  PartialRead out;
  ReadOptions options;
  options.chunk_threads = threads;
  try {
    Reader reader(bag, options);
    Message m;
    while (reader.next(m))
      out.messages.push_back({reader.topics()[m.topic].name, m.timestamp_ns, m.data});
  } catch (const BagError& e) {
    out.error = e.what();
  }
  return out;
}

class ChunkReadAhead : public ::testing::TestWithParam<Compression> {};

TEST_P(ChunkReadAhead, WorkersDeliverTheMessagesOfTheReadingThreadAlone) {
  ScratchDir dir;
  write_chunky_bag(dir / "bag", GetParam(), 1500);
  ASSERT_GT(chunk_offsets(read_file(storage_file(dir / "bag"))).size(), 100u);
  const auto alone = read_with(dir / "bag", 1);
  ASSERT_EQ(alone.size(), 1500u);
  EXPECT_TRUE(std::is_sorted(alone.begin(), alone.end(), [](const auto& a, const auto& b) {
    return a.timestamp_ns < b.timestamp_ns;
  }));
  EXPECT_EQ(read_with(dir / "bag", 2), alone);
  EXPECT_EQ(read_with(dir / "bag", 5), alone);
  EXPECT_EQ(read_with(dir / "bag", 0), alone);
  convert(dir / "bag", dir / "plain", {Storage::kMcap, Compression::kNone});
  EXPECT_EQ(read_with(dir / "plain", 1), alone);
  EXPECT_EQ(read_with(dir / "plain", 3), alone);
  // A topic and a time window leave chunks out: the workers skip the same ones.
  ReadOptions some;
  some.topics = {"/info"};
  some.start_time_ns = 1'200'000;
  some.end_time_ns = 1'300'000;
  const auto window = read_with(dir / "bag", 1, some);
  EXPECT_FALSE(window.empty());
  EXPECT_EQ(read_with(dir / "bag", 4, some), window);
}

TEST_P(ChunkReadAhead, ACorruptChunkFailsAsOnTheReadingThreadAfterTheMessagesBeforeIt) {
  ScratchDir dir;
  write_chunky_bag(dir / "bag", GetParam(), 1500);
  const fs::path file = storage_file(dir / "bag");
  const auto whole = read_with(dir / "bag", 1);
  auto bytes = read_file(file);
  const auto chunks = chunk_offsets(bytes);
  ASSERT_GT(chunks.size(), 100u);
  const std::size_t corrupt = chunks[chunks.size() / 2];
  // Its CRC (a mismatch), then a byte of its compressed data (a decoding error or a mismatch).
  const std::size_t crc_at = corrupt + mcap::kRecordPrefix + 24;
  mcap::Cursor chunk(std::span<const uint8_t>(bytes).subspan(crc_at + 4));
  chunk.string();  // compression
  const std::size_t compressed = chunk.u64();
  const std::size_t data_at = crc_at + 4 + chunk.offset() + compressed / 2;
  for (const std::size_t at : {crc_at, data_at}) {
    SCOPED_TRACE(at == crc_at ? "crc" : "data");
    auto broken = bytes;
    broken[at] ^= 0x5A;
    write_file(file, broken);
    const std::size_t threads_before = thread_count();
    const PartialRead alone = read_until_error(dir / "bag", 1);
    EXPECT_NE(alone.error.find("chunk at offset " + std::to_string(corrupt) + ": "),
              std::string::npos)
        << alone.error;
    ASSERT_GT(alone.messages.size(), 0u);
    ASSERT_LT(alone.messages.size(), whole.size());
    EXPECT_TRUE(std::equal(alone.messages.begin(), alone.messages.end(), whole.begin()));
    for (const std::size_t threads : {2, 4}) {
      const PartialRead parallel = read_until_error(dir / "bag", threads);
      EXPECT_EQ(parallel.error, alone.error) << threads << " threads";
      EXPECT_EQ(parallel.messages, alone.messages) << threads << " threads";
    }
    EXPECT_EQ(thread_count_once_down_to(threads_before), threads_before);
  }
}

INSTANTIATE_TEST_SUITE_P(Compressions, ChunkReadAhead,
                         ::testing::Values(Compression::kZstd, Compression::kLz4),
                         [](const auto& info) { return to_string(info.param); });

TEST(ChunkReadAhead, AReaderDestroyedHalfwayStopsItsWorkers) {
  ScratchDir dir;
  write_chunky_bag(dir / "bag", Compression::kZstd, 6000);
  const std::size_t before = thread_count();
  std::chrono::duration<double> destroying{};
  {
    ReadOptions options;
    options.chunk_threads = 4;
    auto reader = std::make_unique<Reader>(dir / "bag", options);
    Message m;
    for (int i = 0; i < 100; ++i) ASSERT_TRUE(reader->next(m));
    EXPECT_EQ(thread_count(), before + 4);
    const auto start = std::chrono::steady_clock::now();
    reader.reset();
    destroying = std::chrono::steady_clock::now() - start;
  }
  // Each worker finishes at most its chunk of 32 KiB: milliseconds, seconds on a loaded machine.
  EXPECT_LT(destroying.count(), 10.0);
  EXPECT_EQ(thread_count_once_down_to(before), before);
}

// The units' values, in the order taken.
std::vector<std::size_t> take_all(ReadAhead& read_ahead, std::size_t units) {
  std::vector<std::size_t> out;
  for (std::size_t i = 0; i < units; ++i) {
    const ReadAhead::Prepared p = read_ahead.take();
    std::size_t value;
    std::memcpy(&value, p.bytes.data(), sizeof(value));
    out.push_back(value);
    if (p.buffer.use_count() == 1) read_ahead.give_back(p.buffer);
  }
  return out;
}

std::span<const uint8_t> write_unit(std::size_t unit, std::vector<uint8_t>& buffer) {
  buffer.resize(sizeof(unit));
  std::memcpy(buffer.data(), &unit, sizeof(unit));
  return buffer;
}

TEST(ReadAhead, WorkersFillTheReadAheadAndNoMore) {
  constexpr std::size_t kUnits = 300;
  constexpr std::size_t kAhead = 3;
  std::mutex mutex;
  std::condition_variable started_more;
  std::size_t started = 0;
  std::atomic<std::size_t> taking{0};  // the unit the test is taking
  std::atomic<bool> beyond{false};
  ReadAhead read_ahead(kUnits, 4, kAhead, [&](std::size_t unit, std::vector<uint8_t>& buffer) {
    // Taking unit k lets unit k + ahead start, not one more.
    if (unit > taking + kAhead) beyond = true;
    {
      const std::lock_guard lock(mutex);
      ++started;
    }
    started_more.notify_all();
    return write_unit(unit, buffer);
  });
  EXPECT_EQ(read_ahead.workers(), 4u);
  {
    // The workers, left alone, prepare the read-ahead's worth.
    std::unique_lock lock(mutex);
    started_more.wait(lock, [&] { return started >= kAhead; });
  }
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i < kUnits; ++i) {
    taking = i;
    order.push_back(take_all(read_ahead, 1).front());
  }
  std::vector<std::size_t> expected(kUnits);
  for (std::size_t i = 0; i < kUnits; ++i) expected[i] = i;
  EXPECT_EQ(order, expected);
  EXPECT_FALSE(beyond);
  EXPECT_EQ(read_ahead.most_in_flight(), kAhead);
}

TEST(ReadAhead, WithoutWorkersTheTakerPreparesEachUnitReusingItsBuffer) {
  const std::thread::id taker = std::this_thread::get_id();
  std::vector<const std::vector<uint8_t>*> buffers;
  ReadAhead read_ahead(5, 0, 0, [&](std::size_t unit, std::vector<uint8_t>& buffer) {
    EXPECT_EQ(std::this_thread::get_id(), taker);
    buffers.push_back(&buffer);
    return write_unit(unit, buffer);
  });
  EXPECT_EQ(read_ahead.workers(), 0u);
  EXPECT_EQ(take_all(read_ahead, 5), (std::vector<std::size_t>{0, 1, 2, 3, 4}));
  EXPECT_EQ(read_ahead.most_in_flight(), 1u);
  EXPECT_EQ(std::count(buffers.begin(), buffers.end(), buffers.front()), 5);
}

TEST(ReadAhead, AnErrorComesOutWhenItsUnitIsTaken) {
  ReadAhead read_ahead(10, 3, 4, [&](std::size_t unit, std::vector<uint8_t>& buffer) {
    if (unit == 5) throw std::invalid_argument("unit 5 is bad");
    return write_unit(unit, buffer);
  });
  EXPECT_EQ(take_all(read_ahead, 5), (std::vector<std::size_t>{0, 1, 2, 3, 4}));
  try {
    read_ahead.take();
    ADD_FAILURE() << "unit 5 did not throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "unit 5 is bad");
  }
  EXPECT_EQ(take_all(read_ahead, 4), (std::vector<std::size_t>{6, 7, 8, 9}));
}

}  // namespace
}  // namespace robotperf::bag
