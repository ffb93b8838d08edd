// Writing bags: both storages, every chunk compression, split files, and
// conversions of the real ROS 2 bags that must preserve every byte.
#include <yaml-cpp/yaml.h>

#include <map>
#include <set>

#include "bag_test_util.hpp"
#include "robotperf/bag/qos.hpp"

namespace robotperf::bag {
namespace {

using namespace testing;

struct TopicSummary {
  std::string name, type, format, qos;
  uint64_t count;
  friend bool operator==(const TopicSummary&, const TopicSummary&) = default;
};

std::map<std::string, TopicSummary> topics_of(const fs::path& bag) {
  std::map<std::string, TopicSummary> out;
  Reader reader(bag);
  for (const auto& t : reader.topics()) {
    out[t.name] = {t.name, t.type, t.serialization_format, t.offered_qos_profiles, t.message_count};
  }
  return out;
}

void expect_same_bag(const fs::path& a, const fs::path& b) {
  EXPECT_EQ(read_all(a), read_all(b));
  EXPECT_EQ(topics_of(a), topics_of(b));
}

struct Conversion {
  std::string bag;
  Storage there;
  Compression compression;
};

class RoundTrip : public ::testing::TestWithParam<Conversion> {};

TEST_P(RoundTrip, PreservesPayloadsTopicsTypesTimesAndQos) {
  const Conversion& c = GetParam();
  ScratchDir dir;
  const fs::path source = reference_bag(c.bag);
  const Storage back =
      read_info(source).storage == Storage::kMcap ? Storage::kMcap : Storage::kSqlite3;
  WriteOptions to_other{c.there, c.compression};
  WriteOptions to_back{back, Compression::kZstd};
  EXPECT_EQ(convert(source, dir / "there", to_other), read_info(source).message_count);
  EXPECT_EQ(convert(dir / "there", dir / "back", to_back), read_info(source).message_count);
  EXPECT_EQ(read_info(dir / "there").storage, c.there);
  expect_same_bag(source, dir / "there");
  expect_same_bag(source, dir / "back");
}

INSTANTIATE_TEST_SUITE_P(
    Bags, RoundTrip,
    ::testing::Values(Conversion{"sqlite3_cdr_test", Storage::kMcap, Compression::kZstd},
                      Conversion{"sqlite3_cdr_test", Storage::kMcap, Compression::kLz4},
                      Conversion{"sqlite3_cdr_test", Storage::kMcap, Compression::kNone},
                      Conversion{"mcap_talker", Storage::kSqlite3, Compression::kNone}));

TEST(Writer, DefinitionsTravelIntoMcapSchemas) {
  ScratchDir dir;
  convert(reference_bag("sqlite3_cdr_test"), dir / "out", {Storage::kMcap, Compression::kZstd});
  Reader reader(dir / "out");
  for (const auto& t : reader.topics()) {
    EXPECT_EQ(t.definition_encoding, "ros2msg");
    EXPECT_NE(t.definition.find("int32"), std::string::npos) << t.name;
  }
}

// The keys of metadata version 5, which rosbag2 in Humble reads.
TEST(Writer, MetadataHasExactlyTheFieldsHumbleReads) {
  ScratchDir dir;
  convert(reference_bag("mcap_talker"), dir / "out", {Storage::kSqlite3, Compression::kNone});
  const YAML::Node root = YAML::LoadFile((dir / "out" / "metadata.yaml").string());
  ASSERT_EQ(root.size(), 1u);
  const YAML::Node m = root["rosbag2_bagfile_information"];
  std::set<std::string> keys;
  for (const auto& kv : m) keys.insert(kv.first.as<std::string>());
  EXPECT_EQ(keys, (std::set<std::string>{"version", "storage_identifier", "duration",
                                         "starting_time", "message_count",
                                         "topics_with_message_count", "compression_format",
                                         "compression_mode", "relative_file_paths", "files"}));
  EXPECT_EQ(m["version"].as<int>(), 5);
  EXPECT_EQ(m["storage_identifier"].as<std::string>(), "sqlite3");
  EXPECT_EQ(m["duration"]["nanoseconds"].as<int64_t>(), 4531096768);
  EXPECT_EQ(m["starting_time"]["nanoseconds_since_epoch"].as<int64_t>(), 1585866235112411371);
  EXPECT_EQ(m["message_count"].as<uint64_t>(), 20u);
  for (const auto& entry : m["topics_with_message_count"]) {
    std::set<std::string> entry_keys, topic_keys;
    for (const auto& kv : entry) entry_keys.insert(kv.first.as<std::string>());
    for (const auto& kv : entry["topic_metadata"]) topic_keys.insert(kv.first.as<std::string>());
    EXPECT_EQ(entry_keys, (std::set<std::string>{"topic_metadata", "message_count"}));
    EXPECT_EQ(topic_keys, (std::set<std::string>{"name", "type", "serialization_format",
                                                 "offered_qos_profiles"}));
    EXPECT_TRUE(entry["topic_metadata"]["offered_qos_profiles"].IsScalar());
    EXPECT_TRUE(
        qos_uses_integer_enums(entry["topic_metadata"]["offered_qos_profiles"].as<std::string>()));
  }
  ASSERT_EQ(m["files"].size(), 1u);
  std::set<std::string> file_keys;
  for (const auto& kv : m["files"][0]) file_keys.insert(kv.first.as<std::string>());
  EXPECT_EQ(file_keys,
            (std::set<std::string>{"path", "starting_time", "duration", "message_count"}));
  EXPECT_EQ(m["relative_file_paths"][0].as<std::string>(), "out_0.db3");
  EXPECT_TRUE(fs::is_regular_file(dir / "out" / "out_0.db3"));
}

TopicInfo jazzy_topic() {
  TopicInfo t;
  t.name = "/chatter";
  t.type = "std_msgs/msg/String";
  t.offered_qos_profiles =
      "- history: keep_last\n  depth: 7\n  reliability: reliable\n  durability: volatile\n"
      "  deadline:\n    sec: 0\n    nsec: 0\n  lifespan:\n    sec: 0\n    nsec: 0\n"
      "  liveliness: automatic\n  liveliness_lease_duration:\n    sec: 0\n    nsec: 0\n"
      "  avoid_ros_namespace_conventions: false";
  t.definition = "string data\n";
  return t;
}

std::vector<uint8_t> payload(int i) {
  // A CDR string message "m<i>" with its padding: any bytes will do for the bag.
  std::vector<uint8_t> p{0, 1, 0, 0, 0, 0, 0, 0};
  const std::string text = "m" + std::to_string(i);
  p[4] = static_cast<uint8_t>(text.size() + 1);
  p.insert(p.end(), text.begin(), text.end());
  p.push_back(0);
  return p;
}

TEST(Writer, SqliteTopicsGetIntegerEnumQos) {
  ScratchDir dir;
  {
    Writer w(dir / "b", {Storage::kSqlite3, Compression::kNone});
    const auto id = w.add_topic(jazzy_topic());
    w.write(id, 100, payload(0));
  }
  const auto db = read_info(dir / "b" / "b_0.db3");
  ASSERT_EQ(db.topics.size(), 1u);
  EXPECT_TRUE(qos_uses_integer_enums(db.topics[0].offered_qos_profiles));
  EXPECT_EQ(parse_qos_profiles(db.topics[0].offered_qos_profiles),
            parse_qos_profiles(jazzy_topic().offered_qos_profiles));
}

class SplitFiles : public ::testing::TestWithParam<Storage> {};

TEST_P(SplitFiles, ReadBackInOrderAcrossFiles) {
  ScratchDir dir;
  WriteOptions options{GetParam(), Compression::kZstd};
  options.chunk_size = 4096;
  options.max_file_bytes = 16 * 1024;
  std::vector<Recorded> written;
  {
    Writer w(dir / "split", options);
    const auto id = w.add_topic(jazzy_topic());
    for (int i = 0; i < 2000; ++i) {
      written.push_back({"/chatter", 1'000'000'000LL * 1700000000 + i * 1000, payload(i)});
      w.write(id, written.back().timestamp_ns, written.back().data);
    }
  }
  const BagInfo info = read_info(dir / "split");
  EXPECT_GT(info.files.size(), 2u);
  EXPECT_EQ(info.message_count, 2000u);
  uint64_t in_files = 0;
  for (const auto& f : info.files) in_files += f.message_count;
  EXPECT_EQ(in_files, 2000u);
  EXPECT_EQ(info.duration_ns, 1999 * 1000);
  EXPECT_EQ(read_all(dir / "split"), written);
}

INSTANTIATE_TEST_SUITE_P(Storages, SplitFiles,
                         ::testing::Values(Storage::kSqlite3, Storage::kMcap));

TEST(Writer, McapOutOfOrderTimestampsReadBackSorted) {
  ScratchDir dir;
  WriteOptions options{Storage::kMcap, Compression::kLz4};
  options.chunk_size = 64;  // one or two messages per chunk: chunks overlap in time
  {
    Writer w(dir / "b", options);
    const auto id = w.add_topic(jazzy_topic());
    for (int64_t t : {50, 10, 40, 20, 30, 60, 5}) w.write(id, t, payload(static_cast<int>(t)));
  }
  std::vector<int64_t> times;
  for (const auto& r : read_all(dir / "b")) times.push_back(r.timestamp_ns);
  EXPECT_EQ(times, (std::vector<int64_t>{5, 10, 20, 30, 40, 50, 60}));
}

// A run of zero bytes compresses about 32000:1 with zstd, far past what lz4 can reach: such a
// chunk must read back all the same.
TEST(Writer, McapZstdChunkOfZerosReadsBack) {
  ScratchDir dir;
  std::vector<Recorded> written;
  {
    Writer w(dir / "zeros", {Storage::kMcap, Compression::kZstd});
    const auto id = w.add_topic(jazzy_topic());
    for (int64_t t = 1; t <= 3; ++t) {
      written.push_back({"/chatter", t, std::vector<uint8_t>(1 << 20, 0)});
      w.write(id, t, written.back().data);
    }
  }
  EXPECT_EQ(read_all(dir / "zeros"), written);
}

TEST(Writer, RefusesANonEmptyDirectory) {
  ScratchDir dir;
  write_file(dir / "x", {1});
  try {
    Writer w(dir.path(), {});
    FAIL() << "expected a BagError";
  } catch (const BagError& e) {
    EXPECT_NE(std::string(e.what()).find("not empty"), std::string::npos) << e.what();
  }
}

// QoS text that is not QoS profiles is refused when the topic is added, naming it and the bag; the
// bag goes on without that topic and closes as the writer goes out of scope.
TEST(Writer, RefusesATopicWhoseQosIsNotQosProfiles) {
  ScratchDir dir;
  for (const Storage storage : {Storage::kSqlite3, Storage::kMcap}) {
    SCOPED_TRACE(to_string(storage));
    const fs::path bag = dir / to_string(storage);
    {
      Writer w(bag, {storage, Compression::kNone});
      for (const char* qos : {"- reliability: sometimes", "- history: [3]", "- [unclosed"}) {
        TopicInfo bad = jazzy_topic();
        bad.name = "/bad";
        bad.offered_qos_profiles = qos;
        try {
          w.add_topic(bad);
          ADD_FAILURE() << qos << " was accepted";
        } catch (const BagError& e) {
          const std::string what = e.what();
          EXPECT_NE(what.find("topic /bad"), std::string::npos) << what;
          EXPECT_NE(what.find(bag.string()), std::string::npos) << what;
          EXPECT_EQ(what.find('\n'), std::string::npos) << what;
        }
      }
      w.write(w.add_topic(jazzy_topic()), 100, payload(0));
    }
    const BagInfo info = read_info(bag);
    ASSERT_EQ(info.topics.size(), 1u);
    EXPECT_EQ(info.topics[0].name, "/chatter");
    EXPECT_EQ(read_all(bag).size(), 1u);
  }
}

// rosbag2 names the files after the folder however it is written: "b/" holds b_0.mcap.
TEST(Writer, AFolderGivenWithATrailingSlashNamesItsFilesAfterIt) {
  ScratchDir dir;
  {
    Writer w(dir.path() / "b" / "", {Storage::kMcap, Compression::kNone});
    w.write(w.add_topic(jazzy_topic()), 100, payload(0));
  }
  EXPECT_TRUE(fs::is_regular_file(dir / "b" / "b_0.mcap"));
  EXPECT_EQ(read_info(dir / "b").files.at(0).path, "b_0.mcap");
  EXPECT_EQ(read_all(dir / "b").size(), 1u);
}

// A link planted in the bag's folder under the name a fixed temporary file would have: reindex
// writes metadata.yaml through a file of its own, and the link's target is left as it was.
TEST(Writer, ReindexDoesNotWriteThroughALinkInTheFolder) {
  ScratchDir dir;
  {
    Writer w(dir.path() / "b", {Storage::kMcap, Compression::kNone});
    w.write(w.add_topic(jazzy_topic()), 100, payload(0));
  }
  write_file(dir / "victim", {'k', 'e', 'e', 'p'});
  fs::create_symlink(dir / "victim", dir / "b" / "metadata.yaml.tmp");
  fs::remove(dir / "b" / "metadata.yaml");
  EXPECT_EQ(reindex(dir / "b").message_count, 1u);
  EXPECT_EQ(read_file(dir / "victim"), (std::vector<uint8_t>{'k', 'e', 'e', 'p'}));
  EXPECT_TRUE(fs::is_symlink(fs::symlink_status(dir / "b" / "metadata.yaml.tmp")));
  EXPECT_EQ(read_all(dir / "b").size(), 1u);
}

// A storage file is created, never opened: a link planted where it goes (another user's, in a
// shared folder) or a file already there is refused and left as it was, for both storages.
TEST(Writer, AStorageFileIsNeverWrittenThroughALinkOrOverAFile) {
  ScratchDir dir;
  write_file(dir / "victim", {});
  fs::create_symlink(dir / "victim", dir / "link.db3");
  fs::create_symlink(dir / "victim", dir / "link.mcap");
  EXPECT_THROW(create_sqlite3(dir / "link.db3"), BagError);
  EXPECT_THROW(create_mcap(dir / "link.mcap", Compression::kNone, 1 << 20), BagError);
  EXPECT_TRUE(read_file(dir / "victim").empty());
  write_file(dir / "there.db3", {});
  EXPECT_THROW(create_sqlite3(dir / "there.db3"), BagError);
  EXPECT_TRUE(read_file(dir / "there.db3").empty());
}

// A bag folder whose second file is cut short: its conversion fails after the first file's
// messages were written, and must leave nothing that looks like a complete bag behind.
TEST(Writer, AFailedConversionLeavesNoBagBehind) {
  ScratchDir dir;
  const fs::path source = dir / "two_files";
  fs::create_directories(source);
  const auto talker = read_file(reference_bag("mcap_talker") / "talker.mcap");
  write_file(source / "a.mcap", talker);
  write_file(source / "b.mcap", {talker.begin(), talker.begin() + 5000});
  const auto yaml = read_file(reference_bag("mcap_talker") / "metadata.yaml");
  std::string text(yaml.begin(), yaml.end());
  const std::string listed = "  - talker.mcap\n";
  ASSERT_NE(text.find(listed), std::string::npos);
  text.replace(text.find(listed), listed.size(), "  - a.mcap\n  - b.mcap\n");
  write_file(source / "metadata.yaml", {text.begin(), text.end()});
  ASSERT_EQ(read_info(source).files.size(), 2u);

  for (const Storage storage : {Storage::kMcap, Storage::kSqlite3}) {
    SCOPED_TRACE(to_string(storage));
    const fs::path out = dir / ("out_" + to_string(storage));
    EXPECT_THROW(convert(source, out, {storage, Compression::kZstd}), BagError);
    EXPECT_FALSE(fs::exists(out / "metadata.yaml"));
    EXPECT_FALSE(fs::exists(out));  // the writer made it, so it goes
    // A folder that was there before stays, as empty as it was.
    fs::create_directories(out);
    EXPECT_THROW(convert(source, out, {storage, Compression::kZstd}), BagError);
    EXPECT_TRUE(fs::is_directory(out));
    EXPECT_TRUE(fs::is_empty(out));
  }
}

}  // namespace
}  // namespace robotperf::bag
