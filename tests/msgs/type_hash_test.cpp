// REP 2011 type hashes against the values rosidl generates for standard ROS 2 types, computed
// from the ROS 2 .msg files of the shared reference data and from robotperf's own definitions.
#include "robotperf/msgs/type_hash.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "../shared_data.hpp"
#include "robotperf/msgs/definitions.hpp"

namespace robotperf::msgs {
namespace {

namespace dyn = dynamic;

dyn::TypeRegistry ros2_registry() {
  dyn::TypeRegistry registry;
  registry.add_directory(shared_data("msg"));
  // ServiceEventInfo (service_msgs) is not among the shared files; its text as ROS 2 has it.
  registry.add_msg("service_msgs/msg/ServiceEventInfo",
                   "uint8 REQUEST_SENT = 0\nuint8 event_type\nbuiltin_interfaces/Time stamp\n"
                   "char[16] client_gid\nint64 sequence_number\n");
  return registry;
}

// The hashes rosidl_generator_type_description writes for these types (Jazzy and later).
TEST(TypeHash, MatchesRosidlForStandardTypes) {
  const dyn::TypeRegistry registry = ros2_registry();
  const std::pair<const char*, const char*> known[] = {
      {"builtin_interfaces/msg/Time",
       "RIHS01_b106235e25a4c5ed35098aa0a61a3ee9c9b18d197f398b0e4206cea9acf9c197"},
      {"std_msgs/msg/String",
       "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18"},
      {"std_msgs/msg/Header",
       "RIHS01_f49fb3ae2cf070f793645ff749683ac6b06203e41c891e17701b1cb597ce6a01"},
      {"sensor_msgs/msg/Image",
       "RIHS01_d31d41a9a4c4bc8eae9be757b0beed306564f7526c88ea6a4588fb9582527d47"},
      {"sensor_msgs/msg/JointState",
       "RIHS01_a13ee3a330e346c9d87b5aa18d24e11690752bd33a0350f11c5882bc9179260e"},
      {"diagnostic_msgs/msg/KeyValue",
       "RIHS01_d68081eaa540288c5440753baecef0c4e16e81a5f78ad68902ded5100413bb42"},
      // char[16]: an IDL uint8 array.
      {"service_msgs/msg/ServiceEventInfo",
       "RIHS01_41bcbbe07a75c9b52bc96bfd5c24d7f0fc0a08c0cb7921b3373c5732345a6f45"},
  };
  for (const auto& [type, hash] : known) EXPECT_EQ(type_hash(registry, type), hash) << type;
}

// ros_discovery_info's type is built in, so its endpoints carry the hash rmw gives them.
TEST(TypeHash, DiscoveryTypeIsBuiltIn) {
  EXPECT_EQ(builtin_type_hash("rmw_dds_common/msg/ParticipantEntitiesInfo"),
            "RIHS01_91a0593bacdcc50ea9bdcf849a938b128412cc1ea821245c663bcd26f83c295e");
}

TEST(TypeHash, DescriptionIsRosidlsJson) {
  const dyn::TypeRegistry registry = ros2_registry();
  EXPECT_EQ(type_description_json(registry, "builtin_interfaces/msg/Time"),
            "{\"type_description\": {\"type_name\": \"builtin_interfaces/msg/Time\", \"fields\": "
            "[{\"name\": \"sec\", \"type\": {\"type_id\": 6, \"capacity\": 0, "
            "\"string_capacity\": 0, \"nested_type_name\": \"\"}}, {\"name\": \"nanosec\", "
            "\"type\": {\"type_id\": 7, \"capacity\": 0, \"string_capacity\": 0, "
            "\"nested_type_name\": \"\"}}]}, \"referenced_type_descriptions\": []}");
  // Bounded strings and nested sequences: rmw_dds_common's NodeEntitiesInfo.
  const std::string nodes = type_description_json(registry, "rmw_dds_common/msg/NodeEntitiesInfo");
  EXPECT_NE(nodes.find("{\"name\": \"node_namespace\", \"type\": {\"type_id\": 21, \"capacity\": "
                       "0, \"string_capacity\": 256, \"nested_type_name\": \"\"}}"),
            std::string::npos)
      << nodes;
  EXPECT_NE(nodes.find("{\"type_id\": 145, \"capacity\": 0, \"string_capacity\": 0, "
                       "\"nested_type_name\": \"rmw_dds_common/msg/Gid\"}"),
            std::string::npos)
      << nodes;
}

TEST(TypeHash, EmptyMessageHashesItsPlaceholderMember) {
  dyn::TypeRegistry registry;
  registry.add_msg("std_msgs/msg/Empty", "");
  EXPECT_NE(type_description_json(registry, "std_msgs/msg/Empty")
                .find("\"structure_needs_at_least_one_member\", \"type\": {\"type_id\": 3"),
            std::string::npos);
}

// robotperf's compiled-in definitions give every ROS 2 type the hash of its real .msg file, so
// that the endpoints it creates carry the hash ROS 2 nodes of the same type carry.
TEST(TypeHash, BuiltinTypesHashAsTheRos2MsgFiles) {
  const dyn::TypeRegistry registry = ros2_registry();
  for (std::string_view type : builtin_message_types()) {
    if (type.starts_with("robotperf_msgs/")) continue;  // robotperf's own: no ROS 2 file
    const auto ours = builtin_type_hash(type);
    ASSERT_TRUE(ours.has_value()) << type;
    EXPECT_EQ(*ours, type_hash(registry, std::string(type))) << type;
  }
  EXPECT_EQ(builtin_type_hash("sensor_msgs/msg/Image"),
            "RIHS01_d31d41a9a4c4bc8eae9be757b0beed306564f7526c88ea6a4588fb9582527d47");
  EXPECT_FALSE(builtin_type_hash("no_msgs/msg/Unknown").has_value());
}

// The referenced types are gathered with a stack of their own: a chain of types deeper than the
// call stack goes is described, to its last type, like any other.
TEST(TypeHash, AChainOfTypesDeeperThanTheStackIsDescribedWhole) {
  constexpr int kDepth = 200000;
  dyn::TypeRegistry registry;
  for (int i = 0; i < kDepth; ++i)
    registry.add_msg("p/msg/T" + std::to_string(i), "p/T" + std::to_string(i + 1) + " x\n");
  registry.add_msg("p/msg/T" + std::to_string(kDepth), "uint8 y\n");
  const std::string json = type_description_json(registry, "p/msg/T0");
  EXPECT_NE(json.find("{\"type_name\": \"p/msg/T200000\""), std::string::npos);
}

TEST(TypeHash, UnknownNestedTypeIsAnError) {
  dyn::TypeRegistry registry;
  registry.add_msg("a_msgs/msg/A", "b_msgs/B inner\n");
  EXPECT_THROW(type_hash(registry, "a_msgs/msg/A"), dyn::DefinitionError);
}

}  // namespace
}  // namespace robotperf::msgs
