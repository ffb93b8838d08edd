// Helpers shared by the bag tests: the reference bags and scratch directories.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "../shared_data.hpp"
#include "../test_file_name.hpp"
#include "robotperf/bag/bag.hpp"

namespace robotperf::bag::testing {

namespace fs = std::filesystem;

inline fs::path reference_bag(const std::string& name) {
  return shared_data("rosbag2/" + name);
}

// A fresh directory per test, removed afterwards.
class ScratchDir {
 public:
  ScratchDir() {
    path_ = fs::temp_directory_path() / ("robotperf-bag-" + std::to_string(::getpid()) + "-" +
                                         ::robotperf::testing::current_test_file_name());
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }
  fs::path operator/(const std::string& name) const { return path_ / name; }

 private:
  fs::path path_;
};

inline std::vector<uint8_t> read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

inline void write_file(const fs::path& p, const std::vector<uint8_t>& bytes) {
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
}

struct Recorded {
  std::string topic;
  int64_t timestamp_ns;
  std::vector<uint8_t> data;
  friend bool operator==(const Recorded&, const Recorded&) = default;
};

inline std::vector<Recorded> read_all(const fs::path& path, const ReadOptions& options = {}) {
  Reader reader(path, options);
  std::vector<Recorded> out;
  Message m;
  while (reader.next(m)) out.push_back({reader.topics()[m.topic].name, m.timestamp_ns, m.data});
  return out;
}

}  // namespace robotperf::bag::testing
