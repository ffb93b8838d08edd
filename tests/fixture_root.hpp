// A fresh directory tree standing in for "/" (or a sysfs root) in tests that
// read system files; removed again when the fixture goes out of scope.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace robotperf::testing {

class FixtureRoot {
 public:
  FixtureRoot() {
    // Unique per process, test and fixture: one test may hold several trees.
    static int counter = 0;
    const auto* test = ::testing::UnitTest::GetInstance()->current_test_info();
    root_ = std::filesystem::temp_directory_path() /
            ("robotperf_fixture_" + std::string(test->test_suite_name()) + "_" + test->name() +
             "_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    std::filesystem::remove_all(root_);
    std::filesystem::create_directories(root_);
  }
  ~FixtureRoot() { std::filesystem::remove_all(root_); }
  FixtureRoot(const FixtureRoot&) = delete;
  FixtureRoot& operator=(const FixtureRoot&) = delete;

  const std::filesystem::path& path() const { return root_; }

  // Writes `content` to `relative` under the root, creating its folders.
  void write(const std::string& relative, const std::string& content) const {
    const std::filesystem::path file = root_ / relative;
    std::filesystem::create_directories(file.parent_path());
    std::ofstream(file, std::ios::binary) << content;
  }

 private:
  std::filesystem::path root_;
};

}  // namespace robotperf::testing
