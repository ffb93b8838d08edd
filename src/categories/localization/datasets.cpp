// The localization datasets, rendered deterministically with their ground truth.
#include "category.hpp"
#include "robotperf/localization/synthetic_apriltags.hpp"

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
}

}  // namespace robotperf::localization
