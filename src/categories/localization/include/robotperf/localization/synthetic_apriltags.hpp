#pragma once

// A deterministic camera sequence of AprilTags (tag36h11) at known poses, standing in for
// RobotPerf's r2b recordings of the b3 benchmark (not available): every tag is drawn from
// libapriltag's own family bitmaps, in perspective through an ideal pinhole camera, some of them
// small, oblique or partly hidden behind occluders, among tag-like distractor squares, then
// blurred and given sensor noise. The true corners and poses of every tag are known exactly.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "robotperf/msgs/apriltag_msgs.hpp"
#include "robotperf/msgs/geometry_msgs.hpp"
#include "robotperf/msgs/sensor_msgs.hpp"

namespace robotperf::localization {

struct SyntheticAprilTagConfig {
  uint32_t width = 1280;
  uint32_t height = 720;
  uint32_t frames = 24;
  double rate_hz = 30.0;
  double hfov_rad = 1.2;
  double tag_size_m = 0.22;  // edge of the black border square, as apriltag_ros's `size`
  // Frame k holds up to tags_per_frame[k % size] tags (fewer when they no longer fit apart).
  std::vector<uint32_t> tags_per_frame{8, 16, 32, 64};
  double min_distance_m = 0.7;
  double max_distance_m = 4.5;
  double max_tilt_rad = 1.0;        // of the tag's normal away from the camera
  double occluded_fraction = 0.12;  // share of tags partly hidden
  double noise_sigma = 2.0;         // grey levels
  uint64_t seed = 7;
  std::string frame_id = "camera_optical_frame";
};

struct AprilTagFrame {
  msgs::Image image;  // rgb8
  msgs::CameraInfo info;
  // The truth, one entry per tag in the image (all of its white border inside the image): id,
  // family "36h11", hamming 0, corners and centre as libapriltag reports them (pixel centres at
  // integer coordinates, as ROS's image_geometry), homography from the tag's (-1..1) square,
  // and `goodness` = the fraction of the tag's area not hidden by an occluder (1 = unoccluded).
  msgs::AprilTagDetectionArray tags;
  // Each tag's pose in the camera's optical frame, in the order of `tags`: origin at the tag's
  // centre, x to the right and y up as the tag is printed, z out of its face.
  msgs::PoseArray poses;
};

// Frames 0 .. frames-1, frame k stamped k / rate_hz s. Same bytes on every machine.
// Throws std::invalid_argument for a zero size, rate_hz <= 0, tag size <= 0, hfov outside
// (0, pi) or a distance range that is empty or not positive.
std::vector<AprilTagFrame> generate_apriltag_sequence(const SyntheticAprilTagConfig& config = {});

// One tag placed by hand: its pose in the camera's optical frame (as AprilTagFrame::poses).
struct TagPlacement {
  int id = 0;
  msgs::Pose pose;
};

// One frame `k` of the given tags, on the sequence's background, blurred and noisy as its frames
// are, without distractors or occluders. Throws std::invalid_argument as
// generate_apriltag_sequence does, and for an id the family lacks or a tag that is not wholly in
// view or overlaps another.
AprilTagFrame render_apriltag_frame(const SyntheticAprilTagConfig& config,
                                    const std::vector<TagPlacement>& tags, uint32_t k = 0);

}  // namespace robotperf::localization
