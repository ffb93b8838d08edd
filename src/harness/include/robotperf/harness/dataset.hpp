// DataLoader: datasets are loaded whole into memory before any timing starts.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "robotperf/msgs/type_support.hpp"
#include "robotperf/rmw/transport.hpp"

namespace robotperf::harness {

// One kind of message of a dataset, one per frame (e.g. "image", "camera_info").
// Streams loaded from a bag hold msgs::SerializedMessage payloads under
// msgs::serialized_type_support(<their ROS type>), all with a std_msgs/Header.
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
  // Bags only: when each frame was recorded (its earliest message), increasing.
  std::vector<int64_t> frame_times_ns;
  // Generated request streams: the workload they were generated with, defaults filled in
  // (seed, requests, ...), recorded with the results.
  std::map<std::string, std::string> parameters;

  // Throws std::invalid_argument naming the available streams.
  const DatasetStream& stream(const std::string& name) const;
};

struct DatasetInfo {
  std::string name;
  std::string description;
};

const std::vector<DatasetInfo>& builtin_datasets();

// Loads a built-in dataset (generated once per process, then shared); throws
// std::invalid_argument for an unknown name. `workload` configures the generated request streams
// (manipulation/*: seed, requests, near_fraction); other datasets take none.
Dataset load_dataset(const std::string& name,
                     const std::map<std::string, std::string>& workload = {});

// A rosbag2 bag to replay instead of a benchmark's built-in dataset.
struct BagSelection {
  std::filesystem::path path;
  // Bag topic -> benchmark input topic (`--remap from:=to`); unmapped topics keep their name.
  std::map<std::string, std::string> remaps;
  // Only messages recorded in [start, end] seconds after the bag's start.
  std::optional<double> start_s;
  std::optional<double> end_s;
};

struct BoundaryTopic;  // benchmark_spec.hpp, which includes this header

// DataLoader for bags: reads the bag topics that feed `inputs` (after
// remapping) into memory, undecoded. Each input becomes a stream named like
// the input's `stream`. With several inputs, the messages whose header stamps
// are equal form one frame (e.g. an image and its camera_info); frames that
// miss a topic are left out. Throws BenchmarkError (bag::BagError for
// unreadable files) when an input has no topic, a type differs, or a type
// has no std_msgs/Header to carry message IDs.
Dataset load_bag_dataset(const BagSelection& bag, const std::vector<BoundaryTopic>& inputs);

}  // namespace robotperf::harness
