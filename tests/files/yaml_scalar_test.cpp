#include "robotperf/files/yaml_scalar.hpp"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <string>

namespace robotperf::files {
namespace {

const char* const kAwkward[] = {"plain",
                                "true",
                                "No",
                                "2023-07-06 08:05:58",
                                "07-07-2023",
                                "a: b",
                                "with: colon",
                                "#x",
                                "- x",
                                "tab\there",
                                "line\nbreak",
                                "quote \" and \\",
                                "\x01 control \x7f",
                                "ROBOTCORE\xC2\xAE Perception",
                                "null",
                                "Yes",
                                "trailing ",
                                "12",
                                "[x]",
                                "{y}",
                                "x # y",
                                "%",
                                ""};

TEST(YamlScalar, EveryTextReadsBackAsItself) {
  for (const std::string s : kAwkward) {
    EXPECT_EQ(YAML::Load("k: " + yaml_scalar(s))["k"].as<std::string>(), s) << yaml_scalar(s);
    EXPECT_EQ(YAML::Load("k: " + yaml_double_quoted(s))["k"].as<std::string>(), s)
        << yaml_double_quoted(s);
  }
}

TEST(YamlScalar, PlainOnlyWhereNothingElseCanBeRead) {
  EXPECT_EQ(yaml_scalar("Intel i7-8700 (x86_64)"), "Intel i7-8700 (x86_64)");
  EXPECT_EQ(yaml_scalar("null"), "\"null\"");
  EXPECT_EQ(yaml_scalar("12"), "\"12\"");
  EXPECT_EQ(yaml_scalar("trailing "), "\"trailing \"");
  EXPECT_EQ(yaml_double_quoted("a\x01"), "\"a\\x01\"");
  EXPECT_EQ(yaml_double_quoted("/camera/image_raw"), "\"/camera/image_raw\"");
}

}  // namespace
}  // namespace robotperf::files
