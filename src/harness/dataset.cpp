#include "robotperf/harness/dataset.hpp"

#include <charconv>
#include <map>
#include <mutex>
#include <stdexcept>
#include <utility>

#include "robotperf/datasets/control_commands.hpp"
#include "robotperf/datasets/hash.hpp"
#include "robotperf/datasets/manipulation_requests.hpp"
#include "robotperf/datasets/synthetic_camera.hpp"
#include "robotperf/datasets/synthetic_depth.hpp"
#include "robotperf/datasets/synthetic_stereo.hpp"
#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/msgs/stereo_msgs.hpp"

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

template <class T>
DatasetStream make_stream(std::string name, std::string topic) {
  return DatasetStream{std::move(name), std::move(topic), &msgs::type_support<T>(), {}};
}

template <class T>
void append(DatasetStream& stream, T&& message) {
  stream.messages.push_back(std::make_shared<const std::decay_t<T>>(std::forward<T>(message)));
}

const std::string& description_of(const std::string& name) {
  for (const auto& d : builtin_datasets()) {
    if (d.name == name) return d.description;
  }
  throw std::logic_error("dataset " + name + " is not listed");
}

Dataset perception_stereo() {
  const datasets::SyntheticStereoConfig config;
  auto frames = datasets::generate_stereo_sequence(config);
  Dataset d;
  d.name = "perception/stereo";
  d.description = description_of(d.name);
  d.frames = frames.size();
  d.rate_hz = config.rate_hz;
  // The pair is rectified: its topics are those a3 takes, so that the bag `dataset generate`
  // writes plays into a3 without remapping.
  auto left = make_stream<msgs::Image>("left_image", "/left/image_rect");
  auto left_info = make_stream<msgs::CameraInfo>("left_camera_info", "/left/camera_info");
  auto right = make_stream<msgs::Image>("right_image", "/right/image_rect");
  auto right_info = make_stream<msgs::CameraInfo>("right_camera_info", "/right/camera_info");
  auto truth = make_stream<msgs::DisparityImage>("disparity_truth", "/ground_truth/disparity");
  for (auto& f : frames) {
    append(left, std::move(f.left));
    append(left_info, std::move(f.left_info));
    append(right, std::move(f.right));
    append(right_info, std::move(f.right_info));
    append(truth, std::move(f.truth));
  }
  for (auto* s : {&left, &left_info, &right, &right_info, &truth})
    d.streams.push_back(std::move(*s));
  d.hash = content_hash(d.streams);
  return d;
}

Dataset perception_depth() {
  const datasets::SyntheticDepthConfig config;
  auto frames = datasets::generate_depth_sequence(config);
  Dataset d;
  d.name = "perception/depth";
  d.description = description_of(d.name);
  d.frames = frames.size();
  d.rate_hz = config.rate_hz;
  // Depth registered to the colour camera, on the topics a4 takes (depth_image_proc's names).
  auto depth = make_stream<msgs::Image>("depth", "/camera/depth_registered/image_rect");
  auto depth_mm = make_stream<msgs::Image>("depth_mm", "/camera/depth_registered/image_rect_mm");
  auto image = make_stream<msgs::Image>("image", "/camera/rgb/image_rect_color");
  auto info = make_stream<msgs::CameraInfo>("camera_info", "/camera/rgb/camera_info");
  auto truth = make_stream<msgs::Image>("depth_truth", "/ground_truth/depth");
  for (auto& f : frames) {
    append(depth, std::move(f.depth));
    append(depth_mm, std::move(f.depth_mm));
    append(image, std::move(f.colour));
    append(info, std::move(f.info));
    append(truth, std::move(f.truth_depth));
  }
  for (auto* s : {&depth, &depth_mm, &image, &info, &truth}) d.streams.push_back(std::move(*s));
  d.hash = content_hash(d.streams);
  return d;
}

Dataset control_rrbot_goals() {
  Dataset d;
  d.name = "control/rrbot_goals";
  d.description = description_of(d.name);
  d.rate_hz = 1.0 / 6.0;
  auto goals =
      make_stream<msgs::JointTrajectory>("goals", "/joint_trajectory_controller/joint_trajectory");
  for (auto& g : datasets::rrbot_goals()) append(goals, std::move(g));
  d.frames = goals.messages.size();
  d.streams.push_back(std::move(goals));
  d.hash = content_hash(d.streams);
  return d;
}

Dataset control_diffbot_cmd_vel() {
  Dataset d;
  d.name = "control/diffbot_cmd_vel";
  d.description = description_of(d.name);
  d.rate_hz = 5.0;
  auto cmd = make_stream<msgs::TwistStamped>("cmd_vel", "/diff_drive_controller/cmd_vel");
  for (auto& c : datasets::diffbot_commands(d.rate_hz, 100)) append(cmd, std::move(c));
  d.frames = cmd.messages.size();
  d.streams.push_back(std::move(cmd));
  d.hash = content_hash(d.streams);
  return d;
}

Dataset control_rrbot_commands() {
  Dataset d;
  d.name = "control/rrbot_commands";
  d.description = description_of(d.name);
  d.rate_hz = 50.0;
  using datasets::CommandInterface;
  for (auto [name, kind] : {std::pair{"position", CommandInterface::kPosition},
                            std::pair{"velocity", CommandInterface::kVelocity},
                            std::pair{"acceleration", CommandInterface::kAcceleration}}) {
    auto s = make_stream<msgs::Float64MultiArray>(
        name, std::string("/forward_") + name + "_controller/commands");
    for (auto& c : datasets::rrbot_commands(kind, d.rate_hz, 100)) append(s, std::move(c));
    d.frames = s.messages.size();
    d.streams.push_back(std::move(s));
  }
  d.hash = content_hash(d.streams);
  return d;
}

template <class T>
T workload_number(const std::map<std::string, std::string>& workload, const std::string& key,
                  T fallback) {
  auto it = workload.find(key);
  if (it == workload.end()) return fallback;
  T value{};
  const std::string& text = it->second;
  auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || ptr != text.data() + text.size())
    throw std::invalid_argument("workload " + key + ": '" + text + "' is not a valid number");
  return value;
}

Dataset manipulation(const std::string& name, const std::map<std::string, std::string>& workload) {
  datasets::ManipulationWorkload w;
  for (const auto& [key, value] : workload) {
    if (key != "seed" && key != "requests" && key != "near_fraction")
      throw std::invalid_argument("dataset " + name + ": unknown workload parameter '" + key +
                                  "' (known: seed, requests, near_fraction)");
  }
  w.seed = workload_number<uint64_t>(workload, "seed", w.seed);
  w.requests = workload_number<std::size_t>(workload, "requests", w.requests);
  w.near_fraction = workload_number<double>(workload, "near_fraction", w.near_fraction);
  Dataset d;
  d.name = name;
  d.description = description_of(name);
  d.rate_hz = 100;
  d.parameters = {{"seed", std::to_string(w.seed)}, {"requests", std::to_string(w.requests)}};
  if (name == "manipulation/kinematics") {
    auto r = datasets::generate_kinematics_requests(w);
    auto states = make_stream<msgs::JointState>("joint_states", "/fk/joint_states");
    auto poses = make_stream<msgs::PoseStamped>("poses", "/ik/target_pose");
    for (auto& s : r.states) append(states, std::move(s));
    for (auto& p : r.poses) append(poses, std::move(p));
    d.streams.push_back(std::move(states));
    d.streams.push_back(std::move(poses));
  } else if (name == "manipulation/collision") {
    d.parameters["near_fraction"] = workload.contains("near_fraction")
                                        ? workload.at("near_fraction")
                                        : std::to_string(w.near_fraction);
    auto r = datasets::generate_collision_requests(w);
    auto states = make_stream<msgs::JointState>("joint_states", "/collision/joint_states");
    auto truth = make_stream<msgs::CollisionResult>("truth", "/ground_truth/collision");
    for (auto& s : r.states) append(states, std::move(s));
    for (auto& t : r.truth) append(truth, std::move(t));
    d.streams.push_back(std::move(states));
    d.streams.push_back(std::move(truth));
  } else {
    auto queries = make_stream<msgs::JointTrajectory>("queries", "/plan/query");
    for (auto& q : datasets::generate_planning_queries(w)) append(queries, std::move(q));
    d.streams.push_back(std::move(queries));
  }
  d.frames = d.streams.front().messages.size();
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
      {"perception/stereo",
       "synthetic rectified 640x480 rgb8 stereo pair, 10 Hz, 10 frames, baseline 0.10 m, hfov "
       "1.089 rad; ray-cast textured room with moving boxes (depth 1.6-6 m); streams left_image, "
       "left_camera_info, right_image, right_camera_info and the per-pixel ground truth "
       "disparity_truth (DisparityImage, NaN where occluded)"},
      {"perception/depth",
       "synthetic registered 640x480 depth + rgb8 colour, 30 Hz, 20 frames, hfov 1.089 rad, range "
       "0.05-8 m; ray-cast room with moving boxes and a doorway beyond range; streams depth "
       "(32FC1 m, NaN = none), depth_mm (16UC1 mm, 0 = none), image, camera_info and the ground "
       "truth depth_truth (64FC1 true depth)"},
      {"control/rrbot_goals",
       "the RRBot demo's joint trajectory goals, one point each (zero velocity and acceleration: "
       "quintic), [0.785, 0.785] -> [0, 0] -> [-0.785, -0.785] -> [0, 0], 4 s to reach each, one "
       "goal every 6 s; stream goals (trajectory_msgs/JointTrajectory)"},
      {"control/diffbot_cmd_vel",
       "DiffBot velocity commands, 5 Hz, 100 frames (20 s): linear.x = 0.25 + 0.2 sin(2 pi t / "
       "10 s) m/s with a +0.5 m/s step in the first second of every 10 s, angular.z = 0.6 sin(2 "
       "pi t / 5 s) rad/s; stream cmd_vel (geometry_msgs/TwistStamped)"},
      {"control/rrbot_commands",
       "2-joint forward commands, 50 Hz, 100 frames (2 s period): streams position (0.5 sin(pi "
       "t), -0.5 sin(pi t)) rad, velocity (0.5 cos(pi t), ...) rad/s, acceleration (0.5 sin(pi "
       "t), ...) rad/s^2 (std_msgs/Float64MultiArray, the message ID in layout.dim[0].label)"},
      {"manipulation/kinematics",
       "xArm6 joint states uniform within the joint limits and their flange poses (URDF transform "
       "chain, independent of KDL); streams joint_states (JointState) and poses (PoseStamped): FK "
       "requests and truth, IK targets that have a solution; workload seed, requests (200)"},
      {"manipulation/collision",
       "xArm6 joint states near (flange within 0.15 m) and far from a 0.2 x 0.2 x 0.4 m box at "
       "(0.45, 0, 0.2), each with a certain sampled ground-truth answer; streams joint_states and "
       "truth (robotperf_msgs/CollisionResult); workload seed, requests (200), near_fraction "
       "(0.5)"},
      {"manipulation/planning",
       "xArm6 planning queries around the box: start and goal (a JointTrajectory of two points) "
       "collision-free with the flange low on either side, the straight joint-space line between "
       "them blocked; stream queries; workload seed, requests (200)"},
  };
  return infos;
}

Dataset load_dataset(const std::string& name, const std::map<std::string, std::string>& workload) {
  // Generated datasets are immutable and take seconds to render: a process that runs a benchmark
  // again (tests, sweeps) reuses them; copies share the messages.
  static std::mutex mutex;
  static std::map<std::string, Dataset> cache;
  std::lock_guard lock(mutex);
  std::string key = name;
  for (const auto& [k, v] : workload) key += "\n" + k + "=" + v;
  if (auto it = cache.find(key); it != cache.end()) return it->second;
  const bool generated = name.starts_with("manipulation/");
  if (!workload.empty() && !generated)
    throw std::invalid_argument("dataset " + name + " takes no workload parameters");
  Dataset d;
  if (generated && (name == "manipulation/kinematics" || name == "manipulation/collision" ||
                    name == "manipulation/planning")) {
    d = manipulation(name, workload);
  } else if (name == "perception/image") {
    d = perception_image();
  } else if (name == "perception/stereo") {
    d = perception_stereo();
  } else if (name == "perception/depth") {
    d = perception_depth();
  } else if (name == "control/rrbot_goals") {
    d = control_rrbot_goals();
  } else if (name == "control/diffbot_cmd_vel") {
    d = control_diffbot_cmd_vel();
  } else if (name == "control/rrbot_commands") {
    d = control_rrbot_commands();
  } else {
    std::string names;
    for (const auto& d : builtin_datasets()) names += (names.empty() ? "" : ", ") + d.name;
    throw std::invalid_argument("unknown dataset '" + name + "' (built-in: " + names + ")");
  }
  return cache.emplace(key, std::move(d)).first->second;
}

}  // namespace robotperf::harness
