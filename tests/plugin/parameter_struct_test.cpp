// Typed parameters: a settings struct declared once, its parameters' types deduced from its
// members, read back whole.
#include "robotperf/plugin/parameter_struct.hpp"

#include <gtest/gtest.h>

namespace robotperf::plugin {
namespace {

struct Limits {
  double max_speed = 0;
  std::optional<double> min_speed;
};

struct Settings {
  bool flag = false;
  int threads = 0;
  int64_t count = 0;
  uint64_t seed = 0;
  uint8_t level = 0;
  double scale = 0;
  std::string mode;
  std::optional<int64_t> window;
  Limits limits;
};

ParameterStruct<Limits> limit_parameters(const std::string& axis) {
  return ParameterStruct<Limits>{
      field(&Limits::max_speed, axis + ".max_speed", 2, "largest speed", {.minimum = 0}),
      field(&Limits::min_speed, axis + ".min_speed", "smallest speed (default: -max_speed)")};
}

const ParameterStruct<Settings> kParameters{
    field(&Settings::flag, "flag", true, "a flag"),
    field(&Settings::threads, "threads", 4, "worker threads", {.minimum = 1, .maximum = 64}),
    field(&Settings::count, "count", -5, "a count"),
    field(&Settings::seed, "seed", 7, "a seed"),
    field(&Settings::level, "level", 3, "a level"),
    field(&Settings::scale, "scale", 1.5, "a scale", {.maximum = 10}),
    field(&Settings::mode, "mode", "fast", "a mode"),
    field(&Settings::window, "window", "default: the workload's", {.minimum = 1}),
    nested(&Settings::limits, limit_parameters("linear"))};

Parameters given(const std::map<std::string, std::string>& values) {
  return Parameters(kParameters.declarations(), values, "node 'n'");
}

const ParameterInfo& declaration(const std::string& name) {
  static const std::vector<ParameterInfo> all = kParameters.declarations();
  for (const auto& d : all) {
    if (d.name == name) return d;
  }
  throw std::out_of_range(name);
}

TEST(ParameterStruct, TypesFollowFromTheMembers) {
  EXPECT_EQ(declaration("flag").type, ParameterType::kBool);
  EXPECT_EQ(declaration("threads").type, ParameterType::kInt);
  EXPECT_EQ(declaration("seed").type, ParameterType::kInt);
  EXPECT_EQ(declaration("level").type, ParameterType::kInt);
  EXPECT_EQ(declaration("scale").type, ParameterType::kDouble);
  EXPECT_EQ(declaration("mode").type, ParameterType::kString);
  EXPECT_EQ(declaration("window").type, ParameterType::kInt);
  EXPECT_EQ(declaration("linear.min_speed").type, ParameterType::kDouble);
}

// The declarations are what the untyped helpers make: list and describe show the same.
TEST(ParameterStruct, DeclarationsKeepOrderDefaultsDocsAndBounds) {
  const std::vector<ParameterInfo> all = kParameters.declarations();
  std::vector<std::string> names;
  for (const auto& d : all) names.push_back(d.name);
  EXPECT_EQ(names,
            (std::vector<std::string>{"flag", "threads", "count", "seed", "level", "scale", "mode",
                                      "window", "linear.max_speed", "linear.min_speed"}));
  EXPECT_EQ(declaration("flag").default_value, "true");
  EXPECT_EQ(declaration("count").default_value, "-5");
  EXPECT_EQ(declaration("scale").default_value, "1.5");
  EXPECT_EQ(declaration("linear.max_speed").default_value, "2");
  EXPECT_EQ(declaration("mode").default_value, "fast");
  EXPECT_EQ(declaration("mode").doc, "a mode");
  EXPECT_EQ(declaration("window").default_value, std::nullopt);
  EXPECT_EQ(bounds_text(declaration("threads").bounds), "1 to 64");
  EXPECT_EQ(bounds_text(declaration("scale").bounds), "at most 10");
  EXPECT_EQ(bounds_text(declaration("window").bounds), "at least 1");
  EXPECT_EQ(bounds_text(declaration("linear.max_speed").bounds), "at least 0");
  EXPECT_EQ(bounds_text(declaration("count").bounds), "");
}

TEST(ParameterStruct, DefaultsFillTheStructAndComputedOnesStayEmpty) {
  const Settings s = kParameters.read(given({}));
  EXPECT_TRUE(s.flag);
  EXPECT_EQ(s.threads, 4);
  EXPECT_EQ(s.count, -5);
  EXPECT_EQ(s.seed, 7u);
  EXPECT_EQ(s.level, 3);
  EXPECT_DOUBLE_EQ(s.scale, 1.5);
  EXPECT_EQ(s.mode, "fast");
  EXPECT_EQ(s.window, std::nullopt);
  EXPECT_DOUBLE_EQ(s.limits.max_speed, 2);
  EXPECT_EQ(s.limits.min_speed, std::nullopt);
}

TEST(ParameterStruct, GivenValuesWinNestedOnesToo) {
  const Parameters p = given({{"flag", "false"},
                              {"threads", "8"},
                              {"seed", "18446744"},
                              {"scale", "2e-3"},
                              {"mode", "slow"},
                              {"window", "9"},
                              {"linear.min_speed", "-0.5"}});
  const Settings s = kParameters.read(p);
  EXPECT_FALSE(s.flag);
  EXPECT_EQ(s.threads, 8);
  EXPECT_EQ(s.seed, 18446744u);
  EXPECT_DOUBLE_EQ(s.scale, 2e-3);
  EXPECT_EQ(s.mode, "slow");
  EXPECT_EQ(s.window, 9);
  EXPECT_EQ(s.limits.min_speed, -0.5);
  EXPECT_TRUE(kParameters.given(p, s, s.limits.min_speed));
  EXPECT_FALSE(kParameters.given(p, s, s.limits.max_speed));
  EXPECT_TRUE(kParameters.given(p, s, s.mode));
  EXPECT_FALSE(kParameters.given(p, s, s.count));
  const double copy = s.scale;
  EXPECT_THROW(kParameters.given(p, s, copy), std::logic_error);
}

// A value the declaration accepts (an int64) but the member cannot hold is refused, naming the
// parameter and the member's range, rather than wrapped.
TEST(ParameterStruct, AnIntegerBeyondItsMembersRangeIsRefusedNotWrapped) {
  for (const auto& [name, value, type] :
       std::vector<std::tuple<std::string, std::string, std::string>>{
           {"count", "-4294967303", ""},
           {"seed", "-1", "a 64-bit unsigned integer"},
           {"level", "256", "an 8-bit unsigned integer"},
           {"level", "-1", "an 8-bit unsigned integer"},
           {"window", "4294967303", ""}}) {
    const Parameters p = given({{name, value}});
    if (type.empty()) {
      EXPECT_NO_THROW(kParameters.read(p)) << name << " " << value;
      continue;
    }
    try {
      (void)kParameters.read(p);
      ADD_FAILURE() << name << " read " << value;
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()),
                "node 'n': parameter '" + name + "' is " + value + ", beyond " + type);
    }
  }
  EXPECT_EQ(kParameters.read(given({{"level", "255"}})).level, 255);
}

TEST(ParameterStruct, BoundsAreStillCheckedWhereTheValuesAreGiven) {
  EXPECT_THROW(given({{"threads", "0"}}), std::invalid_argument);
  EXPECT_THROW(given({{"window", "0"}}), std::invalid_argument);
  EXPECT_THROW(given({{"linear.max_speed", "-1"}}), std::invalid_argument);
  EXPECT_THROW(given({{"mode", "x"}, {"moed", "y"}}), std::invalid_argument);
}

TEST(ParameterStruct, BoundsOnAnythingButANumberAreAMistakeOfTheDeclaration) {
  EXPECT_THROW(field(&Settings::mode, "mode", "fast", "a mode", {.minimum = 0}), std::logic_error);
  EXPECT_THROW(field(&Settings::flag, "flag", true, "a flag", {.maximum = 1}), std::logic_error);
  EXPECT_THROW(field(&Settings::seed, "seed", UINT64_MAX, "a seed"), std::logic_error);
}

}  // namespace
}  // namespace robotperf::plugin
