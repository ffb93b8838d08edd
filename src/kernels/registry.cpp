#include <charconv>
#include <stdexcept>

#include "builtin_kernels.hpp"

namespace robotperf::kernels {
namespace {

struct Entry {
  KernelInfo info;
  KernelFactory factory;
};

const std::vector<Entry>& entries() {
  static const std::vector<Entry> table{
      {{"image_proc/rectify",
        "undistort and rectify an image with its CameraInfo (cached map, cv::remap), as image_proc",
        {"cpu"},
        {"image", "camera_info"},
        {"image_rect"}},
       make_rectify_node},
      {{"image_proc/resize",
        "resize an image and scale its CameraInfo (K, P, ROI), as image_proc",
        {"cpu"},
        {"image", "camera_info"},
        {"resize", "resize_info"}},
       make_resize_node},
      {{"stereo_image_proc/disparity",
        "disparity of a rectified stereo pair (StereoBM, or StereoSGBM), as stereo_image_proc",
        {"cpu"},
        {"left_image", "left_camera_info", "right_image", "right_camera_info"},
        {"disparity"}},
       make_disparity_node},
      {{"depth_image_proc/point_cloud_xyzrgb",
        "organised xyz + rgb point cloud from registered depth and colour, as depth_image_proc",
        {"cpu"},
        {"depth", "image", "camera_info"},
        {"points"}},
       make_point_cloud_xyzrgb_node},
      {{"control/joint_trajectory_controller",
        "controller manager loop with a joint trajectory controller (splines, tolerances) on "
        "simulated hardware, as ros2_control + ros2_controllers",
        {"cpu"},
        {"joint_trajectory"},
        {"controller_state"}},
       make_joint_trajectory_controller_node},
      {{"control/diff_drive_controller",
        "controller manager loop with a differential drive controller (limiter, timeout, RK2 "
        "odometry) on a simulated DiffBot, as ros2_control + ros2_controllers",
        {"cpu"},
        {"cmd_vel"},
        {"odom", "tf", "ground_truth"}},
       make_diff_drive_controller_node},
      {{"control/forward_command_controller",
        "controller manager loop with a forward command controller (position, velocity or "
        "acceleration) and a joint state broadcaster on simulated hardware",
        {"cpu"},
        {"commands"},
        {"joint_states"}},
       make_forward_command_controller_node},
      {{"manipulation/forward_kinematics",
        "xArm6 flange pose of a joint state (KDL ChainFkSolverPos_recursive)",
        {"cpu"},
        {"joint_states"},
        {"pose"}},
       make_forward_kinematics_node},
      {{"manipulation/ik_kdl",
        "xArm6 joint state for a target pose: Newton-Raphson with joint limits on KDL, random "
        "restarts within the timeout (MoveIt's KDL plugin)",
        {"cpu"},
        {"pose"},
        {"joint_states"}},
       make_ik_kdl_node},
      {{"manipulation/ik_lma",
        "xArm6 joint state for a target pose: KDL ChainIkSolverPos_LMA, random restarts within "
        "the timeout (MoveIt's LMA plugin)",
        {"cpu"},
        {"pose"},
        {"joint_states"}},
       make_ik_lma_node},
      {{"manipulation/collision_fcl",
        "boolean collision query of an xArm6 joint state vs the box, then self-collision (FCL)",
        {"cpu"},
        {"joint_states"},
        {"collision"}},
       make_collision_fcl_node},
      {{"manipulation/collision_bullet",
        "boolean collision query of an xArm6 joint state vs the box, then self-collision (Bullet)",
        {"cpu"},
        {"joint_states"},
        {"collision"}},
       make_collision_bullet_node},
      {{"manipulation/plan",
        "plan a start -> goal query around the box (OMPL RRTConnect, FCL validity), simplify, "
        "time-parameterise within the velocity and acceleration limits",
        {"cpu"},
        {"query"},
        {"trajectory"}},
       make_plan_node},
      {{"manipulation/execute",
        "execute a trajectory on a simulated position-controlled xArm6, publishing its joint "
        "states, then the result",
        {"cpu"},
        {"trajectory"},
        {"joint_states", "result"}},
       make_execute_node},
      {{"util/relay",
        "republish each message unchanged; delay_ms, drop_every and fail_after for harness checks",
        {"cpu"},
        {"input"},
        {"output"}},
       make_relay_node},
  };
  return table;
}

template <class T>
T parse_number(const std::string& name, const std::string& text) {
  T value{};
  const char* end = text.data() + text.size();
  auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (ec != std::errc() || ptr != end) {
    throw std::invalid_argument("parameter '" + name + "': '" + text + "' is not a valid number");
  }
  return value;
}

}  // namespace

const std::string* Parameters::find(const std::string& name) const {
  auto it = values_.find(name);
  if (it == values_.end()) return nullptr;
  read_.insert(name);
  return &it->second;
}

double Parameters::get_double(const std::string& name, double fallback) const {
  const std::string* v = find(name);
  return v ? parse_number<double>(name, *v) : fallback;
}

int64_t Parameters::get_int(const std::string& name, int64_t fallback) const {
  const std::string* v = find(name);
  return v ? parse_number<int64_t>(name, *v) : fallback;
}

bool Parameters::get_bool(const std::string& name, bool fallback) const {
  const std::string* v = find(name);
  if (!v) return fallback;
  if (*v == "true" || *v == "True" || *v == "1") return true;
  if (*v == "false" || *v == "False" || *v == "0") return false;
  throw std::invalid_argument("parameter '" + name + "': '" + *v + "' is not true or false");
}

std::string Parameters::get_string(const std::string& name, const std::string& fallback) const {
  const std::string* v = find(name);
  return v ? *v : fallback;
}

std::vector<std::string> Parameters::unused() const {
  std::vector<std::string> out;
  for (const auto& [name, value] : values_) {
    if (!read_.contains(name)) out.push_back(name);
  }
  return out;
}

std::string KernelConfig::topic(const std::string& port) const {
  auto it = topics.find(port);
  if (it == topics.end()) {
    throw std::invalid_argument("node '" + node_name + "': no topic wired to port '" + port + "'");
  }
  return it->second;
}

const std::vector<KernelInfo>& kernel_infos() {
  static const std::vector<KernelInfo> infos = [] {
    std::vector<KernelInfo> out;
    for (const auto& e : entries()) out.push_back(e.info);
    return out;
  }();
  return infos;
}

const KernelInfo* find_kernel(const std::string& name) {
  for (const auto& info : kernel_infos()) {
    if (info.name == name) return &info;
  }
  return nullptr;
}

std::shared_ptr<graph::Node> make_kernel_node(const std::string& kernel, graph::Context& context,
                                              const KernelConfig& config) {
  for (const auto& e : entries()) {
    if (e.info.name != kernel) continue;
    bool backend_ok = false;
    for (const auto& b : e.info.backends) backend_ok |= b == config.backend;
    if (!backend_ok) {
      throw std::invalid_argument("kernel '" + kernel + "' has no backend '" + config.backend +
                                  "'");
    }
    auto node = e.factory(context, config);
    if (auto unused = config.parameters.unused(); !unused.empty()) {
      std::string names;
      for (const auto& n : unused) names += (names.empty() ? "" : ", ") + n;
      throw std::invalid_argument("node '" + config.node_name + "': unknown parameter(s) " + names +
                                  " for kernel " + kernel);
    }
    return node;
  }
  std::string known;
  for (const auto& e : entries()) known += (known.empty() ? "" : ", ") + e.info.name;
  throw std::invalid_argument("unknown kernel '" + kernel + "' (known: " + known + ")");
}

}  // namespace robotperf::kernels
