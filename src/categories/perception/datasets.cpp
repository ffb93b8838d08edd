// The perception datasets: a distorted camera, a rectified stereo pair and registered depth +
// colour, rendered deterministically with their ground truth.
#include "category.hpp"
#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/msgs/stereo_msgs.hpp"
#include "robotperf/perception/synthetic_camera.hpp"
#include "robotperf/perception/synthetic_depth.hpp"
#include "robotperf/perception/synthetic_stereo.hpp"
#include "robotperf/plugin/stereo_streams.hpp"

namespace robotperf::perception {
namespace {

using plugin::append;
using plugin::DatasetStream;
using plugin::make_stream;

std::vector<DatasetStream> camera_streams(const plugin::Parameters&) {
  auto images = make_stream<msgs::Image>("image", "/camera/image_raw");
  auto infos = make_stream<msgs::CameraInfo>("camera_info", "/camera/camera_info");
  for (auto& f : generate_camera_sequence()) {
    append(images, std::move(f.image));
    append(infos, std::move(f.info));
  }
  return {std::move(images), std::move(infos)};
}

// The pair is rectified: its topics are those a3 takes, and its disparity is on the topic a8 takes,
// so that the bag `dataset generate` writes plays into both without remapping.
std::vector<DatasetStream> stereo_streams(const plugin::Parameters&) {
  plugin::StereoPairStreams pair;
  auto truth = make_stream<msgs::DisparityImage>("disparity_truth", "/ground_truth/disparity");
  auto disparity = make_stream<msgs::DisparityImage>("disparity", "/disparity");
  for (auto& f : generate_stereo_sequence()) {
    pair.append(std::move(f.left), std::move(f.left_info), std::move(f.right),
                std::move(f.right_info));
    append(truth, std::move(f.truth));
    append(disparity, std::move(f.disparity));
  }
  std::vector<DatasetStream> more;
  more.push_back(std::move(truth));
  more.push_back(std::move(disparity));
  return pair.take(std::move(more));
}

// Depth registered to the colour camera, on the topics a4 and a6 take (depth_image_proc's names),
// and its cloud in the camera's body frame, on the topic a7 takes.
std::vector<DatasetStream> depth_streams(const plugin::Parameters&) {
  auto depth = make_stream<msgs::Image>("depth", "/camera/depth_registered/image_rect");
  auto depth_mm = make_stream<msgs::Image>("depth_mm", "/camera/depth_registered/image_rect_mm");
  auto image = make_stream<msgs::Image>("image", "/camera/rgb/image_rect_color");
  auto info = make_stream<msgs::CameraInfo>("camera_info", "/camera/rgb/camera_info");
  auto truth = make_stream<msgs::Image>("depth_truth", "/ground_truth/depth");
  auto cloud = make_stream<msgs::PointCloud2>("cloud", "/camera/depth/points");
  for (auto& f : generate_depth_sequence()) {
    append(depth, std::move(f.depth));
    append(depth_mm, std::move(f.depth_mm));
    append(image, std::move(f.colour));
    append(info, std::move(f.info));
    append(truth, std::move(f.truth_depth));
    append(cloud, std::move(f.cloud));
  }
  return {std::move(depth), std::move(depth_mm), std::move(image),
          std::move(info),  std::move(truth),    std::move(cloud)};
}

}  // namespace

void register_datasets(plugin::Registrar& registrar) {
  const SyntheticCameraConfig camera;
  registrar.add_dataset(
      {.name = "perception/image",
       .description = "synthetic 640x480 rgb8 camera, 30 Hz, 68 frames, plumb_bob k1=-0.25 "
                      "k2=0.12 p1=-0.00028 p2=-5e-5, hfov 1.047 rad; checkerboard with a moving "
                      "box",
       .rate_hz = camera.rate_hz,
       .frames = camera.frames,
       .streams = {{"image", "/camera/image_raw", "sensor_msgs/msg/Image", false,
                    "the distorted camera image"},
                   {"camera_info", "/camera/camera_info", "sensor_msgs/msg/CameraInfo", false,
                    "its calibration (plumb_bob)"}}},
      camera_streams);
  const SyntheticStereoConfig stereo;
  registrar.add_dataset(
      {.name = "perception/stereo",
       .description = "synthetic rectified 640x480 rgb8 stereo pair, 10 Hz, 10 frames, baseline "
                      "0.10 m, hfov 1.089 rad; ray-cast textured room with moving boxes (depth "
                      "1.6-6 m)",
       .rate_hz = stereo.rate_hz,
       .frames = stereo.frames,
       .streams = plugin::stereo_pair_stream_infos(
           {{"disparity_truth", "/ground_truth/disparity", "stereo_msgs/msg/DisparityImage", true,
             "per-pixel true disparity of the left view, NaN where "
             "occluded"},
            {"disparity", "/disparity", "stereo_msgs/msg/DisparityImage", false,
             "the true disparity as stereo_image_proc publishes one: 1/16 px steps, -1 where "
             "there is none"}})},
      stereo_streams);
  const SyntheticDepthConfig depth;
  registrar.add_dataset(
      {.name = "perception/depth",
       .description = "synthetic registered 640x480 depth + rgb8 colour, 30 Hz, 20 frames, hfov "
                      "1.089 rad, range 0.05-8 m; ray-cast room with moving boxes and a doorway "
                      "beyond range",
       .rate_hz = depth.rate_hz,
       .frames = depth.frames,
       .streams = {{"depth", "/camera/depth_registered/image_rect", "sensor_msgs/msg/Image", false,
                    "32FC1 depth in metres, NaN = none"},
                   {"depth_mm", "/camera/depth_registered/image_rect_mm", "sensor_msgs/msg/Image",
                    false, "16UC1 depth in millimetres, 0 = none"},
                   {"image", "/camera/rgb/image_rect_color", "sensor_msgs/msg/Image", false,
                    "rgb8 colour"},
                   {"camera_info", "/camera/rgb/camera_info", "sensor_msgs/msg/CameraInfo", false,
                    "the colour camera's calibration"},
                   {"depth_truth", "/ground_truth/depth", "sensor_msgs/msg/Image", true,
                    "64FC1 true depth"},
                   {"cloud", "/camera/depth/points", "sensor_msgs/msg/PointCloud2", false,
                    "the true depth's xyz points in camera_link (x forward, z up), NaN = none"}}},
      depth_streams);
}

}  // namespace robotperf::perception
