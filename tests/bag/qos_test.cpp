#include "robotperf/bag/qos.hpp"

#include <gtest/gtest.h>

namespace robotperf::bag {
namespace {

constexpr const char* kHumble =
    "- history: 1\n  depth: 10\n  reliability: 2\n  durability: 2\n  deadline:\n    sec: 0\n"
    "    nsec: 0\n  lifespan:\n    sec: 0\n    nsec: 0\n  liveliness: 1\n"
    "  liveliness_lease_duration:\n    sec: 0\n    nsec: 0\n"
    "  avoid_ros_namespace_conventions: false";

constexpr const char* kJazzy =
    "- history: keep_last\n  depth: 10\n  reliability: best_effort\n  durability: volatile\n"
    "  deadline:\n    sec: 0\n    nsec: 0\n  lifespan:\n    sec: 0\n    nsec: 0\n"
    "  liveliness: automatic\n  liveliness_lease_duration:\n    sec: 0\n    nsec: 0\n"
    "  avoid_ros_namespace_conventions: false";

TEST(Qos, BothEncodingsParseToTheSameProfile) {
  const auto humble = parse_qos_profiles(kHumble);
  const auto jazzy = parse_qos_profiles(kJazzy);
  ASSERT_EQ(humble.size(), 1u);
  EXPECT_EQ(humble, jazzy);
  EXPECT_EQ(humble[0].history, 1);
  EXPECT_EQ(humble[0].depth, 10);
  EXPECT_EQ(humble[0].reliability, 2);
  EXPECT_EQ(describe_qos(humble[0]), "best_effort, volatile, keep_last 10");
}

TEST(Qos, IntegerEncodingIsKeptByteForByteAndNamesAreConverted) {
  EXPECT_TRUE(qos_uses_integer_enums(kHumble));
  EXPECT_FALSE(qos_uses_integer_enums(kJazzy));
  EXPECT_EQ(qos_with_integer_enums(kHumble), kHumble);
  EXPECT_EQ(qos_with_integer_enums(kJazzy), kHumble);
  EXPECT_EQ(qos_profiles_to_yaml(parse_qos_profiles(kHumble)), kHumble);
}

TEST(Qos, EmptyAndMalformed) {
  EXPECT_TRUE(parse_qos_profiles("").empty());
  EXPECT_THROW(parse_qos_profiles("- history: sometimes"), std::invalid_argument);
  EXPECT_THROW(parse_qos_profiles("history: 1"), std::invalid_argument);
  EXPECT_THROW(parse_qos_profiles("- [unclosed"), std::invalid_argument);
}

// A policy given as a list or a map is not QoS: the same std::invalid_argument as any other bad
// value, from each function, never yaml-cpp's own exception.
TEST(Qos, APolicyThatIsNeitherANameNorANumberIsMalformed) {
  for (const char* qos : {"- history: [3]", "- reliability: {a: 1}"}) {
    EXPECT_THROW(parse_qos_profiles(qos), std::invalid_argument) << qos;
    EXPECT_FALSE(qos_uses_integer_enums(qos)) << qos;
    EXPECT_THROW(qos_with_integer_enums(qos), std::invalid_argument) << qos;
  }
}

}  // namespace
}  // namespace robotperf::bag
