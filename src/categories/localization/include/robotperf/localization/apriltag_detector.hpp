#pragma once

// AprilTag detection as apriltag_ros does it, on libapriltag, without the node plumbing: what
// the b3 graph node calls per image.

#include <memory>
#include <string>

#include "robotperf/msgs/apriltag_msgs.hpp"
#include "robotperf/msgs/geometry_msgs.hpp"
#include "robotperf/msgs/sensor_msgs.hpp"

namespace robotperf::localization {

// apriltag_ros's parameters, with its defaults.
struct AprilTagParams {
  std::string family = "36h11";  // 16h5, 25h9 or 36h11: the families with the black border outside
  double size = 0.22;            // m, the edge of the black border square
  int max_hamming = 0;           // bits a detection may have corrected (0..2)
  double decimate = 2.0;         // quads are found on an image decimated by this factor
  double blur = 0.0;             // Gaussian sigma (px) before segmentation; < 0 sharpens
  int threads = 1;               // libapriltag's worker threads
  bool refine_edges = true;      // snap the quad's edges to the image's gradients
  double sharpening = 0.25;      // decode sharpening
  // Undistort and rectify the image with its CameraInfo first (image_proc's rectify, its map
  // cached), for a camera whose images are not rectified yet.
  bool rectify = false;
};

// Throws std::invalid_argument naming the parameter that is out of range.
void validate(const AprilTagParams& params);

// Finds the tags of one family in rectified images and each tag's pose from its corners and
// size. Not thread-safe: one detector per stream.
class AprilTagDetector {
 public:
  explicit AprilTagDetector(const AprilTagParams& params);
  ~AprilTagDetector();
  AprilTagDetector(const AprilTagDetector&) = delete;
  AprilTagDetector& operator=(const AprilTagDetector&) = delete;

  // The tags in `image` (mono8, rgb8, bgr8, rgba8 or bgra8), rectified with projection P of
  // `info` (or rectified here first with `rectify`). Corners and centres are in ROS's pixel
  // convention (the first pixel's centre at (0, 0); libapriltag's own is half a pixel off), corners
  // in libapriltag's order. `poses` holds each tag's pose in the camera's optical frame in the
  // order of `detections`: origin at the tag's centre, x to the right and y up as the tag is
  // printed, z out of its face (OpenCV's IPPE for squares, the better of its two solutions). Both
  // get the image's header. Throws std::invalid_argument for another encoding, an image whose size
  // differs from the calibration's, or an uncalibrated camera (P[0] == 0).
  void detect(const msgs::Image& image, const msgs::CameraInfo& info,
              msgs::AprilTagDetectionArray& detections, msgs::PoseArray& poses);

  const AprilTagParams& params() const { return params_; }

 private:
  struct Library;
  AprilTagParams params_;
  std::unique_ptr<Library> library_;
};

}  // namespace robotperf::localization
