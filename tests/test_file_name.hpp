// The running test's name as one file name, for its scratch folders.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <string>

namespace robotperf::testing {

// "Suite-Test": a parameterised test's "Prefix/Suite" and "Test/param" with each '/' a '-', so
// that its scratch folder is one folder, not a folder in another that removing it leaves behind.
inline std::string current_test_file_name() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string name = std::string(info->test_suite_name()) + "-" + info->name();
  std::replace(name.begin(), name.end(), '/', '-');
  return name;
}

}  // namespace robotperf::testing
