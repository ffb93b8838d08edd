// DataLoader: datasets are loaded whole into memory before any timing starts.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "robotperf/plugin/dataset.hpp"

namespace robotperf::harness {

// Datasets are what the plug-in API defines; the DataLoader fills them from the registered
// generators or from a bag.
using plugin::Dataset;
using plugin::DatasetStream;

// Loads a registered dataset, generated once per process and workload, then shared (copies share
// the messages). `workload` sets the generator's workload parameters (benchmark.yaml
// `workload:`). Throws std::invalid_argument for an unknown dataset or workload parameter, and
// std::runtime_error naming the generator when what it generated does not match its description.
Dataset load_dataset(const std::string& name,
                     const std::map<std::string, std::string>& workload = {});

// Checks `workload` as load_dataset reads it (the parameters' names and types) without generating
// anything, so that a series of runs can refuse a bad value before the first run.
void check_workload(const std::string& name, const std::map<std::string, std::string>& workload);

// The content hash of the streams' CDR bytes: identifies the data as it goes on the wire, whatever
// produced it.
std::string content_hash(const std::vector<DatasetStream>& streams);

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
// has no std_msgs/Header to carry message IDs. Messages that do not decode as
// their type (a corrupt payload, a header that cannot be read) are left out of
// the replay, so that the graph is never blamed for them; `corrupt`, when
// given, gets one line per topic that had any, saying how many and why.
Dataset load_bag_dataset(const BagSelection& bag, const std::vector<BoundaryTopic>& inputs,
                         std::vector<std::string>* corrupt = nullptr);

}  // namespace robotperf::harness
