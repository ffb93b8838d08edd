// Parameters: declared with a type and a default, given as text, checked when they are read in.
#include "robotperf/plugin/parameters.hpp"

#include <gtest/gtest.h>

#include <tuple>

namespace robotperf::plugin {
namespace {

std::vector<ParameterInfo> declared() {
  return {bool_parameter("flag", true, "a flag"), int_parameter("count", 5, "a count"),
          double_parameter("scale", 1.5, "a scale"), string_parameter("mode", "fast", "a mode"),
          computed_parameter("seed", ParameterType::kInt, "default: the workload's")};
}

TEST(Parameters, DefaultsAreReadInTheirDeclaredType) {
  const Parameters p(declared(), {}, "node 'n'");
  EXPECT_TRUE(p.get_bool("flag"));
  EXPECT_EQ(p.get_int("count"), 5);
  EXPECT_DOUBLE_EQ(p.get_double("scale"), 1.5);
  EXPECT_EQ(p.get_string("mode"), "fast");
  EXPECT_FALSE(p.has("count"));
  EXPECT_EQ(p.get_int("seed", 42), 42);
}

TEST(Parameters, GivenValuesWin) {
  const Parameters p(
      declared(),
      {{"flag", "false"}, {"count", "-3"}, {"scale", "2e-3"}, {"mode", "slow"}, {"seed", "9"}},
      "node 'n'");
  EXPECT_FALSE(p.get_bool("flag"));
  EXPECT_EQ(p.get_int("count"), -3);
  EXPECT_DOUBLE_EQ(p.get_double("scale"), 2e-3);
  EXPECT_EQ(p.get_string("mode"), "slow");
  EXPECT_EQ(p.get_int("seed", 42), 9);
  EXPECT_TRUE(p.has("count"));
}

// An integer read into an int is refused beyond int's range, named, rather than wrapped (a cast
// made 4294967303 threads 7).
TEST(Parameters, AnIntBeyondThirtyTwoBitsIsRefusedNotWrapped) {
  EXPECT_EQ(Parameters(declared(), {{"count", "-2147483648"}}, "node 'n'").get_int32("count"),
            -2147483648LL);
  const Parameters p(declared(), {{"count", "4294967303"}}, "node 'n'");
  EXPECT_EQ(p.get_int("count"), 4294967303LL);
  try {
    (void)p.get_int32("count");
    ADD_FAILURE() << "4294967303 was read into an int";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "node 'n': parameter 'count' is 4294967303, beyond a 32-bit integer");
  }
}

TEST(Parameters, UnknownNameIsRefusedListingTheKnownOnes) {
  try {
    Parameters(declared(), {{"scael", "2"}}, "node 'resize'");
    FAIL() << "accepted an unknown parameter";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("node 'resize'"), std::string::npos) << what;
    EXPECT_NE(what.find("unknown parameter 'scael'"), std::string::npos) << what;
    EXPECT_NE(what.find("scale"), std::string::npos) << what;
  }
  EXPECT_THROW(Parameters({}, {{"x", "1"}}, "node 'n'"), std::invalid_argument);
}

TEST(Parameters, ValueOfTheWrongTypeIsRefusedNamingIt) {
  for (const auto& [name, text] : std::vector<std::pair<std::string, std::string>>{
           {"flag", "yes"}, {"count", "2.5"}, {"count", ""}, {"scale", "1.0x"}}) {
    try {
      Parameters(declared(), {{name, text}}, "node 'n'");
      FAIL() << name << " accepted '" << text << "'";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("parameter '" + name + "'"), std::string::npos)
          << e.what();
    }
  }
}

// A value outside its declared range is refused naming the parameter and the range; the ends
// are inside, NaN is not.
TEST(Parameters, AValueOutsideItsBoundsIsRefusedNamingTheRange) {
  const std::vector<ParameterInfo> bounded = {
      int_parameter("bytes", 64, "payload", {.minimum = 1, .maximum = 1024}),
      double_parameter("fraction", 0.5, "share", {.minimum = 0, .maximum = 1}),
      int_parameter("count", 1, "at least one", {.minimum = 1})};
  for (const auto& [name, text] : std::vector<std::pair<std::string, std::string>>{
           {"bytes", "1"}, {"bytes", "1024"}, {"fraction", "0"}, {"count", "99999999"}}) {
    EXPECT_NO_THROW(Parameters(bounded, {{name, text}}, "dataset d workload")) << name << text;
  }
  for (const auto& [name, text, range] :
       std::vector<std::tuple<std::string, std::string, std::string>>{
           {"bytes", "300000000", "1 to 1024"},
           {"bytes", "0", "1 to 1024"},
           {"fraction", "1.5", "0 to 1"},
           {"fraction", "nan", "0 to 1"},
           {"count", "-3", "at least 1"}}) {
    try {
      Parameters(bounded, {{name, text}}, "dataset d workload");
      FAIL() << name << " accepted '" << text << "'";
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("parameter '" + name + "'"), std::string::npos) << what;
      EXPECT_NE(what.find("outside its range, " + range), std::string::npos) << what;
    }
  }
}

TEST(Parameters, ReadingAnUndeclaredOrMistypedParameterIsABug) {
  const Parameters p(declared(), {}, "node 'n'");
  EXPECT_THROW(p.get_int("undeclared"), std::logic_error);
  EXPECT_THROW(p.get_double("count"), std::logic_error);  // declared int
  EXPECT_THROW(p.get_int("seed"), std::logic_error);      // no default: needs a fallback
}

TEST(Parameters, EffectiveValuesFillInDefaults) {
  const Parameters p(declared(), {{"count", "7"}}, "node 'n'");
  const auto e = p.effective();
  EXPECT_EQ(e.at("count"), "7");
  EXPECT_EQ(e.at("scale"), "1.5");
  EXPECT_EQ(e.at("flag"), "true");
  EXPECT_FALSE(e.contains("seed"));
}

TEST(Parameters, DeclaredDefaultsRoundTrip) {
  EXPECT_EQ(*double_parameter("x", 0.1, "").default_value, "0.1");
  EXPECT_EQ(*double_parameter("x", 360000, "").default_value, "360000");
  EXPECT_EQ(*int_parameter("x", -1, "").default_value, "-1");
  EXPECT_EQ(*bool_parameter("x", false, "").default_value, "false");
}

}  // namespace
}  // namespace robotperf::plugin
