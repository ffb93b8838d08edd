// DataLoader: datasets are loaded whole into memory before any timing starts.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "robotperf/msgs/type_support.hpp"
#include "robotperf/rmw/transport.hpp"

namespace robotperf::harness {

// One kind of message of a dataset, one per frame (e.g. "image", "camera_info").
struct DatasetStream {
  std::string name;
  std::string topic;  // where it is recorded when written as a bag ("/camera/image_raw")
  const msgs::TypeSupport* type = nullptr;
  std::vector<rmw::MessagePtr> messages;
};

struct Dataset {
  std::string name;
  std::string description;
  std::string hash;  // content hash of every message of every stream
  std::size_t frames = 0;
  double rate_hz = 0;  // the rate it was recorded (or generated) at
  std::vector<DatasetStream> streams;

  // Throws std::invalid_argument naming the available streams.
  const DatasetStream& stream(const std::string& name) const;
};

struct DatasetInfo {
  std::string name;
  std::string description;
};

const std::vector<DatasetInfo>& builtin_datasets();

// Loads a built-in dataset (generated once per process, then shared); throws
// std::invalid_argument for an unknown name.
Dataset load_dataset(const std::string& name);

}  // namespace robotperf::harness
