// Decodes every message of a bag that ROS 2 itself wrote
// (rosbag2 test resource sqlite3/cdr_test: 4 test_msgs/msg/Arrays and
// 3 test_msgs/msg/BasicTypes, recorded in April 2020), checks the values, and
// re-encodes each one to bytes identical to what ROS 2 stored.
//
// Where the values come from: rosbag2's play end-to-end test
// (rosbag2_tests/test_rosbag2_play_end_to_end.cpp) plays this bag and expects
// every BasicTypes to have int32_value == 123, and every Arrays to have
// bool_values == {true, false, true} and string_values == {"Complex Hello1",
// "Complex Hello2", "Complex Hello3"}. The BasicTypes is the test_msgs fixture
// get_messages_basic_types()[0] (all zero) with int32_value set to 123. The
// Arrays is not get_messages_arrays()[0] (that fixture has byte_values
// {0, 255, 0}, int64 min/max, ...): everything it does not set explicitly holds
// the rosidl default value, so the *_default arrays, the Defaults elements and
// the alignment_check carry the values of Arrays.msg and Defaults.msg.
#include <gtest/gtest.h>
#include <sqlite3.h>

#include <cstdint>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "../shared_data.hpp"
#include "robotperf/msgs/cdr.hpp"
#include "test_msgs_types.hpp"

namespace robotperf::msgs {
namespace {

using Bytes = std::vector<uint8_t>;

struct BagMessage {
  int64_t id = 0;
  int64_t timestamp = 0;
  std::string topic;
  std::string type;
  std::string serialization_format;
  Bytes data;
};

std::filesystem::path BagPath() {
  return shared_data("rosbag2/sqlite3_cdr_test/cdr_test_0.db3");
}

// Reads every message of the bag, in id order, with its topic. Fails the test
// (not skips) when the reference bag is missing: it must exist beside the repo.
std::vector<BagMessage> ReadBag() {
  const std::filesystem::path path = BagPath();
  std::vector<BagMessage> out;
  sqlite3* db = nullptr;
  if (sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) {
    ADD_FAILURE() << "cannot open " << path << ": " << sqlite3_errmsg(db);
    sqlite3_close(db);
    return out;
  }
  const char* sql =
      "SELECT m.id, m.timestamp, t.name, t.type, t.serialization_format, m.data "
      "FROM messages m JOIN topics t ON m.topic_id = t.id ORDER BY m.id";
  sqlite3_stmt* stmt = nullptr;
  if (sqlite3_prepare_v2(db, sql, -1, &stmt, nullptr) != SQLITE_OK) {
    ADD_FAILURE() << "cannot query " << path << ": " << sqlite3_errmsg(db);
    sqlite3_close(db);
    return out;
  }
  auto text = [&](int col) {
    const unsigned char* s = sqlite3_column_text(stmt, col);
    return s ? std::string(reinterpret_cast<const char*>(s)) : std::string();
  };
  int rc;
  while ((rc = sqlite3_step(stmt)) == SQLITE_ROW) {
    BagMessage m;
    m.id = sqlite3_column_int64(stmt, 0);
    m.timestamp = sqlite3_column_int64(stmt, 1);
    m.topic = text(2);
    m.type = text(3);
    m.serialization_format = text(4);
    const auto* blob = static_cast<const uint8_t*>(sqlite3_column_blob(stmt, 5));
    const int n = sqlite3_column_bytes(stmt, 5);
    m.data.assign(blob, blob + n);
    out.push_back(std::move(m));
  }
  EXPECT_EQ(rc, SQLITE_DONE) << sqlite3_errmsg(db);
  sqlite3_finalize(stmt);
  sqlite3_close(db);
  return out;
}

// Re-encodes `msg` and compares with the bytes ROS 2 stored. Every payload in
// this bag ends exactly at its last field (the BasicTypes body is 48 bytes;
// the Arrays body ends with an int32 at a 4-aligned offset), so no trailing
// padding is expected; should a payload carry some, it may only be zeros up to
// the next multiple of 4 of the body (what Cyclone DDS writes), and the rest
// must match exactly.
template <class T>
void ExpectReencodesIdentically(const T& msg, const Bytes& stored) {
  const Bytes ours = to_cdr(msg);
  ASSERT_LE(ours.size(), stored.size());
  if (ours.size() == stored.size()) {
    EXPECT_EQ(ours, stored);
    return;
  }
  EXPECT_EQ(ours, Bytes(stored.begin(), stored.begin() + static_cast<std::ptrdiff_t>(ours.size())));
  const size_t body = ours.size() - kEncapsulationSize;
  const size_t padded_body = (body + 3) / 4 * 4;
  EXPECT_EQ(stored.size() - kEncapsulationSize, padded_body) << "more than padding to 4 follows";
  for (size_t i = ours.size(); i < stored.size(); ++i) EXPECT_EQ(stored[i], 0) << i;
}

TEST(RosbagCdr, BagHoldsTheExpectedTopicsAndCounts) {
  const std::vector<BagMessage> msgs = ReadBag();
  ASSERT_EQ(msgs.size(), 7u);
  int arrays = 0;
  int basic = 0;
  for (const BagMessage& m : msgs) {
    EXPECT_EQ(m.serialization_format, "cdr");
    ASSERT_GE(m.data.size(), 4u);
    // Every stored payload starts with the CDR_LE encapsulation header.
    EXPECT_EQ(Bytes(m.data.begin(), m.data.begin() + 4),
              Bytes(kCdrLittleEndianHeader.begin(), kCdrLittleEndianHeader.end()));
    if (m.type == "test_msgs/msg/Arrays") {
      EXPECT_EQ(m.topic, "/array_topic");
      ++arrays;
    } else if (m.type == "test_msgs/msg/BasicTypes") {
      EXPECT_EQ(m.topic, "/test_topic");
      ++basic;
    } else {
      ADD_FAILURE() << "unexpected type " << m.type;
    }
  }
  EXPECT_EQ(arrays, 4);
  EXPECT_EQ(basic, 3);
}

void ExpectBasicTypesFixture(const test_msgs::BasicTypes& b) {
  // get_messages_basic_types()[0] (all zero / false) with int32_value = 123.
  EXPECT_FALSE(b.bool_value);
  EXPECT_EQ(b.byte_value, 0);
  EXPECT_EQ(b.char_value, 0);
  EXPECT_EQ(b.float32_value, 0.0f);
  EXPECT_EQ(b.float64_value, 0.0);
  EXPECT_EQ(b.int8_value, 0);
  EXPECT_EQ(b.uint8_value, 0);
  EXPECT_EQ(b.int16_value, 0);
  EXPECT_EQ(b.uint16_value, 0);
  EXPECT_EQ(b.int32_value, 123);
  EXPECT_EQ(b.uint32_value, 0u);
  EXPECT_EQ(b.int64_value, 0);
  EXPECT_EQ(b.uint64_value, 0u);
}

TEST(RosbagCdr, BasicTypesDecodeAndReencodeIdentically) {
  int seen = 0;
  for (const BagMessage& m : ReadBag()) {
    if (m.type != "test_msgs/msg/BasicTypes") continue;
    ++seen;
    SCOPED_TRACE("message id " + std::to_string(m.id));
    // 4 header + 48 body: 3 one-byte fields, pad @3, float32 @4, float64 @8,
    // int8 @16, uint8 @17, int16 @18, uint16 @20, pad, int32 @24, uint32 @28,
    // int64 @32, uint64 @40.
    EXPECT_EQ(m.data.size(), 52u);
    const auto b = from_cdr<test_msgs::BasicTypes>(m.data);
    ExpectBasicTypesFixture(b);
    // int32_value = 123 = 0x7B sits at body offset 24.
    EXPECT_EQ(m.data[4 + 24], 0x7B);
    ExpectReencodesIdentically(b, m.data);
  }
  EXPECT_EQ(seen, 3);
}

void ExpectArraysValues(const test_msgs::Arrays& a) {
  // Set by the rosbag2 test that recorded the bag.
  EXPECT_EQ(a.bool_values, (std::array<bool, 3>{true, false, true}));
  EXPECT_EQ(a.string_values,
            (std::array<std::string, 3>{"Complex Hello1", "Complex Hello2", "Complex Hello3"}));
  // Everything else default-constructed: zero arrays...
  EXPECT_EQ(a.byte_values, (std::array<uint8_t, 3>{}));
  EXPECT_EQ(a.char_values, (std::array<uint8_t, 3>{}));
  EXPECT_EQ(a.float64_values, (std::array<double, 3>{}));
  EXPECT_EQ(a.int64_values, (std::array<int64_t, 3>{}));
  EXPECT_EQ(a.uint64_values, (std::array<uint64_t, 3>{}));
  for (const test_msgs::BasicTypes& b : a.basic_types_values) {
    EXPECT_EQ(b, test_msgs::BasicTypes{});
  }
  // ... the placeholder byte of the field-less Constants ...
  for (const test_msgs::Constants& c : a.constants_values) {
    EXPECT_EQ(c.structure_needs_at_least_one_member, 0);
  }
  // ... Defaults.msg defaults in each nested Defaults ...
  for (const test_msgs::Defaults& d : a.defaults_values) {
    EXPECT_TRUE(d.bool_value);
    EXPECT_EQ(d.byte_value, 50);
    EXPECT_EQ(d.char_value, 100);  // char decodes as an unsigned byte
    EXPECT_EQ(d.float32_value, 1.125f);
    EXPECT_EQ(d.float64_value, 1.125);
    EXPECT_EQ(d.int8_value, -50);
    EXPECT_EQ(d.uint8_value, 200);
    EXPECT_EQ(d.int16_value, -1000);
    EXPECT_EQ(d.uint16_value, 2000);
    EXPECT_EQ(d.int32_value, -30000);
    EXPECT_EQ(d.uint32_value, 60000u);
    EXPECT_EQ(d.int64_value, -40000000);
    EXPECT_EQ(d.uint64_value, 50000000u);
  }
  // ... and the Arrays.msg defaults, with the extreme integers and strings.
  EXPECT_EQ(a.bool_values_default, (std::array<bool, 3>{false, true, false}));
  EXPECT_EQ(a.byte_values_default, (std::array<uint8_t, 3>{0, 1, 255}));
  EXPECT_EQ(a.char_values_default, (std::array<uint8_t, 3>{0, 1, 127}));
  EXPECT_EQ(a.float32_values_default, (std::array<float, 3>{1.125f, 0.0f, -1.125f}));
  EXPECT_EQ(a.float64_values_default, (std::array<double, 3>{3.1415, 0.0, -3.1415}));
  EXPECT_EQ(a.int8_values_default, (std::array<int8_t, 3>{0, 127, -128}));
  EXPECT_EQ(a.uint8_values_default, (std::array<uint8_t, 3>{0, 1, 255}));
  EXPECT_EQ(a.int16_values_default, (std::array<int16_t, 3>{0, 32767, -32768}));
  EXPECT_EQ(a.uint16_values_default, (std::array<uint16_t, 3>{0, 1, 65535}));
  EXPECT_EQ(a.int32_values_default, (std::array<int32_t, 3>{0, std::numeric_limits<int32_t>::max(),
                                                            std::numeric_limits<int32_t>::min()}));
  EXPECT_EQ(a.uint32_values_default,
            (std::array<uint32_t, 3>{0, 1, std::numeric_limits<uint32_t>::max()}));
  EXPECT_EQ(a.int64_values_default, (std::array<int64_t, 3>{0, std::numeric_limits<int64_t>::max(),
                                                            std::numeric_limits<int64_t>::min()}));
  EXPECT_EQ(a.uint64_values_default,
            (std::array<uint64_t, 3>{0, 1, std::numeric_limits<uint64_t>::max()}));
  EXPECT_EQ(a.string_values_default, (std::array<std::string, 3>{"", "max value", "min value"}));
  EXPECT_EQ(a.alignment_check, 0);
}

TEST(RosbagCdr, ArraysDecodeAndReencodeIdentically) {
  int seen = 0;
  for (const BagMessage& m : ReadBag()) {
    if (m.type != "test_msgs/msg/Arrays") continue;
    ++seen;
    SCOPED_TRACE("message id " + std::to_string(m.id));
    EXPECT_EQ(m.data.size(), 696u);
    const auto a = from_cdr<test_msgs::Arrays>(m.data);
    ExpectArraysValues(a);
    // The decoder consumed the whole payload: nothing is left over.
    CdrReader reader(m.data);
    test_msgs::Arrays again;
    reader(again);
    EXPECT_EQ(reader.remaining(), 0u);
    EXPECT_EQ(again, a);
    ExpectReencodesIdentically(a, m.data);
  }
  EXPECT_EQ(seen, 4);
}

TEST(RosbagCdr, FieldlessMessageIsOneByteOnTheWire) {
  // Three Constants take exactly three bytes in the stored Arrays: had the
  // placeholder member not been serialized, the re-encoding above would be 3
  // bytes short. Check the size arithmetic independently here.
  CdrSizer one;
  one(test_msgs::Constants{});
  EXPECT_EQ(one.size(), kEncapsulationSize + 1);
}

TEST(RosbagCdr, ModifiedMessagesRoundTrip) {
  // Exercise the test_msgs types away from the stored values too: the
  // get_messages_basic_types() extremes inside an Arrays.
  test_msgs::Arrays a;
  test_msgs::BasicTypes max;
  max.bool_value = true;
  max.byte_value = 255;
  max.char_value = 255;
  max.float32_value = 1.125f;
  max.float64_value = 1.125;
  max.int8_value = std::numeric_limits<int8_t>::max();
  max.uint8_value = std::numeric_limits<uint8_t>::max();
  max.int16_value = std::numeric_limits<int16_t>::max();
  max.uint16_value = std::numeric_limits<uint16_t>::max();
  max.int32_value = std::numeric_limits<int32_t>::max();
  max.uint32_value = std::numeric_limits<uint32_t>::max();
  max.int64_value = std::numeric_limits<int64_t>::max();
  max.uint64_value = std::numeric_limits<uint64_t>::max();
  test_msgs::BasicTypes min;
  min.float32_value = -2.125f;
  min.float64_value = -2.125;
  min.int8_value = std::numeric_limits<int8_t>::min();
  min.int16_value = std::numeric_limits<int16_t>::min();
  min.int32_value = std::numeric_limits<int32_t>::min();
  min.int64_value = std::numeric_limits<int64_t>::min();
  a.basic_types_values = {test_msgs::BasicTypes{}, max, min};
  a.string_values = {"", "max value", "min value"};
  a.alignment_check = 42;
  const Bytes cdr = to_cdr(a);
  CdrSizer sizer;
  sizer(a);
  EXPECT_EQ(sizer.size(), cdr.size());
  EXPECT_EQ(from_cdr<test_msgs::Arrays>(cdr), a);
}

}  // namespace
}  // namespace robotperf::msgs
