// The localization datasets, rendered deterministically with their ground truth.
#include "category.hpp"
#include "quaternion.hpp"
#include "robotperf/localization/synthetic_apriltags.hpp"
#include "robotperf/localization/synthetic_odometry.hpp"
#include "robotperf/localization/synthetic_scans.hpp"
#include "robotperf/msgs/nav_msgs.hpp"
#include "robotperf/perception/camera_model.hpp"
#include "robotperf/perception/image_proc.hpp"
#include "robotperf/plugin/stereo_streams.hpp"

namespace robotperf::localization {
namespace {

using plugin::append;
using plugin::DatasetStream;
using plugin::make_stream;

// On apriltag_ros's topics (it subscribes image_rect and camera_info).
std::vector<DatasetStream> apriltag_streams(const plugin::Parameters&) {
  auto images = make_stream<msgs::Image>("image", "/camera/image_rect");
  auto infos = make_stream<msgs::CameraInfo>("camera_info", "/camera/camera_info");
  auto tags = make_stream<msgs::AprilTagDetectionArray>("tags", "/ground_truth/tags");
  auto poses = make_stream<msgs::PoseArray>("tag_poses", "/ground_truth/tag_poses");
  for (auto& f : generate_apriltag_sequence()) {
    append(images, std::move(f.image));
    append(infos, std::move(f.info));
    append(tags, std::move(f.tags));
    append(poses, std::move(f.poses));
  }
  return {std::move(images), std::move(infos), std::move(tags), std::move(poses)};
}

// The map goes with every scan (one message shared by all frames): a node keeps the latest, as it
// would keep a latched map.
std::vector<DatasetStream> map_scan_streams(const plugin::Parameters&) {
  const SyntheticScanDataset data = generate_scan_dataset();
  msgs::OccupancyGrid grid;
  grid.header.frame_id = "map";
  grid.info.resolution = static_cast<float>(data.map.resolution);
  grid.info.width = data.map.width;
  grid.info.height = data.map.height;
  grid.info.origin.position = {data.map.origin_x, data.map.origin_y, 0.0};
  grid.data = data.map.cells;
  const auto map = std::make_shared<const msgs::OccupancyGrid>(std::move(grid));

  auto maps = make_stream<msgs::OccupancyGrid>("map", "/map");
  auto scans = make_stream<msgs::LaserScan>("scan", "/scan");
  auto truth = make_stream<msgs::PoseStamped>("pose_truth", "/ground_truth/pose");
  for (std::size_t k = 0; k < data.scans.size(); ++k) {
    const SyntheticScan& s = data.scans[k];
    msgs::Header header;
    header.stamp = msgs::Time::from_ns(static_cast<int64_t>(k) * 100'000'000);
    maps.messages.push_back(map);
    msgs::LaserScan scan;
    scan.header = header;
    scan.header.frame_id = "laser";
    scan.angle_min = s.scan.angle_min;
    scan.angle_increment = s.scan.angle_increment;
    scan.angle_max = static_cast<float>(s.scan.angle_min +
                                        s.scan.angle_increment * (s.scan.ranges.size() - 1.0));
    scan.range_min = s.scan.range_min;
    scan.range_max = s.scan.range_max;
    scan.scan_time = 0.1f;
    scan.ranges = s.scan.ranges;
    append(scans, std::move(scan));
    msgs::PoseStamped pose;
    pose.header = header;
    pose.header.frame_id = "map";
    pose.pose.position = {s.x, s.y, 0.0};
    pose.pose.orientation = quaternion_from_yaw(s.yaw);
    append(truth, std::move(pose));
  }
  return {std::move(maps), std::move(scans), std::move(truth)};
}

msgs::Image mono_image(const cv::Mat& pixels, const msgs::Header& header) {
  msgs::Image image;
  pixels.copyTo(perception::prepare_image(image, header, "mono8", pixels.cols, pixels.rows));
  return image;
}

// A rectified stereo pair on stereo_image_proc's topics, and the left camera's true pose in the
// first frame's left camera (the odometry frame a visual odometry starts from).
std::vector<DatasetStream> odometry_streams(const plugin::Parameters&) {
  const SyntheticOdometryConfig config;
  const OdometrySequence sequence = generate_odometry_sequence(config);
  plugin::StereoPairStreams pair;
  auto truth = make_stream<msgs::PoseStamped>("pose_truth", "/ground_truth/pose");
  msgs::CameraInfo left_camera = perception::make_pinhole_camera_info(
      config.width, config.height, config.hfov_rad, std::vector<double>(5, 0.0),
      "left_camera_optical_frame");
  msgs::CameraInfo right_camera = left_camera;
  right_camera.header.frame_id = "right_camera_optical_frame";
  right_camera.p[3] = -right_camera.p[0] * config.baseline_m;
  for (std::size_t k = 0; k < sequence.frames.size(); ++k) {
    const OdometryFrame& f = sequence.frames[k];
    msgs::Header header;
    header.stamp = msgs::Time::from_ns(std::llround(f.stamp_s * 1e9));
    header.frame_id = left_camera.header.frame_id;
    msgs::Image left = mono_image(f.left, header);
    left_camera.header.stamp = header.stamp;
    header.frame_id = right_camera.header.frame_id;
    right_camera.header.stamp = header.stamp;
    pair.append(std::move(left), left_camera, mono_image(f.right, header), right_camera);
    msgs::PoseStamped pose;
    pose.header.stamp = header.stamp;
    pose.header.frame_id = "odom";
    const Eigen::Vector3d t = f.left_in_first.translation();
    pose.pose.position = {t.x(), t.y(), t.z()};
    pose.pose.orientation = quaternion_from_matrix(f.left_in_first.rotation());
    append(truth, std::move(pose));
  }
  std::vector<DatasetStream> more;
  more.push_back(std::move(truth));
  return pair.take(std::move(more));
}

}  // namespace

void register_datasets(plugin::Registrar& registrar) {
  const SyntheticAprilTagConfig tags;
  registrar.add_dataset(
      {.name = "localization/apriltags",
       .description = "synthetic 1280x720 rgb8 camera, 30 Hz, 24 frames of 8-64 tag36h11 tags "
                      "(0.22 m) at 0.7-4.5 m, tilted up to 57 deg, 12 % partly occluded, among "
                      "tag-like distractors; blur and noise",
       .rate_hz = tags.rate_hz,
       .frames = tags.frames,
       .streams = {{"image", "/camera/image_rect", "sensor_msgs/msg/Image", false,
                    "the rectified camera image"},
                   {"camera_info", "/camera/camera_info", "sensor_msgs/msg/CameraInfo", false,
                    "its calibration (ideal pinhole, hfov 1.2 rad)"},
                   {"tags", "/ground_truth/tags", "apriltag_msgs/msg/AprilTagDetectionArray", true,
                    "every tag in view: id, true corners and centre, goodness = fraction not "
                    "occluded"},
                   {"tag_poses", "/ground_truth/tag_poses", "geometry_msgs/msg/PoseArray", true,
                    "their true poses in the camera frame, in the same order"}}},
      apriltag_streams);
  const SyntheticScansConfig scans;
  registrar.add_dataset(
      {.name = "localization/map_scans",
       .description = "synthetic 20 m x 20 m office floor as a 0.05 m occupancy grid and 100 "
                      "360-degree lidar scans (720 beams, 20 m, noise 0.02 m, 2 % dropouts, "
                      "unmapped people and boxes) from known poses, 10 Hz",
       .rate_hz = 10.0,
       .frames = scans.scans,
       .streams = {{"map", "/map", "nav_msgs/msg/OccupancyGrid", false,
                    "the floor's occupancy grid, the same with every scan"},
                   {"scan", "/scan", "sensor_msgs/msg/LaserScan", false,
                    "one sweep from the robot's pose"},
                   {"pose_truth", "/ground_truth/pose", "geometry_msgs/msg/PoseStamped", true,
                    "the pose the scan was taken from, map frame"}}},
      map_scan_streams);
  const SyntheticOdometryConfig odometry;
  registrar.add_dataset(
      {.name = "localization/stereo_odometry",
       .description = "synthetic rectified 640x480 mono8 stereo pair, 20 Hz, 300 frames (one "
                      "15 s, 16.5 m lap of a figure-of-eight), baseline 0.12 m, hfov 1.1 rad; "
                      "ray-cast textured room with pillars and crates",
       .rate_hz = odometry.rate_hz,
       .frames = odometry.frames,
       .streams = plugin::stereo_pair_stream_infos(
           {{"pose_truth", "/ground_truth/pose", "geometry_msgs/msg/PoseStamped", true,
             "the left camera's true pose in the first frame's left camera"}})},
      odometry_streams);
}

}  // namespace robotperf::localization
