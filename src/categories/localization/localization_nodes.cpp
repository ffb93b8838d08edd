// The localization kernels as graph nodes.
#include <cmath>
#include <stdexcept>

#include "category.hpp"
#include "quaternion.hpp"
#include "robotperf/localization/apriltag_detector.hpp"
#include "robotperf/localization/scan_matcher.hpp"
#include "robotperf/localization/stereo_odometry.hpp"
#include "robotperf/msgs/apriltag_msgs.hpp"
#include "robotperf/msgs/eigen_geometry.hpp"
#include "robotperf/msgs/geometry_msgs.hpp"
#include "robotperf/msgs/nav_msgs.hpp"
#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/perception/image_proc.hpp"
#include "robotperf/plugin/synced_inputs.hpp"

namespace robotperf::localization {
namespace {

using plugin::KernelConfig;

// Inputs paired by exact stamps (as the ROS nodes' message_filters do); a set the kernel rejects
// is skipped and counted.
template <std::size_t N>
class SyncedNode : public graph::Node, public plugin::NodeCounters {
 public:
  std::map<std::string, uint64_t> counters() const override {
    std::map<std::string, uint64_t> out = inputs_.counters();
    out["rejected_sets"] = rejected_.count();
    return out;
  }

 protected:
  using Set = typename plugin::SyncedInputs<N>::Set;

  SyncedNode(graph::Context& context, const KernelConfig& config,
             std::array<std::string, N> port_names)
      : Node(context, config.node_name),
        inputs_(std::move(port_names), plugin::SyncOptions{},
                [this](const Set& set) { guarded(set); }) {}

  template <class T>
  void subscribe(const KernelConfig& config, std::size_t input) {
    inputs_.template subscribe<T>(*this, config, input);
  }

  virtual void process(const Set& set) = 0;

 private:
  void guarded(const Set& set) {
    try {
      process(set);
    } catch (const std::invalid_argument& e) {
      rejected_.note(name(), e.what());
    }
  }

  plugin::SyncedInputs<N> inputs_;
  plugin::SkippedInputs rejected_;
};

template <class T>
const T& input(const std::shared_ptr<const void>& m) {
  return *std::static_pointer_cast<const T>(m);
}

const AprilTagParams kTag;
const plugin::ParameterStruct<AprilTagParams> kAprilTagParameters{
    plugin::field(&AprilTagParams::family, "family", kTag.family,
                  "tag family: 16h5, 25h9 or 36h11"),
    plugin::field(&AprilTagParams::size, "size", kTag.size, "edge of the black border square, m"),
    plugin::field(&AprilTagParams::max_hamming, "max_hamming", kTag.max_hamming,
                  "bits a detection may have corrected (0..2)"),
    plugin::field(&AprilTagParams::decimate, "decimate", kTag.decimate,
                  "find quads on the image decimated by this factor"),
    plugin::field(&AprilTagParams::blur, "blur", kTag.blur,
                  "Gaussian sigma (px) before segmentation; < 0 sharpens"),
    plugin::field(&AprilTagParams::threads, "threads", kTag.threads, "libapriltag worker threads"),
    plugin::field(&AprilTagParams::refine_edges, "refine_edges", kTag.refine_edges,
                  "snap quad edges to the image gradients"),
    plugin::field(&AprilTagParams::sharpening, "sharpening", kTag.sharpening, "decode sharpening"),
    plugin::field(&AprilTagParams::rectify, "rectify", kTag.rectify,
                  "undistort and rectify the image with its CameraInfo first")};

AprilTagParams apriltag_params(const KernelConfig& c) {
  const AprilTagParams out = kAprilTagParameters.read(c.parameters);
  try {
    validate(out);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("node '" + c.node_name + "': " + e.what());
  }
  return out;
}

class AprilTagNode final : public SyncedNode<2> {
 public:
  enum Input { kImage, kInfo };

  AprilTagNode(graph::Context& context, const KernelConfig& config)
      : SyncedNode(context, config, {"image", "camera_info"}), detector_(apriltag_params(config)) {
    detections_out_ =
        create_publisher<msgs::AprilTagDetectionArray>(config.topic("detections"), config.qos);
    poses_out_ = create_publisher<msgs::PoseArray>(config.topic("poses"), config.qos);
    subscribe<msgs::Image>(config, kImage);
    subscribe<msgs::CameraInfo>(config, kInfo);
  }

 private:
  void process(const Set& set) override {
    const auto& image = input<msgs::Image>(set[kImage]);
    auto detections = std::make_shared<msgs::AprilTagDetectionArray>();
    auto poses = std::make_shared<msgs::PoseArray>();
    plugin::trace_kernel_init(*this, kKernel, image.header.stamp.to_ns(), image);
    detector_.detect(image, input<msgs::CameraInfo>(set[kInfo]), *detections, *poses);
    plugin::trace_kernel_fini(*this, kKernel, *detections);
    // Poses first: a subscriber pairing them with the detections finds them waiting.
    poses_out_->publish(std::shared_ptr<const msgs::PoseArray>(std::move(poses)));
    detections_out_->publish(
        std::shared_ptr<const msgs::AprilTagDetectionArray>(std::move(detections)));
  }

  static constexpr const char* kKernel = "apriltag/detect";
  AprilTagDetector detector_;
  std::shared_ptr<graph::Publisher<msgs::AprilTagDetectionArray>> detections_out_;
  std::shared_ptr<graph::Publisher<msgs::PoseArray>> poses_out_;
};

GridMap grid_map(const msgs::OccupancyGrid& grid) {
  const msgs::Quaternion& q = grid.info.origin.orientation;
  if (q.x != 0.0 || q.y != 0.0 || q.z != 0.0) {
    throw std::invalid_argument(
        "map_localization: the map's origin is rotated; only maps aligned "
        "with their frame are supported");
  }
  GridMap map;
  map.width = grid.info.width;
  map.height = grid.info.height;
  map.resolution = grid.info.resolution;
  map.origin_x = grid.info.origin.position.x;
  map.origin_y = grid.info.origin.position.y;
  map.cells = grid.data;
  return map;
}

const GlobalLocalizerOptions kMap;
const plugin::ParameterStruct<GlobalLocalizerOptions> kMapLocalizationParameters{
    plugin::field(&GlobalLocalizerOptions::max_range_m, "max_range", kMap.max_range_m,
                  "returns farther are unused, m"),
    plugin::field(&GlobalLocalizerOptions::min_score, "min_score", kMap.min_score,
                  "score (mean likelihood of the scan's hits) for a pose"),
    plugin::field(&GlobalLocalizerOptions::branch_and_bound_depth, "branch_and_bound_depth",
                  kMap.branch_and_bound_depth, "levels of the search tree (1..10)"),
    plugin::field(&GlobalLocalizerOptions::angular_step_rad, "angular_step", kMap.angular_step_rad,
                  "yaw lattice step, rad, 2 pi / 262144 .. pi; 0 = one cell at the farthest point"),
    plugin::field(&GlobalLocalizerOptions::max_points, "max_points", kMap.max_points,
                  "scan points scored, thinned along the contour"),
    plugin::field(&GlobalLocalizerOptions::likelihood_sigma_m, "likelihood_sigma",
                  kMap.likelihood_sigma_m, "likelihood field's width, m"),
    plugin::field(&GlobalLocalizerOptions::ambiguity_ratio, "ambiguity_ratio", kMap.ambiguity_ratio,
                  "poses within this fraction of the best make the covariance"),
    plugin::field(&GlobalLocalizerOptions::refinement_iterations, "refinement_iterations",
                  kMap.refinement_iterations, "Gauss-Newton iterations of the sub-cell refinement"),
    plugin::field(&GlobalLocalizerOptions::threads, "threads", kMap.threads,
                  "threads the search is split over")};

// Global localization of each scan in the latest map, as Isaac ROS's occupancy grid localizer:
// the map arrives on its own topic (latched in ROS; here it may come with every frame) and the
// search structures are rebuilt only when its content changes; each scan is localized from
// scratch.
class MapLocalizationNode final : public graph::Node, public plugin::NodeCounters {
 public:
  MapLocalizationNode(graph::Context& context, const KernelConfig& config)
      : Node(context, config.node_name), options_(options_from(config)) {
    output_ = create_publisher<msgs::PoseWithCovarianceStamped>(config.topic("pose"), config.qos);
    map_sub_ = create_subscription<msgs::OccupancyGrid>(
        config.topic("map"), config.qos,
        [this](std::shared_ptr<const msgs::OccupancyGrid> m) { take_map(*m); });
    scan_sub_ = create_subscription<msgs::LaserScan>(
        config.topic("scan"), config.qos,
        [this](std::shared_ptr<const msgs::LaserScan> m) { localize(*m); });
  }

  std::map<std::string, uint64_t> counters() const override {
    return {{"maps_built", maps_built_},
            {"scans_without_map", scans_without_map_},
            {"rejected_inputs", rejected_.count()},
            {"not_found", not_found_}};
  }

 private:
  static GlobalLocalizerOptions options_from(const KernelConfig& c) {
    const GlobalLocalizerOptions o = kMapLocalizationParameters.read(c.parameters);
    // Checked here, once, so that a bad value is one line when the graph is built.
    try {
      const GridMap probe{1, 1, 0.05, 0.0, 0.0, {0}};
      GlobalLocalizer check(probe, o);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("node '" + c.node_name + "': " + e.what());
    }
    return o;
  }

  void take_map(const msgs::OccupancyGrid& grid) {
    if (localizer_ && grid.info == map_info_ && grid.data == map_data_) return;
    try {
      localizer_ = std::make_unique<GlobalLocalizer>(grid_map(grid), options_);
      map_info_ = grid.info;
      map_data_ = grid.data;
      map_frame_ = grid.header.frame_id;
      ++maps_built_;
    } catch (const std::invalid_argument& e) {
      rejected_.note(name(), e.what());
    }
  }

  void localize(const msgs::LaserScan& scan) {
    if (!localizer_) {
      ++scans_without_map_;
      return;
    }
    try {
      plugin::trace_kernel_init(*this, kKernel, scan.header.stamp.to_ns(), scan);
      Scan in;
      in.angle_min = scan.angle_min;
      in.angle_increment = scan.angle_increment;
      in.range_min = scan.range_min;
      in.range_max = scan.range_max;
      in.ranges = scan.ranges;
      const LocalizationResult r = localizer_->localize(in);
      auto out = std::make_shared<msgs::PoseWithCovarianceStamped>();
      out->header.stamp = scan.header.stamp;
      out->header.frame_id = map_frame_;
      out->pose.pose.position = {r.x, r.y, 0.0};
      out->pose.pose.orientation = quaternion_from_yaw(r.yaw);
      // (x, y, yaw) into the 6x6 of (x, y, z, roll, pitch, yaw); z, roll and pitch are fixed.
      const std::size_t index[3] = {0, 1, 5};
      for (std::size_t i = 0; i < 3; ++i) {
        for (std::size_t j = 0; j < 3; ++j) {
          out->pose.covariance[6 * index[i] + index[j]] = r.covariance[3 * i + j];
        }
      }
      not_found_ += r.found ? 0 : 1;
      plugin::trace_kernel_fini(*this, kKernel, *out);
      output_->publish(std::shared_ptr<const msgs::PoseWithCovarianceStamped>(std::move(out)));
    } catch (const std::invalid_argument& e) {
      rejected_.note(name(), e.what());
    }
  }

  static constexpr const char* kKernel = "localization/map_localization";
  GlobalLocalizerOptions options_;
  std::unique_ptr<GlobalLocalizer> localizer_;
  msgs::MapMetaData map_info_;
  std::vector<int8_t> map_data_;
  std::string map_frame_;
  plugin::SkippedInputs rejected_;
  uint64_t maps_built_ = 0, scans_without_map_ = 0, not_found_ = 0;
  std::shared_ptr<graph::Publisher<msgs::PoseWithCovarianceStamped>> output_;
  std::shared_ptr<graph::GenericSubscription> map_sub_, scan_sub_;
};

const StereoOdometryOptions kOdometry;
const plugin::ParameterStruct<StereoOdometryOptions> kOdometryOptionParameters{
    plugin::field(&StereoOdometryOptions::max_features, "max_features", kOdometry.max_features,
                  "features kept per image after grid bucketing"),
    plugin::field(&StereoOdometryOptions::fast_threshold, "fast_threshold",
                  kOdometry.fast_threshold, "FAST threshold (1..255)"),
    plugin::field(&StereoOdometryOptions::max_disparity_px, "max_disparity",
                  kOdometry.max_disparity_px, "largest stereo disparity searched, px"),
    plugin::field(&StereoOdometryOptions::ratio, "ratio", kOdometry.ratio,
                  "descriptor ratio test (0..1]"),
    plugin::field(&StereoOdometryOptions::search_radius_px, "search_radius",
                  kOdometry.search_radius_px, "tracking window around the predicted position, px"),
    plugin::field(&StereoOdometryOptions::ransac_reprojection_px, "ransac_reprojection",
                  kOdometry.ransac_reprojection_px, "PnP RANSAC inlier threshold, px"),
    plugin::field(&StereoOdometryOptions::ransac_iterations, "ransac_iterations",
                  kOdometry.ransac_iterations, "PnP RANSAC iterations"),
    plugin::field(&StereoOdometryOptions::min_inliers, "min_inliers", kOdometry.min_inliers,
                  "fewer PnP inliers: tracking lost"),
    plugin::field(&StereoOdometryOptions::keyframe_inlier_fraction, "keyframe_inlier_fraction",
                  kOdometry.keyframe_inlier_fraction,
                  "new keyframe below this share of its points as inliers"),
    plugin::field(&StereoOdometryOptions::keyframe_min_inliers, "keyframe_min_inliers",
                  kOdometry.keyframe_min_inliers, "new keyframe below this many inliers")};

struct StereoOdometrySettings {
  StereoOdometryOptions options;
  std::string odom_frame;
};

const plugin::ParameterStruct<StereoOdometrySettings> kStereoOdometryParameters{
    plugin::nested(&StereoOdometrySettings::options, kOdometryOptionParameters),
    plugin::field(&StereoOdometrySettings::odom_frame, "odom_frame", "odom",
                  "the output's header frame")};

StereoOdometryOptions odometry_options(const KernelConfig& c) {
  const StereoOdometryOptions o = kStereoOdometryParameters.read(c.parameters).options;
  try {
    StereoOdometry check(500.0, 500.0, 320.0, 240.0, 0.1, o);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("node '" + c.node_name + "': " + e.what());
  }
  return o;
}

// The camera a rectified pair's CameraInfos describe, as image_geometry's StereoCameraModel
// reads them: the left P's intrinsics, the right P's principal point column (P[2]; a
// rectification may put it elsewhere than the left's) and the baseline from the right P
// (P[3] = -fx * baseline). The rows of a rectified pair are the same rows, seen with the same
// focal length: a pair whose fx, fy or cy differ is no rectified pair, and is refused.
StereoCalibration stereo_calibration(const msgs::CameraInfo& left, const msgs::CameraInfo& right) {
  if (left.p[0] == 0.0 || right.p[0] == 0.0)
    throw std::invalid_argument("stereo_odometry: camera is not calibrated (P[0] = 0)");
  constexpr double kTolerancePx = 1e-3;
  if (!(std::abs(left.p[0] - right.p[0]) <= kTolerancePx &&
        std::abs(left.p[5] - right.p[5]) <= kTolerancePx &&
        std::abs(left.p[6] - right.p[6]) <= kTolerancePx)) {
    throw std::invalid_argument(
        "stereo_odometry: the left and right P differ in fx, fy or cy (P[0], P[5], P[6]); "
        "the images must be a rectified pair");
  }
  const StereoCalibration c{.fx = left.p[0],
                            .fy = left.p[5],
                            .cx = left.p[2],
                            .cy = left.p[6],
                            .right_cx = right.p[2],
                            .baseline_m = -right.p[3] / right.p[0]};
  if (!(c.baseline_m > 0.0)) {
    throw std::invalid_argument(
        "stereo_odometry: the right CameraInfo gives no baseline "
        "(P[3] = -fx * baseline must be negative)");
  }
  return c;
}

// Stereo visual odometry, the SLAM front end (as Isaac ROS Visual SLAM's odometry output): the
// left camera's pose in the odometry frame, which is the first frame's left camera, and its
// velocity between the last two frames in the camera's frame at the later one (child_frame_id).
// The covariance is not estimated (all zero). A new calibration starts a new odometry frame.
class StereoOdometryNode final : public SyncedNode<4> {
 public:
  enum Input { kLeftImage, kLeftInfo, kRightImage, kRightInfo };

  StereoOdometryNode(graph::Context& context, const KernelConfig& config)
      : SyncedNode(context, config,
                   {"left_image", "left_camera_info", "right_image", "right_camera_info"}),
        options_(odometry_options(config)),
        odom_frame_(kStereoOdometryParameters.read(config.parameters).odom_frame) {
    output_ = create_publisher<msgs::Odometry>(config.topic("odom"), config.qos);
    subscribe<msgs::Image>(config, kLeftImage);
    subscribe<msgs::CameraInfo>(config, kLeftInfo);
    subscribe<msgs::Image>(config, kRightImage);
    subscribe<msgs::CameraInfo>(config, kRightInfo);
  }

  std::map<std::string, uint64_t> counters() const override {
    auto out = SyncedNode::counters();
    out["keyframes"] = keyframes_;
    out["tracking_lost"] = lost_;
    return out;
  }

 private:
  void process(const Set& set) override {
    const auto& left = input<msgs::Image>(set[kLeftImage]);
    const auto& right = input<msgs::Image>(set[kRightImage]);
    const StereoCalibration camera = stereo_calibration(input<msgs::CameraInfo>(set[kLeftInfo]),
                                                        input<msgs::CameraInfo>(set[kRightInfo]));
    plugin::trace_kernel_init(*this, kKernel, left.header.stamp.to_ns(), left, right);
    perception::to_mono8(left, "stereo_odometry: left image", left_mono_);
    perception::to_mono8(right, "stereo_odometry: right image", right_mono_);
    if (!odometry_ || camera != camera_) {
      odometry_ = std::make_unique<StereoOdometry>(camera, options_);
      camera_ = camera;
      have_previous_ = false;
    }
    const StereoOdometryResult r = odometry_->process(left_mono_, right_mono_);
    keyframes_ += r.new_keyframe ? 1 : 0;
    lost_ += r.tracking_lost ? 1 : 0;

    auto out = std::make_shared<msgs::Odometry>();
    out->header.stamp = left.header.stamp;
    out->header.frame_id = odom_frame_;
    out->child_frame_id = left.header.frame_id;
    out->pose.pose = msgs::pose_msg_of(r.pose);
    const int64_t stamp_ns = left.header.stamp.to_ns();
    if (have_previous_ && stamp_ns > previous_ns_) {
      const double dt = static_cast<double>(stamp_ns - previous_ns_) * 1e-9;
      // nav_msgs/Odometry's twist is in child_frame_id, the camera at this stamp: the step's
      // translation is in the previous camera's frame, and turns into this one's. Its rotation
      // axis is the same in both.
      const Eigen::Isometry3d step = previous_.inverse() * r.pose;
      const Eigen::AngleAxisd turn(step.rotation());
      const Eigen::Vector3d v = step.rotation().transpose() * step.translation() / dt;
      const Eigen::Vector3d w = turn.axis() * (turn.angle() / dt);
      out->twist.twist.linear = {v.x(), v.y(), v.z()};
      out->twist.twist.angular = {w.x(), w.y(), w.z()};
    }
    previous_ = r.pose;
    previous_ns_ = stamp_ns;
    have_previous_ = true;
    plugin::trace_kernel_fini(*this, kKernel, *out);
    output_->publish(std::shared_ptr<const msgs::Odometry>(std::move(out)));
  }

  static constexpr const char* kKernel = "localization/stereo_odometry";
  StereoOdometryOptions options_;
  std::string odom_frame_;
  std::unique_ptr<StereoOdometry> odometry_;
  StereoCalibration camera_{};
  cv::Mat left_mono_, right_mono_;
  Eigen::Isometry3d previous_ = Eigen::Isometry3d::Identity();
  int64_t previous_ns_ = 0;
  bool have_previous_ = false;
  uint64_t keyframes_ = 0, lost_ = 0;
  std::shared_ptr<graph::Publisher<msgs::Odometry>> output_;
};

}  // namespace

void register_kernels(plugin::Registrar& registrar) {
  registrar.add_kernel(
      {.name = "apriltag/detect",
       .description = "AprilTag detection (libapriltag) and each tag's pose from its corners and "
                      "size, as apriltag_ros",
       .inputs = {{"image", "sensor_msgs/msg/Image"},
                  {"camera_info", "sensor_msgs/msg/CameraInfo"}},
       .outputs = {{"detections", "apriltag_msgs/msg/AprilTagDetectionArray"},
                   {"poses", "geometry_msgs/msg/PoseArray"}},
       .parameters = kAprilTagParameters.declarations()},
      [](graph::Context& context, const KernelConfig& config) {
        return std::make_shared<AprilTagNode>(context, config);
      });
  registrar.add_kernel(
      {.name = "localization/map_localization",
       .description = "global 2D localization of a laser scan in an occupancy grid (correlative "
                      "search, multi-resolution branch and bound), as Isaac ROS's occupancy grid "
                      "localizer",
       .inputs = {{"map", "nav_msgs/msg/OccupancyGrid"}, {"scan", "sensor_msgs/msg/LaserScan"}},
       .outputs = {{"pose", "geometry_msgs/msg/PoseWithCovarianceStamped"}},
       .parameters = kMapLocalizationParameters.declarations()},
      [](graph::Context& context, const KernelConfig& config) {
        return std::make_shared<MapLocalizationNode>(context, config);
      });
  registrar.add_kernel(
      {.name = "localization/stereo_odometry",
       .description = "stereo visual odometry (FAST + ORB features, row matching, triangulation, "
                      "frame to keyframe PnP RANSAC and refinement) on OpenCV",
       .inputs = {{"left_image", "sensor_msgs/msg/Image"},
                  {"left_camera_info", "sensor_msgs/msg/CameraInfo"},
                  {"right_image", "sensor_msgs/msg/Image"},
                  {"right_camera_info", "sensor_msgs/msg/CameraInfo"}},
       .outputs = {{"odom", "nav_msgs/msg/Odometry"}},
       .parameters = kStereoOdometryParameters.declarations()},
      [](graph::Context& context, const KernelConfig& config) {
        return std::make_shared<StereoOdometryNode>(context, config);
      });
}

}  // namespace robotperf::localization
