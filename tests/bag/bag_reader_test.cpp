// Reading the real ROS 2 bags of ../shared/data/rosbag2: sqlite3_cdr_test
// (schema 4 with message_definitions, metadata v7) and mcap_talker (zstd
// chunks, ros2msg schemas, metadata v4).
#include <zstd.h>

#include <algorithm>
#include <cstring>

#include "bag_test_util.hpp"
#include "robotperf/bag/qos.hpp"
#include "robotperf/msgs/cdr.hpp"
#include "test_msgs_types.hpp"

namespace robotperf::bag {
namespace {

using namespace testing;

const TopicInfo& topic_named(const std::vector<TopicInfo>& topics, const std::string& name) {
  auto it = std::find_if(topics.begin(), topics.end(),
                         [&](const TopicInfo& t) { return t.name == name; });
  if (it == topics.end()) throw std::runtime_error("no topic " + name);
  return *it;
}

TEST(SqliteReader, InfoFromMetadataYaml) {
  const BagInfo info = read_info(reference_bag("sqlite3_cdr_test"));
  EXPECT_EQ(info.storage, Storage::kSqlite3);
  EXPECT_EQ(info.metadata_version, 7);
  EXPECT_EQ(info.message_count, 7u);
  EXPECT_EQ(info.starting_time_ns, 1586406456763032325);
  EXPECT_EQ(info.duration_ns, 151137181);
  ASSERT_EQ(info.files.size(), 1u);
  EXPECT_EQ(info.files[0].path, "cdr_test_0.db3");
  EXPECT_EQ(info.bytes, 28672u);
  const TopicInfo& arrays = topic_named(info.topics, "/array_topic");
  EXPECT_EQ(arrays.type, "test_msgs/msg/Arrays");
  EXPECT_EQ(arrays.message_count, 4u);
  const auto qos = parse_qos_profiles(arrays.offered_qos_profiles);
  ASSERT_EQ(qos.size(), 1u);
  EXPECT_EQ(qos[0].depth, 4);
  EXPECT_EQ(qos[0].reliability, 1);
  EXPECT_EQ(qos[0].durability, 1);
  EXPECT_EQ(topic_named(info.topics, "/test_topic").message_count, 3u);
}

TEST(SqliteReader, MessagesInTimeOrderWithDefinitions) {
  Reader reader(reference_bag("sqlite3_cdr_test"));
  // Definitions come from the message_definitions table of schema 4.
  const TopicInfo& basic = topic_named(reader.topics(), "/test_topic");
  EXPECT_EQ(basic.definition_encoding, "ros2msg");
  EXPECT_NE(basic.definition.find("int32 int32_value"), std::string::npos);
  Message m;
  int64_t last = 0;
  int basic_count = 0;
  int arrays_count = 0;
  while (reader.next(m)) {
    EXPECT_GE(m.timestamp_ns, last);
    last = m.timestamp_ns;
    const std::string& type = reader.topics()[m.topic].type;
    if (type == "test_msgs/msg/BasicTypes") {
      ++basic_count;
      const auto b = msgs::from_cdr<::test_msgs::BasicTypes>(m.data);
      EXPECT_EQ(b.int32_value, 123);
      EXPECT_EQ(msgs::to_cdr(b), m.data);
    } else {
      ASSERT_EQ(type, "test_msgs/msg/Arrays");
      ++arrays_count;
      const auto a = msgs::from_cdr<::test_msgs::Arrays>(m.data);
      EXPECT_EQ(a.string_values[1], "Complex Hello2");
      EXPECT_EQ(msgs::to_cdr(a), m.data);
    }
  }
  EXPECT_EQ(basic_count, 3);
  EXPECT_EQ(arrays_count, 4);
  EXPECT_GE(last, 1586406456763032325);
}

TEST(SqliteReader, StorageFileAloneGivesTheSameMessages) {
  const auto via_dir = read_all(reference_bag("sqlite3_cdr_test"));
  const auto via_file = read_all(reference_bag("sqlite3_cdr_test") / "cdr_test_0.db3");
  EXPECT_EQ(via_dir.size(), 7u);
  EXPECT_EQ(via_dir, via_file);
  const BagInfo info = read_info(reference_bag("sqlite3_cdr_test") / "cdr_test_0.db3");
  EXPECT_EQ(info.metadata_version, 0);
  EXPECT_EQ(info.message_count, 7u);
  EXPECT_EQ(info.duration_ns, 151137181);
}

TEST(SqliteReader, TopicFilterAndTimeWindow) {
  ReadOptions only_basic;
  only_basic.topics = {"/test_topic"};
  const auto basic = read_all(reference_bag("sqlite3_cdr_test"), only_basic);
  ASSERT_EQ(basic.size(), 3u);
  for (const auto& r : basic) EXPECT_EQ(r.topic, "/test_topic");

  const auto all = read_all(reference_bag("sqlite3_cdr_test"));
  ReadOptions window;
  window.start_time_ns = all[2].timestamp_ns;
  window.end_time_ns = all[4].timestamp_ns;
  const auto middle = read_all(reference_bag("sqlite3_cdr_test"), window);
  EXPECT_EQ(middle, std::vector<Recorded>(all.begin() + 2, all.begin() + 5));
}

// Turns the one-file sqlite3 bag at `bag` into what rosbag2's file compression writes: its
// storage file zstd-compressed whole as <file>.zstd, and metadata.yaml saying so.
void compress_bag_file(const fs::path& bag) {
  std::string text;
  {
    const auto yaml = read_file(bag / "metadata.yaml");
    text.assign(yaml.begin(), yaml.end());
  }
  const BagInfo info = read_info(bag);
  ASSERT_EQ(info.files.size(), 1u);
  const std::string name = info.files[0].path.string();
  const auto db = read_file(bag / name);
  std::vector<uint8_t> compressed(ZSTD_compressBound(db.size()));
  compressed.resize(ZSTD_compress(compressed.data(), compressed.size(), db.data(), db.size(), 1));
  write_file(bag / (name + ".zstd"), compressed);
  fs::remove(bag / name);
  for (const auto& [from, to] :
       {std::pair<std::string, std::string>{"compression_format: \"\"", "compression_format: zstd"},
        {"compression_mode: \"\"", "compression_mode: FILE"}}) {
    ASSERT_NE(text.find(from), std::string::npos) << from;
    text.replace(text.find(from), from.size(), to);
  }
  for (auto at = text.find(name); at != std::string::npos; at = text.find(name, at)) {
    text.insert(at + name.size(), ".zstd");
    at += name.size();
  }
  write_file(bag / "metadata.yaml", {text.begin(), text.end()});
}

// rosbag2's file compression zstd-compresses each storage file whole: the definitions are in
// the compressed storage only, and must come out of it as from the plain one.
TEST(SqliteReader, FileCompressedBagKeepsItsDefinitions) {
  ScratchDir dir;
  const fs::path plain = reference_bag("sqlite3_cdr_test");
  fs::copy(plain, dir / "bag");
  compress_bag_file(dir / "bag");
  ASSERT_TRUE(fs::exists(dir / "bag" / "cdr_test_0.db3.zstd"));

  EXPECT_EQ(read_all(dir / "bag"), read_all(plain));
  const Reader uncompressed(plain);
  const Reader reader(dir / "bag");
  for (const auto& t : reader.topics()) {
    EXPECT_FALSE(t.definition.empty()) << t.name;
    EXPECT_EQ(t.definition, topic_named(uncompressed.topics(), t.name).definition) << t.name;
  }
  convert(dir / "bag", dir / "mcap", {Storage::kMcap, Compression::kZstd});
  const Reader converted(dir / "mcap");
  for (const auto& t : converted.topics()) {
    EXPECT_EQ(t.definition_encoding, "ros2msg") << t.name;
    EXPECT_EQ(t.definition, topic_named(uncompressed.topics(), t.name).definition) << t.name;
  }
}

// Each reader decompresses into a file of its own: two bags whose storage files share a name,
// open at once, each read their own messages.
TEST(SqliteReader, TwoFileCompressedBagsWithOneFileNameOpenAtOnce) {
  ScratchDir dir;
  fs::copy(reference_bag("sqlite3_cdr_test"), dir / "first");
  compress_bag_file(dir / "first");
  fs::create_directories(dir / "second");
  {
    Writer writer(dir / "second" / "cdr_test", {});
    TopicInfo topic;
    topic.name = "/other";
    topic.type = "std_msgs/msg/String";
    const std::vector<uint8_t> payload = {0, 1, 0, 0, 3, 0, 0, 0, 'h', 'i', 0};
    writer.write(writer.add_topic(topic), 42, payload);
  }
  compress_bag_file(dir / "second" / "cdr_test");
  ASSERT_TRUE(fs::exists(dir / "second" / "cdr_test" / "cdr_test_0.db3.zstd"));

  const auto expected = read_all(reference_bag("sqlite3_cdr_test"));
  Reader first(dir / "first");
  Reader second(dir / "second" / "cdr_test");
  std::vector<Recorded> from_first;
  Message m;
  while (first.next(m))
    from_first.push_back({first.topics()[m.topic].name, m.timestamp_ns, m.data});
  EXPECT_EQ(from_first, expected);
  ASSERT_TRUE(second.next(m));
  EXPECT_EQ(second.topics()[m.topic].name, "/other");
  EXPECT_EQ(m.timestamp_ns, 42);
  EXPECT_FALSE(second.next(m));
}

std::string cdr_string(const std::vector<uint8_t>& payload) {
  std::string s;
  msgs::CdrReader r(payload);
  r(s);
  return s;
}

// Decoded independently with the zstd tool from the chunk at offset 45.
constexpr int64_t kTalkerTimes[10] = {1585866235112609068, 1585866235612975047, 1585866236113032123,
                                      1585866236613084249, 1585866237113144533, 1585866237613243815,
                                      1585866238112976087, 1585866238613186119, 1585866239113147889,
                                      1585866239643508139};

void expect_talker_messages(const std::vector<Recorded>& all) {
  std::vector<Recorded> strings;
  for (const auto& r : all) {
    if (r.topic == "/topic") strings.push_back(r);
  }
  ASSERT_EQ(strings.size(), 10u);
  for (std::size_t i = 0; i < strings.size(); ++i) {
    SCOPED_TRACE(i);
    EXPECT_EQ(strings[i].timestamp_ns, kTalkerTimes[i]);
    EXPECT_EQ(cdr_string(strings[i].data), "Hello, world! " + std::to_string(i));
    EXPECT_EQ(strings[i].data.size(), 24u);
  }
}

TEST(McapReader, TalkerStringsWithExactTextAndTimes) {
  Reader reader(reference_bag("mcap_talker"));
  EXPECT_EQ(reader.info().storage, Storage::kMcap);
  EXPECT_EQ(reader.info().metadata_version, 4);
  const TopicInfo& topic = topic_named(reader.topics(), "/topic");
  EXPECT_EQ(topic.type, "std_msgs/msg/String");
  EXPECT_EQ(topic.definition_encoding, "ros2msg");
  EXPECT_NE(topic.definition.find("string data"), std::string::npos);
  EXPECT_EQ(topic_named(reader.topics(), "/rosout").message_count, 10u);
  EXPECT_EQ(topic_named(reader.topics(), "/parameter_events").message_count, 0u);
  const auto all = read_all(reference_bag("mcap_talker"));
  EXPECT_EQ(all.size(), 20u);
  EXPECT_TRUE(std::is_sorted(all.begin(), all.end(), [](const Recorded& a, const Recorded& b) {
    return a.timestamp_ns < b.timestamp_ns;
  }));
  expect_talker_messages(all);
}

TEST(McapReader, StorageFileAloneUsesTheSummary) {
  const fs::path file = reference_bag("mcap_talker") / "talker.mcap";
  const BagInfo info = read_info(file);
  EXPECT_EQ(info.message_count, 20u);
  EXPECT_EQ(info.starting_time_ns, 1585866235112411371);  // a /rosout message comes first
  const TopicInfo& topic = topic_named(info.topics, "/topic");
  EXPECT_EQ(topic.message_count, 10u);
  // The channel carries its QoS as rosbag2 wrote it.
  const auto qos = parse_qos_profiles(topic.offered_qos_profiles);
  ASSERT_EQ(qos.size(), 1u);
  EXPECT_EQ(qos[0].reliability, 1);
  expect_talker_messages(read_all(file));
}

TEST(McapReader, LinearScanWithoutSummary) {
  ScratchDir dir;
  auto bytes = read_file(reference_bag("mcap_talker") / "talker.mcap");
  // Footer: summary_start = 0 means the file has no summary section.
  const std::size_t footer = bytes.size() - 8 - 29;
  ASSERT_EQ(bytes[footer], 0x02);
  std::memset(bytes.data() + footer + 9, 0, 20);
  write_file(dir / "nosummary.mcap", bytes);
  const auto via_scan = read_all(dir / "nosummary.mcap");
  EXPECT_EQ(via_scan, read_all(reference_bag("mcap_talker") / "talker.mcap"));
  EXPECT_EQ(read_info(dir / "nosummary.mcap").message_count, 20u);
}

// A summary may hold chunk indexes without a Statistics record (it is optional): the counts
// and times then come from the message indexes, the same as the Statistics give.
TEST(McapReader, SummaryWithoutStatistics) {
  ScratchDir dir;
  const fs::path original = reference_bag("mcap_talker") / "talker.mcap";
  auto bytes = read_file(original);
  constexpr std::size_t kStatistics = 12567;
  ASSERT_EQ(bytes[kStatistics], 0x0B);
  bytes[kStatistics] = 0x80;  // a private opcode: readers skip the record
  const std::size_t footer = bytes.size() - 8 - 29;
  std::memset(bytes.data() + footer + 9 + 16, 0, 4);  // summary CRC 0: not computed
  write_file(dir / "nostats.mcap", bytes);

  const BagInfo info = read_info(dir / "nostats.mcap");
  const BagInfo expected = read_info(original);
  EXPECT_EQ(info.message_count, 20u);
  EXPECT_EQ(info.starting_time_ns, expected.starting_time_ns);
  EXPECT_EQ(info.duration_ns, expected.duration_ns);
  ASSERT_EQ(info.topics.size(), expected.topics.size());
  for (const auto& t : expected.topics)
    EXPECT_EQ(topic_named(info.topics, t.name).message_count, t.message_count) << t.name;
  EXPECT_EQ(read_all(dir / "nostats.mcap"), read_all(original));
}

TEST(McapReader, TopicFilter) {
  ReadOptions options;
  options.topics = {"/rosout"};
  const auto rosout = read_all(reference_bag("mcap_talker"), options);
  ASSERT_EQ(rosout.size(), 10u);
  for (const auto& r : rosout) EXPECT_EQ(r.topic, "/rosout");
}

}  // namespace
}  // namespace robotperf::bag

namespace robotperf::bag {
namespace {

using namespace testing;

// Jazzy's metadata version 9 stores offered_qos_profiles as a YAML sequence
// with enum names instead of a string with integers.
TEST(Metadata, Version9QosSequenceWithNames) {
  ScratchDir dir;
  fs::create_directories(dir / "bag");
  fs::copy_file(reference_bag("sqlite3_cdr_test") / "cdr_test_0.db3",
                dir / "bag" / "cdr_test_0.db3");
  const std::string yaml = R"(rosbag2_bagfile_information:
  version: 9
  storage_identifier: sqlite3
  duration:
    nanoseconds: 151137181
  starting_time:
    nanoseconds_since_epoch: 1586406456763032325
  message_count: 7
  topics_with_message_count:
    - topic_metadata:
        name: /test_topic
        type: test_msgs/msg/BasicTypes
        serialization_format: cdr
        offered_qos_profiles:
          - history: keep_last
            depth: 3
            reliability: best_effort
            durability: volatile
            deadline:
              sec: 9223372036
              nsec: 854775807
            lifespan:
              sec: 9223372036
              nsec: 854775807
            liveliness: automatic
            liveliness_lease_duration:
              sec: 9223372036
              nsec: 854775807
            avoid_ros_namespace_conventions: false
        type_description_hash: RIHS01_abc
      message_count: 3
  compression_format: ""
  compression_mode: ""
  relative_file_paths:
    - cdr_test_0.db3
  files:
    - path: cdr_test_0.db3
      starting_time:
        nanoseconds_since_epoch: 1586406456763032325
      duration:
        nanoseconds: 151137181
      message_count: 7
  custom_data: ~
  ros_distro: jazzy
)";
  write_file(dir / "bag" / "metadata.yaml", {yaml.begin(), yaml.end()});
  const BagInfo info = read_info(dir / "bag");
  EXPECT_EQ(info.metadata_version, 9);
  EXPECT_EQ(info.ros_distro, "jazzy");
  const TopicInfo& t = topic_named(info.topics, "/test_topic");
  EXPECT_EQ(t.type_description_hash, "RIHS01_abc");
  const auto qos = parse_qos_profiles(t.offered_qos_profiles);
  ASSERT_EQ(qos.size(), 1u);
  EXPECT_EQ(qos[0].history, 1);
  EXPECT_EQ(qos[0].depth, 3);
  EXPECT_EQ(qos[0].reliability, 2);
  EXPECT_EQ(qos[0].deadline.sec, 9223372036);
  EXPECT_EQ(read_all(dir / "bag").size(), 7u);
}

}  // namespace
}  // namespace robotperf::bag
