// Real-world bags through the bag verbs: definitions kept by conversion in both directions,
// Humble bags without definitions, flat .msg folders, types without fields, definitions that do
// not match the payload, and serialization formats other than CDR.
#include <gtest/gtest.h>
#include <sqlite3.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "../command_line.hpp"
#include "../shared_data.hpp"
#include "robotperf/bag/bag.hpp"

namespace {

namespace fs = std::filesystem;
using robotperf::test_support::Outcome;
using robotperf::test_support::robotperf_cli;

// A bag of ROS 2's own, in the shared data folder.
std::string shared_bag(const std::string& name) {
  return shared_data("rosbag2/" + name).string();
}
// ros2-test-interface-files: test_msgs' .msg files in one flat folder named "msg".
const std::string kTestMsgs = "/usr/share/test_interface_files/msg";

class BagCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("robotperf-bag-cli-" + std::to_string(getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  // ROS 2's sqlite3 test bag as Humble writes it: schema 3, no message_definitions table.
  std::string humble_bag() const {
    const fs::path copy = dir_ / "humble.db3";
    for (const auto& e : fs::directory_iterator(shared_bag("sqlite3_cdr_test"))) {
      if (e.path().extension() == ".db3") fs::copy_file(e.path(), copy);
    }
    sqlite3* db = nullptr;
    EXPECT_EQ(sqlite3_open(copy.c_str(), &db), SQLITE_OK);
    EXPECT_EQ(
        sqlite3_exec(db, "DROP TABLE message_definitions; UPDATE schema SET schema_version=3;",
                     nullptr, nullptr, nullptr),
        SQLITE_OK);
    sqlite3_close(db);
    return copy.string();
  }

  // A bag with one topic of `type`, `format` and definition `definition`, holding `payload`.
  std::string bag_of(const std::string& name, const std::string& type, const std::string& format,
                     const std::string& definition, const std::vector<uint8_t>& payload) const {
    robotperf::bag::WriteOptions w;
    w.storage = robotperf::bag::Storage::kMcap;
    robotperf::bag::Writer writer(dir_ / name, w);
    robotperf::bag::TopicInfo t;
    t.name = "/t";
    t.type = type;
    t.serialization_format = format;
    t.definition_encoding = "ros2msg";
    t.definition = definition;
    const std::size_t id = writer.add_topic(t);
    for (int64_t k = 0; k < 3; ++k) writer.write(id, 1'000'000'000 + k, payload);
    writer.close();
    return path(name);
  }

  fs::path dir_;
};

TEST_F(BagCli, ConversionKeepsDefinitionsBothWays) {
  // MCAP -> sqlite3 -> MCAP: every type still decodes from the bag alone at each step.
  ASSERT_EQ(robotperf_cli("bag convert " + shared_bag("mcap_talker") + " " + path("db") +
                          " --storage sqlite3")
                .exit_code,
            0);
  ASSERT_EQ(robotperf_cli("bag convert " + path("db") + " " + path("mcap")).exit_code, 0);
  for (const std::string bag : {"db", "mcap"}) {
    const Outcome o = robotperf_cli("bag echo " + path(bag));
    ASSERT_EQ(o.exit_code, 0) << bag << ": " << o.out;
    EXPECT_NE(o.out.find("msg: 'Publishing: ''Hello, world! 9'''"), std::string::npos) << o.out;
    EXPECT_NE(o.out.find("data: 'Hello, world! 9'"), std::string::npos) << o.out;
  }
  // The sqlite3 file has Iron's and Jazzy's layout, with a definition per type.
  sqlite3* db = nullptr;
  fs::path file;
  for (const auto& e : fs::directory_iterator(dir_ / "db")) {
    if (e.path().extension() == ".db3") file = e.path();
  }
  ASSERT_EQ(sqlite3_open_v2(file.c_str(), &db, SQLITE_OPEN_READONLY, nullptr), SQLITE_OK);
  sqlite3_stmt* q = nullptr;
  ASSERT_EQ(sqlite3_prepare_v2(db,
                               "SELECT (SELECT schema_version FROM schema), COUNT(*), "
                               "MIN(length(encoded_message_definition)) FROM message_definitions",
                               -1, &q, nullptr),
            SQLITE_OK);
  ASSERT_EQ(sqlite3_step(q), SQLITE_ROW);
  EXPECT_EQ(sqlite3_column_int(q, 0), 4);
  EXPECT_EQ(sqlite3_column_int(q, 1), 3);  // String, Log, ParameterEvent
  EXPECT_GT(sqlite3_column_int(q, 2), 10);
  sqlite3_finalize(q);
  sqlite3_close(db);
}

TEST_F(BagCli, AHumbleBagGetsItsDefinitionsFromAFlatMsgFolder) {
  const std::string humble = humble_bag();
  Outcome o = robotperf_cli("bag echo " + humble + " --topic /test_topic --limit 1");
  EXPECT_EQ(o.exit_code, 2);
  EXPECT_NE(o.out.find("no definition of test_msgs/msg/BasicTypes"), std::string::npos) << o.out;
  // A flat folder named msg: its files serve test_msgs/msg/* by name (not msg/msg/*).
  o = robotperf_cli("bag echo " + humble + " --msg-dir " + kTestMsgs);
  ASSERT_EQ(o.exit_code, 0) << o.out;
  EXPECT_NE(o.out.find("[test_msgs/msg/Arrays]"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("- 'Complex Hello1'"), std::string::npos) << o.out;

  // Converting without the .msg files says which types stay undefined...
  o = robotperf_cli("bag convert " + humble + " " + path("bare"));
  ASSERT_EQ(o.exit_code, 0) << o.out;
  EXPECT_NE(o.out.find("warning: no definition of test_msgs/msg/Arrays (/array_topic)"),
            std::string::npos)
      << o.out;
  EXPECT_EQ(robotperf_cli("bag echo " + path("bare")).exit_code, 2);
  // ...and with them writes full definitions, dependencies included, into the new bag.
  o = robotperf_cli("bag convert " + humble + " " + path("full") + " --msg-dir " + kTestMsgs);
  ASSERT_EQ(o.exit_code, 0) << o.out;
  EXPECT_EQ(o.out.find("warning"), std::string::npos) << o.out;
  o = robotperf_cli("bag echo " + path("full"));
  ASSERT_EQ(o.exit_code, 0) << o.out;
  EXPECT_NE(o.out.find("[test_msgs/msg/Arrays]"), std::string::npos) << o.out;
}

// A Jazzy bag's service event topic: its definition is the .srv text, '---' line and all.
TEST_F(BagCli, ServiceEventTopicsDecode) {
  std::ifstream in(std::string("/usr/share/test_interface_files/srv/BasicTypes.srv"));
  const std::string srv((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<uint8_t> payload = {0, 1, 0, 0, 2, 0, 0, 0, 5, 0, 0, 0, 6, 0, 0, 0};
  payload.resize(payload.size() + 16 + 4);  // client_gid, padding to sequence_number
  for (const uint8_t b : {9, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0}) payload.push_back(b);
  const std::string bag = bag_of("events", "test_msgs/srv/BasicTypes_Event", "cdr", srv, payload);
  const Outcome o = robotperf_cli("bag echo " + bag + " --limit 1");
  ASSERT_EQ(o.exit_code, 0) << o.out;
  EXPECT_NE(o.out.find("event_type: 2"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("sequence_number: 9"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("request: []"), std::string::npos) << o.out;
}

// CDR as ROS 2 writes it (little endian): each value aligned to its size, counted from the first
// byte after the 4-byte encapsulation header.
class Cdr {
 public:
  template <class T>
  Cdr& put(T value) {
    while ((bytes_.size() - 4) % sizeof(T) != 0) bytes_.push_back(0);
    const auto* p = reinterpret_cast<const uint8_t*>(&value);
    bytes_.insert(bytes_.end(), p, p + sizeof(T));
    return *this;
  }
  const std::vector<uint8_t>& bytes() const { return bytes_; }

 private:
  std::vector<uint8_t> bytes_{0, 1, 0, 0};
};

// One example_interfaces/srv/AddTwoInts_Event: ServiceEventInfo (event_type, stamp, a 16-byte
// client GID, sequence number), then request[<=1] {a, b} and response[<=1] {sum}.
std::vector<uint8_t> add_two_ints_event(uint8_t event_type,
                                        const std::vector<std::pair<int64_t, int64_t>>& request,
                                        const std::vector<int64_t>& response) {
  Cdr cdr;
  cdr.put(event_type).put(int32_t{1'700'000'000}).put(uint32_t{5});
  for (uint8_t b = 1; b <= 16; ++b) cdr.put(b);
  cdr.put(int64_t{1}).put(static_cast<uint32_t>(request.size()));
  for (const auto& [a, b] : request) cdr.put(a).put(b);
  cdr.put(static_cast<uint32_t>(response.size()));
  for (const int64_t sum : response) cdr.put(sum);
  return cdr.bytes();
}

constexpr const char* kAddTwoIntsSrv = "int64 a\nint64 b\n---\nint64 sum\n";

// A Jazzy recording of the service /add_two_ints, as rosbag2 writes it into sqlite3 (schema 4):
// the topic /add_two_ints/_service_event of type example_interfaces/srv/AddTwoInts_Event, and,
// when `with_definition`, its definition stored under the service's name, the .srv text behind
// an "SRV:" heading. One request sent, one response received.
void write_jazzy_service_bag(const fs::path& file, bool with_definition) {
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(file.c_str(), &db), SQLITE_OK);
  const std::string definition =
      std::string(80, '=') + "\nSRV: example_interfaces/srv/AddTwoInts\n" + kAddTwoIntsSrv;
  const std::string sql =
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
      "timestamp INTEGER NOT NULL,data BLOB NOT NULL);"
      "INSERT INTO topics VALUES(1,'/add_two_ints/_service_event',"
      "'example_interfaces/srv/AddTwoInts_Event','cdr','','');" +
      (with_definition ? "INSERT INTO message_definitions VALUES(1,"
                         "'example_interfaces/srv/AddTwoInts','ros2msg','" +
                             definition + "','');"
                       : std::string());
  ASSERT_EQ(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr), SQLITE_OK)
      << sqlite3_errmsg(db);
  const std::vector<uint8_t> events[] = {add_two_ints_event(0, {{2, 3}}, {}),
                                         add_two_ints_event(3, {}, {5})};
  sqlite3_stmt* insert = nullptr;
  ASSERT_EQ(sqlite3_prepare_v2(db, "INSERT INTO messages(topic_id, timestamp, data) VALUES(1,?,?)",
                               -1, &insert, nullptr),
            SQLITE_OK);
  for (int k = 0; k < 2; ++k) {
    sqlite3_bind_int64(insert, 1, 1'700'000'000'000'000'000 + k);
    sqlite3_bind_blob(insert, 2, events[k].data(), static_cast<int>(events[k].size()),
                      SQLITE_STATIC);
    ASSERT_EQ(sqlite3_step(insert), SQLITE_DONE);
    sqlite3_reset(insert);
  }
  sqlite3_finalize(insert);
  sqlite3_close(db);
}

// What `bag echo` prints for the two AddTwoInts events, in order.
void expect_add_two_ints_events(const Outcome& o) {
  ASSERT_EQ(o.exit_code, 0) << o.out;
  EXPECT_EQ(o.out.find("warning"), std::string::npos) << o.out;
  const auto request = o.out.find("event_type: 0");
  const auto response = o.out.find("event_type: 3");
  ASSERT_NE(request, std::string::npos) << o.out;
  ASSERT_NE(response, std::string::npos) << o.out;
  EXPECT_NE(
      o.out.find("--- /add_two_ints/_service_event [example_interfaces/srv/AddTwoInts_Event]"),
      std::string::npos)
      << o.out;
  EXPECT_NE(o.out.find("sec: 1700000000"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("sequence_number: 1"), std::string::npos) << o.out;
  const auto a = o.out.find("a: 2", request);
  const auto b = o.out.find("b: 3", request);
  EXPECT_LT(a, response) << o.out;
  EXPECT_LT(b, response) << o.out;
  EXPECT_NE(o.out.find("sum: 5", response), std::string::npos) << o.out;
}

// Jazzy stores a service event topic's definition under the service (pkg/srv/Name), not under
// the topic's type (pkg/srv/Name_Event): echo finds it there, and conversion carries it into an
// MCAP schema that decodes on its own.
TEST_F(BagCli, AJazzySqliteServiceEventBagDecodesAndConverts) {
  write_jazzy_service_bag(dir_ / "jazzy.db3", true);
  expect_add_two_ints_events(robotperf_cli("bag echo " + path("jazzy.db3")));
  const Outcome converted = robotperf_cli("bag convert " + path("jazzy.db3") + " " + path("mcap"));
  ASSERT_EQ(converted.exit_code, 0) << converted.out;
  EXPECT_EQ(converted.out.find("warning"), std::string::npos) << converted.out;
  expect_add_two_ints_events(robotperf_cli("bag echo " + path("mcap")));
}

// Without a stored definition, a flat --msg-dir holding the .srv file serves the service's
// derived types by name, whatever the folder is called.
TEST_F(BagCli, AFlatMsgDirSrvFileServesAServiceEventTopic) {
  write_jazzy_service_bag(dir_ / "bare.db3", false);
  fs::create_directories(dir_ / "interfaces");
  std::ofstream(dir_ / "interfaces" / "AddTwoInts.srv") << kAddTwoIntsSrv;
  expect_add_two_ints_events(
      robotperf_cli("bag echo " + path("bare.db3") + " --msg-dir " + path("interfaces")));
  const Outcome converted = robotperf_cli("bag convert " + path("bare.db3") + " " + path("mcap") +
                                          " --msg-dir " + path("interfaces"));
  ASSERT_EQ(converted.exit_code, 0) << converted.out;
  EXPECT_EQ(converted.out.find("warning"), std::string::npos) << converted.out;
  expect_add_two_ints_events(robotperf_cli("bag echo " + path("mcap")));
}

// ROS 2's bags keep their definitions in the storage (MCAP schemas, sqlite3 message_definitions),
// not in metadata.yaml: `run --dataset` reads them there, so that refusing a topic names its real
// fault (no std_msgs/Header to carry message IDs), not a missing definition.
TEST_F(BagCli, RunDatasetJudgesTopicsByTheDefinitionsInTheStorage) {
  const std::pair<std::string, std::string> bags[] = {
      {"mcap_talker", " --remap /topic:=/camera/image_raw --remap /rosout:=/camera/camera_info"},
      {"sqlite3_cdr_test",
       " --remap /test_topic:=/camera/image_raw --remap /array_topic:=/camera/camera_info"}};
  for (const auto& [name, remaps] : bags) {
    const Outcome o = robotperf_cli("run a1 --dataset " + shared_bag(name) + remaps);
    EXPECT_EQ(o.exit_code, 2) << name << ": " << o.out;
    EXPECT_EQ(o.out.find("has no definition"), std::string::npos) << name << ": " << o.out;
    EXPECT_NE(o.out.find("does not start with a std_msgs/Header"), std::string::npos)
        << name << ": " << o.out;
  }
}

// `bag info` states what metadata.yaml says; `--verify` reads the storage too and names, one line
// each, where it disagrees: counts per topic and in total, first and last times, a storage that
// cannot be read. ROS 2's own bags agree with themselves.
TEST_F(BagCli, InfoVerifyReportsWhereTheStorageDisagreesWithMetadata) {
  for (const std::string name : {"mcap_talker", "sqlite3_cdr_test"}) {
    const Outcome o = robotperf_cli("bag info --verify " + shared_bag(name));
    EXPECT_EQ(o.exit_code, 0) << name << ": " << o.out;
    EXPECT_NE(o.out.find("counts and times agree"), std::string::npos) << name << ": " << o.out;
  }
  // A writable copy of ROS 2's bag `name` at `to`.
  const auto copy = [&](const std::string& name, const std::string& to) {
    fs::copy(shared_bag(name), dir_ / to);
    for (const auto& e : fs::directory_iterator(dir_ / to))
      fs::permissions(e.path(), fs::perms::owner_write, fs::perm_options::add);
    return dir_ / to;
  };

  // The first and last messages lost (one of each topic), metadata.yaml left as it was.
  const fs::path lost = copy("sqlite3_cdr_test", "lost");
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open((lost / "cdr_test_0.db3").c_str(), &db), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(db,
                         "DELETE FROM messages WHERE timestamp IN ((SELECT MIN(timestamp) FROM "
                         "messages), (SELECT MAX(timestamp) FROM messages))",
                         nullptr, nullptr, nullptr),
            SQLITE_OK);
  sqlite3_close(db);
  Outcome o = robotperf_cli("bag info " + lost.string());
  EXPECT_EQ(o.exit_code, 0) << o.out;
  EXPECT_NE(o.out.find("Messages:          7"), std::string::npos) << o.out;
  o = robotperf_cli("bag info --verify " + lost.string());
  EXPECT_EQ(o.exit_code, 2) << o.out;
  for (const std::string line :
       {"topic /array_topic: metadata.yaml says 4 messages, the storage holds 3\n",
        "topic /test_topic: metadata.yaml says 3 messages, the storage holds 2\n",
        "total: metadata.yaml says 7 messages, the storage holds 5\n",
        "start: metadata.yaml says 1586406456.763032325 s, the first message is at "
        "1586406456.782683500 s\n",
        "end: metadata.yaml says 1586406456.914169506 s (start + duration), the last message is "
        "at 1586406456.866330524 s\n"}) {
    EXPECT_NE(o.out.find("robotperf: " + lost.string() + ": " + line), std::string::npos)
        << line << o.out;
  }
  EXPECT_EQ(o.out.find("Verified"), std::string::npos) << o.out;

  // Storage files cut short: `bag info` alone cannot tell, --verify says so in one line.
  const fs::path cut_sqlite = copy("sqlite3_cdr_test", "cut_sqlite");
  fs::resize_file(cut_sqlite / "cdr_test_0.db3", 5000);
  const fs::path cut_mcap = copy("mcap_talker", "cut_mcap");
  fs::resize_file(cut_mcap / "talker.mcap", fs::file_size(cut_mcap / "talker.mcap") / 2);
  for (const fs::path& cut : {cut_sqlite, cut_mcap}) {
    EXPECT_EQ(robotperf_cli("bag info " + cut.string()).exit_code, 0) << cut;
    o = robotperf_cli("bag info --verify " + cut.string());
    EXPECT_EQ(o.exit_code, 2) << o.out;
    EXPECT_NE(o.out.find("robotperf: " + cut.string() + ": the storage is unreadable after "),
              std::string::npos)
        << o.out;
    EXPECT_EQ(o.out.find("total:"), std::string::npos) << o.out;
  }
}

// A split bag that lost its metadata.yaml: reindex writes it again from the storage files, in
// the order of their split index, and will not overwrite one that exists.
TEST_F(BagCli, ReindexRestoresASplitBagsMetadata) {
  ASSERT_EQ(robotperf_cli("bag convert " + shared_bag("mcap_talker") + " " + path("split") +
                          " --max-file-size 0.001")
                .exit_code,
            0);
  const Outcome before = robotperf_cli("bag info " + path("split"));
  fs::remove(dir_ / "split" / "metadata.yaml");
  Outcome o = robotperf_cli("bag info " + path("split"));
  EXPECT_EQ(o.exit_code, 2);
  EXPECT_NE(o.out.find("robotperf bag reindex"), std::string::npos) << o.out;
  o = robotperf_cli("bag reindex " + path("split"));
  ASSERT_EQ(o.exit_code, 0) << o.out;
  EXPECT_NE(o.out.find("3 topics, 20 messages"), std::string::npos) << o.out;
  const Outcome after = robotperf_cli("bag info " + path("split"));
  EXPECT_EQ(after.out, before.out);  // files in split order, counts, times, QoS: all as written
  o = robotperf_cli("bag echo " + path("split") + " --topic /topic");
  EXPECT_NE(o.out.find("Hello, world! 9"), std::string::npos) << o.out;
  o = robotperf_cli("bag reindex " + path("split"));
  EXPECT_EQ(o.exit_code, 2);
  EXPECT_NE(o.out.find("has one already"), std::string::npos) << o.out;
  o = robotperf_cli("bag reindex " + dir_.string());
  EXPECT_EQ(o.exit_code, 2);
  EXPECT_NE(o.out.find("no .db3 or .mcap file to index"), std::string::npos) << o.out;
}

TEST_F(BagCli, ATypeWithoutFieldsDecodes) {
  // std_msgs/msg/Empty: a 0-byte ros2msg definition, one uint8 member on the wire.
  const std::string bag = bag_of("empty", "std_msgs/msg/Empty", "cdr", "", {0, 1, 0, 0, 0});
  const Outcome o = robotperf_cli("bag echo " + bag);
  ASSERT_EQ(o.exit_code, 0) << o.out;
  EXPECT_NE(o.out.find("--- /t [std_msgs/msg/Empty]"), std::string::npos) << o.out;
  EXPECT_EQ(o.out.find("warning"), std::string::npos) << o.out;
}

TEST_F(BagCli, ADefinitionThatLeavesBytesOverIsWarnedOnce) {
  // A "level" read out of the first byte of a 12-byte payload.
  const std::string bag = bag_of("mismatch", "demo_msgs/msg/Level", "cdr", "uint8 level\n",
                                 {0, 1, 0, 0, 251, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12});
  const Outcome o = robotperf_cli("bag echo " + bag);
  ASSERT_EQ(o.exit_code, 0) << o.out;
  EXPECT_NE(o.out.find("level: 251"), std::string::npos) << o.out;
  const std::string warning = "the definition of demo_msgs/msg/Level accounts for 5 of the 16";
  const auto at = o.out.find(warning);
  ASSERT_NE(at, std::string::npos) << o.out;
  EXPECT_EQ(o.out.find("accounts for", at + warning.size()), std::string::npos) << "warned twice";
}

// A definition the bag stores that does not parse is named with the bag and the topic.
TEST_F(BagCli, AMalformedStoredDefinitionNamesTheBagAndTopic) {
  const std::string bag =
      bag_of("malformed", "demo_msgs/msg/Levels", "cdr", "uint8[3 levels\n", {0, 1, 0, 0, 1, 2, 3});
  const Outcome o = robotperf_cli("bag echo " + bag);
  EXPECT_EQ(o.exit_code, 2) << o.out;
  EXPECT_NE(o.out.find(bag + ": the definition of /t's type stored in the bag: "
                             "demo_msgs/msg/Levels line 1:"),
            std::string::npos)
      << o.out;
}

TEST_F(BagCli, SerializationFormatsOtherThanCdrAreRefused) {
  const std::string bag =
      bag_of("proto", "std_msgs/msg/String", "protobuf", "string data\n", {1, 2, 3, 4});
  Outcome o = robotperf_cli("bag echo " + bag);
  EXPECT_EQ(o.exit_code, 2) << o.out;
  EXPECT_NE(o.out.find("/t is serialized as 'protobuf': robotperf decodes CDR only"),
            std::string::npos)
      << o.out;
  // Conversion copies the bytes and the format untouched.
  o = robotperf_cli("bag convert " + bag + " " + path("copy") + " --storage sqlite3");
  ASSERT_EQ(o.exit_code, 0) << o.out;
  o = robotperf_cli("bag info " + path("copy"));
  EXPECT_NE(o.out.find("[protobuf]"), std::string::npos) << o.out;
}

}  // namespace
