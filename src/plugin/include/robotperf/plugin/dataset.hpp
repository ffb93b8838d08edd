// Datasets: the input streams a benchmark plays into its graph and the ground truth its outputs
// are checked against. A dataset generator is registered with a description of its streams and
// workload parameters, and a function that generates the messages, deterministically: the same
// workload gives the same bytes on every machine.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "robotperf/msgs/type_support.hpp"
#include "robotperf/plugin/parameters.hpp"
#include "robotperf/rmw/transport.hpp"

namespace robotperf::plugin {

// One kind of message of a dataset, one per frame (e.g. "image", "camera_info").
struct StreamInfo {
  std::string name{};
  std::string topic;   // where it is recorded when written as a bag ("/camera/image_raw")
  std::string type{};  // ROS type, e.g. sensor_msgs/msg/Image
  bool truth = false;  // ground truth, for evaluators; never played into the graph
  std::string doc{};   // one line
};

struct DatasetInfo {
  std::string name{};         // "<category>/<dataset>", e.g. perception/image
  std::string description{};  // one line
  double rate_hz = 0;         // the rate it was recorded (or generated) at
  std::size_t frames = 0;     // with the default workload
  std::vector<StreamInfo> streams{};
  // benchmark.yaml `workload:` parameters (e.g. seed, requests); none for a fixed sequence.
  std::vector<ParameterInfo> workload{};
  // Limits that involve several workload parameters (each one's own range is its bounds):
  // throws std::invalid_argument saying which and what to give instead. Called before any run
  // (a sweep calls it for every value before the first) and before the generator.
  std::function<void(const Parameters& workload)> check_workload{};
};

// The messages of one stream. Streams loaded from a bag hold msgs::SerializedMessage payloads
// under msgs::serialized_type_support(<their ROS type>), all with a std_msgs/Header.
struct DatasetStream {
  std::string name{};
  std::string topic{};
  const msgs::TypeSupport* type = nullptr;
  std::vector<rmw::MessagePtr> messages{};
};

struct Dataset {
  std::string name{};
  std::string description{};
  std::string hash;  // content hash of every message of every stream (filled by robotperf)
  std::size_t frames = 0;
  double rate_hz = 0;
  std::vector<DatasetStream> streams{};
  // Bags only: when each frame was recorded (its earliest message), increasing.
  std::vector<int64_t> frame_times_ns{};
  // The workload the dataset was generated with, defaults filled in (recorded with results).
  std::map<std::string, std::string> parameters{};

  // Throws std::invalid_argument naming the available streams.
  const DatasetStream& stream(const std::string& name) const;
};

// Generates the streams of the dataset's StreamInfo, in that order, each with the same number of
// messages; robotperf fills in the name, description, rate, frames, hash and parameters.
using DatasetGenerator = std::function<std::vector<DatasetStream>(const Parameters& workload)>;

// An empty stream of the dataset's declared stream `name`, ready to be filled.
template <class T>
DatasetStream make_stream(const std::string& name, const std::string& topic) {
  return DatasetStream{name, topic, &msgs::type_support<T>(), {}};
}

// Appends one message to a stream.
template <class T>
void append(DatasetStream& stream, T&& message) {
  stream.messages.push_back(std::make_shared<const std::decay_t<T>>(std::forward<T>(message)));
}

}  // namespace robotperf::plugin
