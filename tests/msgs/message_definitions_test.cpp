// The compiled-in message types against the ROS 2 .msg files in the shared
// reference data: same fields as ROS 2 defines them, and CDR bytes that a
// codec driven only by those .msg files decodes and re-encodes identically.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "../shared_data.hpp"
#include "robotperf/msgs/cdr.hpp"
#include "robotperf/msgs/definitions.hpp"
#include "robotperf/msgs/dynamic.hpp"
#include "robotperf/msgs/known_types.hpp"

namespace robotperf::msgs {
namespace {

namespace dyn = dynamic;

// Fills every field with a value that differs from its neighbours and from the
// default, and every sequence with two elements, so that a field out of order
// or of the wrong width changes the bytes.
struct Filler {
  int next = 1;
  template <CdrPrimitive T>
  void operator()(T& x) {
    if constexpr (std::is_same_v<T, bool>) {
      x = next++ % 2 == 1;
    } else {
      x = static_cast<T>(next++ % 100 + 1);
    }
  }
  void operator()(std::string& s) { s = "s" + std::to_string(next++); }
  template <class T>
  void operator()(std::vector<T>& seq) {
    seq.resize(2);
    for (T& x : seq) (*this)(x);
  }
  template <class T, std::size_t N>
  void operator()(std::array<T, N>& arr) {
    for (T& x : arr) (*this)(x);
  }
  template <class T>
  requires(!CdrPrimitive<T>) void operator()(T& m) { visit_fields(*this, m); }
};

// robotperf_msgs are robotperf's own types; the ROS 2 .msg files do not define them.
bool is_robotperf_own(std::string_view type) {
  return type.starts_with("robotperf_msgs/");
}

dyn::TypeRegistry shared_registry() {
  dyn::TypeRegistry registry;
  EXPECT_GT(registry.add_directory(shared_data("msg")), 100u)
      << "expected the ROS 2 .msg files in " << shared_data("msg");
  return registry;
}

TEST(MessageDefinitions, FieldsMatchTheRos2MsgFiles) {
  const dyn::TypeRegistry shared = shared_registry();
  const auto types = builtin_message_types();
  ASSERT_GE(types.size(), 30u);
  for (std::string_view type : types) {
    if (is_robotperf_own(type)) continue;  // not ROS 2 interfaces: nothing to compare with
    SCOPED_TRACE(std::string(type));
    dyn::TypeRegistry ours;
    ours.add_ros2msg(std::string(type), *ros2msg_schema(type));
    ASSERT_NO_THROW(ours.check_complete(std::string(type)));
    const auto& mine = ours.get(std::string(type)).fields;
    const auto& ros = shared.get(std::string(type)).fields;
    ASSERT_EQ(mine.size(), ros.size());
    for (std::size_t i = 0; i < mine.size(); ++i) {
      EXPECT_EQ(mine[i].name, ros[i].name);
      EXPECT_EQ(mine[i].type.primitive, ros[i].type.primitive) << mine[i].name;
      EXPECT_EQ(mine[i].type.message_type, ros[i].type.message_type) << mine[i].name;
      EXPECT_EQ(mine[i].type.array, ros[i].type.array) << mine[i].name;
      EXPECT_EQ(mine[i].type.array_size, ros[i].type.array_size) << mine[i].name;
    }
  }
}

TEST(MessageDefinitions, CompiledTypesRoundTripThroughTheRos2Definitions) {
  const dyn::TypeRegistry shared = shared_registry();
  std::size_t checked = 0;
  [&]<class... Ts>(MessageTypeList<Ts...>) {
    (
        [&]<class T>() {
          const std::string type(MessageTraits<T>::ros_type);
          SCOPED_TRACE(type);
          T msg{};
          Filler{}(msg);
          const std::vector<uint8_t> cdr = to_cdr(msg);
          // Our own types against the definitions we publish for them (with the ROS 2 ones
          // they nest).
          dyn::TypeRegistry own;
          if (is_robotperf_own(type)) own.add_ros2msg(type, *ros2msg_schema(type));
          const dyn::TypeRegistry& registry = is_robotperf_own(type) ? own : shared;
          const dyn::Value value = dyn::decode(registry, type, cdr);
          EXPECT_EQ(dyn::encode(registry, type, value), cdr);
          EXPECT_TRUE(from_cdr<T>(cdr) == msg);
          ++checked;
        }.template operator()<Ts>(),
        ...);
  }(KnownMessageTypes{});
  EXPECT_EQ(checked, 22u);
}

TEST(MessageDefinitions, DispatchFindsEveryKnownTypeAndRejectsOthers) {
  std::string seen;
  EXPECT_TRUE(with_message_type("nav_msgs/msg/Odometry",
                                [&]<class T>() { seen = MessageTraits<T>::ros_type; }));
  EXPECT_EQ(seen, "nav_msgs/msg/Odometry");
  EXPECT_FALSE(with_message_type("std_msgs/msg/String", []<class T>() {}));
}

TEST(MessageDefinitions, SchemaListsEachDependencyOnce) {
  const std::string schema = *ros2msg_schema("control_msgs/msg/JointTrajectoryControllerState");
  auto count = [&](const std::string& needle) {
    std::size_t n = 0;
    for (auto pos = schema.find(needle); pos != std::string::npos;
         pos = schema.find(needle, pos + 1))
      ++n;
    return n;
  };
  EXPECT_EQ(count("MSG: trajectory_msgs/JointTrajectoryPoint\n"), 1u);
  EXPECT_EQ(count("MSG: geometry_msgs/Vector3\n"), 1u);
  EXPECT_EQ(count("MSG: builtin_interfaces/Duration\n"), 1u);
  EXPECT_FALSE(ros2msg_schema("std_msgs/msg/String").has_value());
}

}  // namespace
}  // namespace robotperf::msgs
