// The shared data folder the tests read: real files other projects wrote (ROS 2 bags, .msg
// definitions, the published RobotPerf results, the xArm6 description). It lies beside the
// checkout (../shared/data); the environment variable ROBOTPERF_SHARED_DATA names another place.
#pragma once

#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <string>

// `relative` inside the shared data folder. A missing path throws, so that the test fails on one
// line naming it instead of reading nothing and failing (or crashing) somewhere later. Call it in
// a test's body, not at namespace scope: a throw there would end the whole program.
inline std::filesystem::path shared_data(const std::string& relative) {
  const char* overridden = std::getenv("ROBOTPERF_SHARED_DATA");
  const std::filesystem::path root =
      overridden != nullptr && *overridden != '\0' ? overridden : ROBOTPERF_SHARED_DATA_DIR;
  std::filesystem::path path = root / relative;
  if (!std::filesystem::exists(path)) {
    throw std::runtime_error(path.string() +
                             " is missing: the tests read the shared data folder, ../shared/data "
                             "beside the checkout (or the folder ROBOTPERF_SHARED_DATA names)");
  }
  return path;
}
