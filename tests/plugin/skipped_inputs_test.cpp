#include <gtest/gtest.h>

#include "robotperf/plugin/kernel.hpp"

namespace robotperf::plugin {
namespace {

TEST(SkippedInputs, CountsEveryInputAndSaysTheFirstOnOneLine) {
  SkippedInputs skipped{"request"};
  testing::internal::CaptureStderr();
  skipped.note("/planner", "joint 3 is out of its limits\n");
  skipped.note("/planner", "another reason");
  const std::string said = testing::internal::GetCapturedStderr();
  EXPECT_EQ(skipped.count(), 2u);
  EXPECT_EQ(said, "robotperf node /planner: skipping request: joint 3 is out of its limits\n");
}

TEST(SkippedInputs, SaysInputByDefault) {
  SkippedInputs skipped;
  testing::internal::CaptureStderr();
  skipped.note("/rectify", "image is 0x0");
  EXPECT_EQ(testing::internal::GetCapturedStderr(),
            "robotperf node /rectify: skipping input: image is 0x0\n");
  EXPECT_EQ(skipped.count(), 1u);
}

}  // namespace
}  // namespace robotperf::plugin
