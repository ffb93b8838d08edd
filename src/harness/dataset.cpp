#include "robotperf/harness/dataset.hpp"

#include <stdexcept>

#include "robotperf/datasets/hash.hpp"
#include "robotperf/datasets/synthetic_camera.hpp"
#include "robotperf/msgs/sensor_msgs.hpp"

namespace robotperf::harness {
namespace {

// Hashes the CDR bytes of every message, so the hash identifies the data as it
// goes on the wire, whatever produced it.
std::string content_hash(const std::vector<DatasetStream>& streams) {
  datasets::Fnv1a64 hash;
  std::vector<uint8_t> buffer;
  for (const auto& s : streams) {
    hash.add_string(s.name).add_string(s.type->ros_type);
    for (const auto& m : s.messages) {
      buffer.resize(s.type->serialized_size(m.get()));
      s.type->serialize(m.get(), buffer);
      hash.add_bytes(buffer);
    }
  }
  return hash.hex_digest();
}

Dataset perception_image() {
  const datasets::SyntheticCameraConfig config;
  auto frames = datasets::generate_camera_sequence(config);
  Dataset d;
  d.name = "perception/image";
  d.description = builtin_datasets()[0].description;
  d.frames = frames.size();
  d.rate_hz = config.rate_hz;
  DatasetStream images{"image", "/camera/image_raw", &msgs::type_support<msgs::Image>(), {}};
  DatasetStream infos{
      "camera_info", "/camera/camera_info", &msgs::type_support<msgs::CameraInfo>(), {}};
  for (auto& f : frames) {
    images.messages.push_back(std::make_shared<const msgs::Image>(std::move(f.image)));
    infos.messages.push_back(std::make_shared<const msgs::CameraInfo>(std::move(f.info)));
  }
  d.streams.push_back(std::move(images));
  d.streams.push_back(std::move(infos));
  d.hash = content_hash(d.streams);
  return d;
}

}  // namespace

const DatasetStream& Dataset::stream(const std::string& stream_name) const {
  std::string names;
  for (const auto& s : streams) {
    if (s.name == stream_name) return s;
    names += (names.empty() ? "" : ", ") + s.name;
  }
  throw std::invalid_argument("dataset " + name + " has no stream '" + stream_name + "' (it has " +
                              names + ")");
}

const std::vector<DatasetInfo>& builtin_datasets() {
  static const std::vector<DatasetInfo> infos{
      {"perception/image",
       "synthetic 640x480 rgb8 camera, 30 Hz, 68 frames, plumb_bob k1=-0.25 k2=0.12 "
       "p1=-0.00028 p2=-5e-5, hfov 1.047 rad; checkerboard with a moving box"},
  };
  return infos;
}

Dataset load_dataset(const std::string& name) {
  if (name == "perception/image") return perception_image();
  std::string names;
  for (const auto& d : builtin_datasets()) names += (names.empty() ? "" : ", ") + d.name;
  throw std::invalid_argument("unknown dataset '" + name + "' (built-in: " + names + ")");
}

}  // namespace robotperf::harness
