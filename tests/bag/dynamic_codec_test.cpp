// The .msg-driven codec on the real ROS 2 bags: definitions from the bags'
// own schemas, from the test_msgs .msg files and from ../shared/data/msg.
#include <cstring>
#include <fstream>
#include <sstream>

#include "../shared_data.hpp"
#include "allocation_limit.hpp"
#include "bag_test_util.hpp"
#include "robotperf/msgs/cdr.hpp"
#include "robotperf/msgs/definitions.hpp"
#include "robotperf/msgs/dynamic.hpp"
#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/msgs/stereo_msgs.hpp"

namespace robotperf::bag {
namespace {

using namespace testing;
namespace dyn = msgs::dynamic;

dyn::TypeRegistry registry_from_bag(const Reader& reader) {
  dyn::TypeRegistry registry;
  for (const auto& t : reader.topics()) {
    if (t.definition_encoding == "ros2msg" && !t.definition.empty())
      registry.add_ros2msg(t.type, t.definition);
  }
  return registry;
}

void check_cdr_test_bag(const dyn::TypeRegistry& registry) {
  Reader reader(reference_bag("sqlite3_cdr_test"));
  Message m;
  int seen = 0;
  while (reader.next(m)) {
    ++seen;
    const std::string& type = reader.topics()[m.topic].type;
    const dyn::Value v = dyn::decode(registry, type, m.data);
    if (type == "test_msgs/msg/BasicTypes") {
      EXPECT_EQ(std::get<int64_t>(v["int32_value"].data), 123);
      EXPECT_EQ(std::get<uint64_t>(v["uint64_value"].data), 0u);
      EXPECT_EQ(std::get<bool>(v["bool_value"].data), false);
    } else {
      const auto& strings = std::get<dyn::List>(v["string_values"].data);
      ASSERT_EQ(strings.size(), 3u);
      EXPECT_EQ(std::get<std::string>(strings[2].data), "Complex Hello3");
      const auto& defaults = std::get<dyn::List>(v["defaults_values"].data);
      EXPECT_EQ(std::get<double>(defaults[0]["float32_value"].data), 1.125);
      EXPECT_EQ(std::get<int64_t>(defaults[0]["int64_value"].data), -40000000);
      const auto& int64s = std::get<dyn::List>(v["int64_values_default"].data);
      EXPECT_EQ(std::get<int64_t>(int64s[2].data), std::numeric_limits<int64_t>::min());
    }
    EXPECT_EQ(dyn::encode(registry, type, v), m.data) << type;
  }
  EXPECT_EQ(seen, 7);
}

TEST(DynamicCodec, CdrTestBagWithItsOwnDefinitions) {
  Reader reader(reference_bag("sqlite3_cdr_test"));
  check_cdr_test_bag(registry_from_bag(reader));
}

TEST(DynamicCodec, CdrTestBagWithMsgFiles) {
  dyn::TypeRegistry registry;
  EXPECT_GE(registry.add_directory("/usr/share/test_interface_files/msg", "test_msgs"), 10u);
  check_cdr_test_bag(registry);
}

// A flat folder named "msg" without a package: its files are adopted by name for the types a bag
// asks for, and a ros2msg schema composed from them decodes the bag as the bag's own does.
TEST(DynamicCodec, FlatMsgFolderIsAdoptedAndComposesSchemas) {
  dyn::TypeRegistry flat;
  EXPECT_GE(flat.add_directory("/usr/share/test_interface_files/msg"), 10u);
  EXPECT_FALSE(flat.contains("msg/msg/Arrays"));
  EXPECT_FALSE(flat.contains("test_msgs/msg/Arrays"));
  EXPECT_GE(flat.adopt("test_msgs/msg/Arrays"), 2u);  // Arrays and the BasicTypes it nests
  EXPECT_EQ(flat.adopt("test_msgs/msg/BasicTypes"), 0u);
  dyn::TypeRegistry composed;
  for (const std::string type : {"test_msgs/msg/Arrays", "test_msgs/msg/BasicTypes"}) {
    const std::string schema = flat.ros2msg_schema(type);
    composed.add_ros2msg(type, schema);
  }
  EXPECT_NE(flat.ros2msg_schema("test_msgs/msg/Arrays").find("\nMSG: test_msgs/BasicTypes\n"),
            std::string::npos);
  check_cdr_test_bag(composed);
}

// Shell completion ends a folder's name with '/': the folder is just as flat.
TEST(DynamicCodec, FlatMsgFolderGivenWithATrailingSlash) {
  dyn::TypeRegistry flat;
  EXPECT_GE(flat.add_directory("/usr/share/test_interface_files/msg/"), 10u);
  EXPECT_GE(flat.adopt("test_msgs/msg/Arrays"), 2u);
  check_cdr_test_bag(flat);
}

// std_msgs/msg/Empty's definition is empty; rosidl gives it one uint8 member, which CDR carries.
TEST(DynamicCodec, ATypeWithoutFieldsHasItsPlaceholderMember) {
  dyn::TypeRegistry registry;
  registry.add_ros2msg("std_msgs/msg/Empty", "");
  const std::vector<uint8_t> payload = {0, 1, 0, 0, 0};
  const dyn::Value v = dyn::decode(registry, "std_msgs/msg/Empty", payload);
  EXPECT_EQ(std::get<uint64_t>(v["structure_needs_at_least_one_member"].data), 0u);
  EXPECT_EQ(dyn::encode(registry, "std_msgs/msg/Empty", v), payload);
}

std::string file_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// Jazzy records a service event topic's definition as the .srv text itself (request, "---",
// response): the _Request, _Response and _Event types are derived from it, the event with
// service_msgs/ServiceEventInfo.
TEST(DynamicCodec, ServiceEventTypesComeFromTheSrvText) {
  dyn::TypeRegistry registry;
  registry.add_ros2msg("test_msgs/srv/BasicTypes_Event",
                       file_text("/usr/share/test_interface_files/srv/BasicTypes.srv"));
  EXPECT_EQ(registry.get("test_msgs/srv/BasicTypes_Request").fields.size(), 14u);
  EXPECT_EQ(registry.get("test_msgs/srv/BasicTypes_Response").fields.size(), 14u);
  // event_type 1, stamp 5 s 6 ns, a 16-byte gid, sequence 7, no request, no response.
  std::vector<uint8_t> payload = {0, 1, 0, 0, 1, 0, 0, 0, 5, 0, 0, 0, 6, 0, 0, 0};
  for (uint8_t b = 0; b < 16; ++b) payload.push_back(b);
  for (const uint8_t b : {0, 0, 0, 0, 7, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0})
    payload.push_back(b);
  const dyn::Value v = dyn::decode(registry, "test_msgs/srv/BasicTypes_Event", payload);
  const std::string yaml = dyn::to_yaml(v);
  EXPECT_NE(yaml.find("event_type: 1"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("sequence_number: 7"), std::string::npos) << yaml;
  EXPECT_EQ(dyn::encode(registry, "test_msgs/srv/BasicTypes_Event", v), payload);
}

// Jazzy's schema of a service event type is the .srv text behind an "SRV: pkg/srv/Name" heading,
// with no text of its own: the name it is stored under gets no definition from the empty text
// before the heading (it would decode as a type without fields).
TEST(DynamicCodec, AJazzyServiceSchemaDefinesOnlyTheTypesOfItsSrvSection) {
  const std::string schema = std::string(80, '=') +
                             "\nSRV: example_interfaces/srv/AddTwoInts\nint64 a\nint64 b\n---\n"
                             "int64 sum\n";
  dyn::TypeRegistry registry;
  registry.add_ros2msg("example_interfaces/srv/AddTwoInts_Event", schema);
  EXPECT_EQ(registry.get("example_interfaces/srv/AddTwoInts_Event").fields.size(), 3u);
  EXPECT_EQ(registry.get("example_interfaces/srv/AddTwoInts_Request").fields.size(), 2u);
  dyn::TypeRegistry misnamed;
  misnamed.add_ros2msg("example_interfaces/srv/Other_Event", schema);
  EXPECT_FALSE(misnamed.contains("example_interfaces/srv/Other_Event"));
}

TEST(DynamicCodec, ActionTypesComeFromTheActionText) {
  dyn::TypeRegistry registry;
  registry.add_interface("test_msgs/action/Fibonacci_FeedbackMessage",
                         file_text("/usr/share/test_interface_files/action/Fibonacci.action"));
  for (const std::string suffix :
       {"_Goal", "_Result", "_Feedback", "_FeedbackMessage", "_SendGoal_Request",
        "_SendGoal_Response", "_SendGoal_Event", "_GetResult_Request", "_GetResult_Response",
        "_GetResult_Event"}) {
    EXPECT_NO_THROW(registry.check_complete("test_msgs/action/Fibonacci" + suffix)) << suffix;
  }
  // goal_id (16 bytes), then the feedback's int32[] sequence {0, 1}.
  std::vector<uint8_t> payload = {0, 1, 0, 0};
  for (uint8_t b = 0; b < 16; ++b) payload.push_back(b);
  for (const uint8_t b : {2, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0}) payload.push_back(b);
  const dyn::Value v = dyn::decode(registry, "test_msgs/action/Fibonacci_FeedbackMessage", payload);
  EXPECT_EQ(dyn::encode(registry, "test_msgs/action/Fibonacci_FeedbackMessage", v), payload);
  // A text with the wrong number of parts for its kind is one clear error.
  EXPECT_THROW(registry.add_interface("test_msgs/srv/Broken_Request", "int8 a\n---\n---\n"),
               dyn::DefinitionError);
}

TEST(DynamicCodec, TalkerStringsAndLogs) {
  Reader reader(reference_bag("mcap_talker"));
  const dyn::TypeRegistry registry = registry_from_bag(reader);
  Message m;
  int strings = 0;
  int logs = 0;
  while (reader.next(m)) {
    const std::string& type = reader.topics()[m.topic].type;
    const dyn::Value v = dyn::decode(registry, type, m.data);
    if (type == "std_msgs/msg/String") {
      EXPECT_EQ(std::get<std::string>(v["data"].data), "Hello, world! " + std::to_string(strings));
      EXPECT_EQ(dyn::to_yaml(v), "data: 'Hello, world! " + std::to_string(strings) + "'\n");
      ++strings;
    } else {
      ASSERT_EQ(type, "rcl_interfaces/msg/Log");
      EXPECT_EQ(std::get<std::string>(v["name"].data), "minimal_publisher");
      ++logs;
      // rclcpp of Eloquent left its alignment padding uninitialised: the
      // re-encoding equals the stored bytes except there, where it writes zeros.
      const auto again = dyn::encode(registry, type, v);
      ASSERT_EQ(again.size(), m.data.size());
      for (std::size_t i = 0; i < again.size(); ++i) {
        if (again[i] != m.data[i]) {
          EXPECT_EQ(again[i], 0) << "byte " << i << " is not padding";
        }
      }
      EXPECT_EQ(dyn::encode(registry, type, dyn::decode(registry, type, again)), again);
      continue;
    }
    EXPECT_EQ(dyn::encode(registry, type, v), m.data) << type;
  }
  EXPECT_EQ(strings, 10);
  EXPECT_EQ(logs, 10);
}

TEST(DynamicCodec, SharedMsgFolderMatchesTheTypedCodec) {
  dyn::TypeRegistry registry;
  EXPECT_GT(registry.add_directory(shared_data("msg")), 100u);
  msgs::CameraInfo info;
  info.header.stamp.sec = 7;
  info.header.frame_id = "camera";
  info.width = 640;
  info.distortion_model = "plumb_bob";
  info.d = {-0.25, 0.12, -0.00028, -5e-5, 0};
  info.k[0] = 554.38;
  info.roi.do_rectify = true;
  const auto cdr = msgs::to_cdr(info);
  const dyn::Value v = dyn::decode(registry, "sensor_msgs/CameraInfo", cdr);
  EXPECT_EQ(std::get<std::string>(v["header"]["frame_id"].data), "camera");
  EXPECT_EQ(std::get<double>(std::get<dyn::List>(v["k"].data)[0].data), 554.38);
  EXPECT_EQ(dyn::encode(registry, "sensor_msgs/msg/CameraInfo", v), cdr);

  msgs::Image image;
  image.height = 2;
  image.width = 3;
  image.encoding = "rgb8";
  image.step = 9;
  image.data.assign(18, 42);
  const auto image_cdr = msgs::to_cdr(image);
  const dyn::Value iv = dyn::decode(registry, "sensor_msgs/msg/Image", image_cdr);
  EXPECT_EQ(std::get<dyn::Bytes>(iv["data"].data).size(), 18u);
  EXPECT_NE(dyn::to_yaml(iv, 4).find("data: '<18 bytes>'"), std::string::npos);
  EXPECT_EQ(dyn::encode(registry, "sensor_msgs/msg/Image", iv), image_cdr);
}

TEST(DynamicCodec, ParsesArraysBoundsConstantsAndDefaults) {
  const auto def = dyn::parse_msg("pkg/Thing",
                                  "# a comment\n"
                                  "int32 A=1\n"
                                  "string NAME = 'x # y'\n"
                                  "uint8[4] fixed\n"
                                  "float64[] open  # trailing comment\n"
                                  "string<=8[<=3] bounded\n"
                                  "Header header\n"
                                  "Other other 5\n");
  EXPECT_EQ(def.type, "pkg/msg/Thing");
  ASSERT_EQ(def.fields.size(), 5u);
  EXPECT_EQ(def.fields[0].type.array, dyn::ArrayKind::kFixed);
  EXPECT_EQ(def.fields[0].type.array_size, 4u);
  EXPECT_EQ(def.fields[1].type.array, dyn::ArrayKind::kUnbounded);
  EXPECT_EQ(def.fields[2].type.primitive, dyn::Primitive::kString);
  EXPECT_EQ(def.fields[2].type.array, dyn::ArrayKind::kBounded);
  EXPECT_EQ(def.fields[3].type.message_type, "std_msgs/msg/Header");
  EXPECT_EQ(def.fields[4].type.message_type, "pkg/msg/Other");
}

TEST(DynamicCodec, ClearErrors) {
  EXPECT_THROW(dyn::parse_msg("p/T", "int32[x] a\n"), dyn::DefinitionError);
  EXPECT_THROW(dyn::parse_msg("p/T", "int32\n"), dyn::DefinitionError);
  EXPECT_THROW(dyn::parse_msg("p/T", "int32 a-b\n"), dyn::DefinitionError);
  dyn::TypeRegistry registry;
  registry.add_msg("p/T", "Missing m\n");
  try {
    dyn::decode(registry, "p/T", std::vector<uint8_t>{0, 1, 0, 0, 1, 2, 3, 4});
    FAIL();
  } catch (const dyn::DefinitionError& e) {
    EXPECT_STREQ(e.what(), "no definition of p/msg/Missing (used by p/msg/T)");
  }
  registry.add_msg("p/U", "string s\n");
  EXPECT_THROW(dyn::decode(registry, "p/U", std::vector<uint8_t>{0, 1, 0, 0, 200, 0, 0, 0}),
               msgs::CdrError);
}

// A schema can chain more types than the call stack holds: the checks and the schema walk them
// with stacks of their own, and decode() refuses more than 64 levels of nesting.
TEST(DynamicCodec, AChainOfTypesDeeperThanTheStackIsADefinitionError) {
  constexpr int kDepth = 50000;
  std::string schema = "p/T1 x\n";
  for (int i = 1; i <= kDepth; ++i) {
    schema += std::string(80, '=') + "\nMSG: p/T" + std::to_string(i) + "\n" +
              (i < kDepth ? "p/T" + std::to_string(i + 1) + " x\n" : "uint8 y\n");
  }
  dyn::TypeRegistry registry;
  registry.add_ros2msg("p/msg/T0", schema);
  EXPECT_THROW(dyn::decode(registry, "p/msg/T0", std::vector<uint8_t>{0, 1, 0, 0, 1}),
               dyn::DefinitionError);
  const std::string back = registry.ros2msg_schema("p/msg/T0");
  EXPECT_EQ(back.size(), schema.size());
  EXPECT_NE(back.find("MSG: p/T50000\nuint8 y\n"), std::string::npos);
}

// Elements the payload cannot hold are refused before anything is allocated for them, and a
// count it could hold at a byte each costs no more memory up front than the payload's size.
TEST(DynamicCodec, ForgedArraySizesAllocateNoMoreThanThePayloadHolds) {
  dyn::TypeRegistry registry;
  registry.add_msg("p/Big", "uint8[1073741824] data\n");
  registry.add_msg("p/Four", "float64 a\nfloat64 b\nfloat64 c\nfloat64 d\n");
  registry.add_msg("p/Many", "p/Four[] items\n");
  {
    const robotperf::testing::AllocationLimit limit(1 << 20);
    EXPECT_THROW(dyn::decode(registry, "p/Big", std::vector<uint8_t>{0, 1, 0, 0, 1, 2, 3, 4}),
                 msgs::CdrError);
  }
  constexpr uint32_t n = 1 << 20;
  std::vector<uint8_t> payload(8 + n, 0);
  payload[1] = 1;
  std::memcpy(payload.data() + 4, &n, sizeof(n));
  const robotperf::testing::AllocationLimit limit(8 * payload.size());
  EXPECT_THROW(dyn::decode(registry, "p/Many", payload), msgs::CdrError);
}

// Bags robotperf writes carry these schemas: each must decode and re-encode
// its type exactly as the typed codec does.
TEST(DynamicCodec, BuiltInSchemasMatchTheTypedCodec) {
  msgs::DisparityImage disparity;
  disparity.header.frame_id = "left";
  disparity.image.width = 2;
  disparity.image.height = 1;
  disparity.image.encoding = "32FC1";
  disparity.image.step = 8;
  disparity.image.data.assign(8, 3);
  disparity.f = 528.4f;
  disparity.t = 0.1f;
  disparity.max_disparity = 64;
  disparity.delta_d = 0.0625f;
  msgs::PointCloud2 cloud;
  cloud.width = 1;
  cloud.height = 1;
  cloud.fields.push_back({"x", 0, 7, 1});
  cloud.fields.push_back({"rgb", 16, 7, 1});
  cloud.point_step = 32;
  cloud.row_step = 32;
  cloud.data.assign(32, 1);
  cloud.is_dense = true;

  auto check = [](const std::string& type, const std::vector<uint8_t>& cdr) {
    const auto schema = msgs::ros2msg_schema(type);
    ASSERT_TRUE(schema.has_value()) << type;
    dyn::TypeRegistry registry;
    registry.add_ros2msg(type, *schema);
    EXPECT_EQ(dyn::encode(registry, type, dyn::decode(registry, type, cdr)), cdr) << type;
  };
  check("stereo_msgs/msg/DisparityImage", msgs::to_cdr(disparity));
  check("sensor_msgs/msg/PointCloud2", msgs::to_cdr(cloud));
  check("sensor_msgs/msg/CameraInfo", msgs::to_cdr(msgs::CameraInfo{}));
}

}  // namespace
}  // namespace robotperf::bag
