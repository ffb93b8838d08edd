// The perception kernels as graph nodes: an input the kernel cannot use is skipped and counted, as
// the ROS nodes log and drop it, and the node goes on with the next.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "../node_test_support.hpp"
#include "category.hpp"
#include "output_pool.hpp"
#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/msgs/stereo_msgs.hpp"
#include "robotperf/perception/image_proc.hpp"
#include "robotperf/perception/synthetic_depth.hpp"
#include "robotperf/perception/synthetic_stereo.hpp"

namespace robotperf::perception {
namespace {

const testing::CategoryUnderTest& category() {
  static const testing::CategoryUnderTest c{
      register_image_proc_kernels, register_stereo_depth_kernels, register_laser_scan_kernels};
  return c;
}

const StereoFrame& frame() {
  static const StereoFrame f = [] {
    SyntheticStereoConfig c;
    c.frames = 1;
    return generate_stereo_sequence(c).front();
  }();
  return f;
}

template <class T>
T stamped(T message, int32_t sec) {
  message.header.stamp = {sec, 0};
  return message;
}

template <class T>
bool has_stamp(const std::vector<T>& messages, int32_t sec) {
  for (const auto& m : messages)
    if (m.header.stamp.sec == sec) return true;
  return false;
}

// A node's next output is its last one only when nobody else holds that one: a subscriber still
// reading a message never sees it overwritten by the next frame.
TEST(OutputPool, ReusesTheLastMessageOnlyOnceEveryHolderHasLetGo) {
  OutputPool<msgs::Image> pool;
  std::shared_ptr<msgs::Image> first = pool.acquire();
  first->data.assign(1000, 7);
  const uint8_t* pixels = first->data.data();
  std::shared_ptr<const msgs::Image> held = first;  // published; a subscriber holds it
  first.reset();
  std::shared_ptr<msgs::Image> second = pool.acquire();
  EXPECT_NE(second.get(), held.get());
  second->data.assign(1000, 9);
  EXPECT_EQ(held->data, std::vector<uint8_t>(1000, 7));
  second.reset();
  held.reset();
  // The second is the pool's last now; the first went with its holder.
  std::shared_ptr<msgs::Image> third = pool.acquire();
  EXPECT_EQ(third->data, std::vector<uint8_t>(1000, 9));
  EXPECT_NE(third->data.data(), pixels);
  const uint8_t* kept = third->data.data();
  third.reset();
  // Let go by everyone: the same message and buffer, which resize() to its size does not touch.
  std::shared_ptr<msgs::Image> fourth = pool.acquire();
  EXPECT_EQ(fourth->data.data(), kept);
}

// An uncalibrated camera (K[0] = 0), which image_proc's rectify refuses, then a calibrated one.
TEST(RectifyNode, SkipsAnUncalibratedCameraAndGoesOn) {
  testing::NodeUnderTest node(category(), "image_proc/rectify");
  auto& rectified = node.output<msgs::Image>("image_rect");
  auto image = node.input<msgs::Image>("image");
  auto info = node.input<msgs::CameraInfo>("camera_info");
  node.start();
  msgs::CameraInfo uncalibrated = frame().left_info;
  uncalibrated.k[0] = 0;
  info->publish(stamped(uncalibrated, 1));
  image->publish(stamped(frame().left, 1));
  info->publish(stamped(frame().left_info, 2));
  image->publish(stamped(frame().left, 2));
  EXPECT_TRUE(rectified.wait([](const auto& so_far) { return has_stamp(so_far, 2); }));
  node.stop();
  EXPECT_EQ(rectified.messages().size(), 1u);
  EXPECT_EQ(node.counters().at("rejected_sets"), 1u);
}

// A pair smaller than the correlation window, which OpenCV's StereoBM refuses with a cv::Exception,
// then a pair it can match.
TEST(DisparityNode, SkipsAPairOpenCvRefusesAndGoesOn) {
  testing::NodeUnderTest node(category(), "stereo_image_proc/disparity");
  auto& disparity = node.output<msgs::DisparityImage>("disparity");
  auto left = node.input<msgs::Image>("left_image");
  auto right = node.input<msgs::Image>("right_image");
  auto left_info = node.input<msgs::CameraInfo>("left_camera_info");
  auto right_info = node.input<msgs::CameraInfo>("right_camera_info");
  node.start();
  msgs::Image tiny;
  prepare_image(tiny, {}, "mono8", 12, 12);
  msgs::CameraInfo tiny_left = frame().left_info, tiny_right = frame().right_info;
  tiny_left.width = tiny_right.width = 12;
  tiny_left.height = tiny_right.height = 12;
  left->publish(stamped(tiny, 1));
  right->publish(stamped(tiny, 1));
  left_info->publish(stamped(tiny_left, 1));
  right_info->publish(stamped(tiny_right, 1));
  left->publish(stamped(frame().left, 2));
  right->publish(stamped(frame().right, 2));
  left_info->publish(stamped(frame().left_info, 2));
  right_info->publish(stamped(frame().right_info, 2));
  EXPECT_TRUE(disparity.wait([](const auto& so_far) { return has_stamp(so_far, 2); }));
  node.stop();
  EXPECT_EQ(disparity.messages().size(), 1u);
  EXPECT_EQ(node.counters().at("rejected_sets"), 1u);
}

// A disparity the point cloud cannot use (16UC1) is skipped and counted, and the next is used.
TEST(StereoPointCloudNode, SkipsADisparityItCannotUseAndGoesOn) {
  testing::NodeUnderTest node(category(), "stereo_image_proc/point_cloud");
  auto& points = node.output<msgs::PointCloud2>("points2");
  auto left = node.input<msgs::Image>("left_image");
  auto left_info = node.input<msgs::CameraInfo>("left_camera_info");
  auto right_info = node.input<msgs::CameraInfo>("right_camera_info");
  auto disparity = node.input<msgs::DisparityImage>("disparity");
  node.start();
  msgs::DisparityImage millimetres = frame().disparity;
  prepare_image(millimetres.image, {}, "16UC1", 640, 480);
  const msgs::DisparityImage& unusable = millimetres;
  for (const msgs::DisparityImage* d : {&unusable, &frame().disparity}) {
    const int32_t sec = d == &unusable ? 1 : 2;
    left_info->publish(stamped(frame().left_info, sec));
    right_info->publish(stamped(frame().right_info, sec));
    left->publish(stamped(frame().left, sec));
    disparity->publish(stamped(*d, sec));
  }
  EXPECT_TRUE(points.wait([](const auto& so_far) { return has_stamp(so_far, 2); }));
  node.stop();
  EXPECT_EQ(points.messages().size(), 1u);
  EXPECT_EQ(node.counters().at("rejected_sets"), 1u);
}

// depthimage_to_laserscan converts each depth image with the latest CameraInfo (a depth image
// published after one is converted with it, whatever its stamp), counts images that come before
// any, and skips an image it cannot convert.
TEST(DepthToScanNode, UsesTheLatestCameraInfoAndSkipsWhatItCannotConvert) {
  static const DepthFrame depth_frame = [] {
    SyntheticDepthConfig c;
    c.frames = 1;
    return generate_depth_sequence(c).front();
  }();
  testing::NodeUnderTest node(category(), "depthimage_to_laserscan/convert");
  auto& scans = node.output<msgs::LaserScan>("scan");
  auto depth = node.input<msgs::Image>("depth");
  auto info = node.input<msgs::CameraInfo>("depth_camera_info");
  node.start();
  depth->publish(stamped(depth_frame.depth, 1));
  info->publish(stamped(depth_frame.info, 7));
  depth->publish(stamped(depth_frame.depth, 2));
  // A camera whose principal point is 40 px to the right: a wider left half of the scan.
  msgs::CameraInfo shifted = depth_frame.info;
  shifted.p[2] += 40.0;
  info->publish(stamped(shifted, 8));
  depth->publish(stamped(depth_frame.colour, 3));  // rgb8: no depth
  depth->publish(stamped(depth_frame.depth, 4));
  ASSERT_TRUE(scans.wait([](const auto& so_far) { return has_stamp(so_far, 4); }));
  node.stop();
  const std::vector<msgs::LaserScan> out = scans.messages();
  const auto counters = node.counters();
  EXPECT_EQ(counters.at("rejected_images"), 1u);
  // Image 1 may be converted, or dropped when it came before the first CameraInfo; image 2 is
  // converted with the first or, when the second came in between, with the second.
  EXPECT_EQ(out.size() + counters.at("images_without_camera_info"), 3u);
  EXPECT_FALSE(has_stamp(out, 3));
  const double fx = depth_frame.info.p[0];
  EXPECT_NEAR(out.back().angle_max, std::atan2(shifted.p[2], fx), 1e-6);
}

// pointcloud_to_laserscan skips a cloud in a frame it would need tf for and goes on; angles that
// make no scan are refused when the node is built, naming it.
TEST(CloudToScanNode, SkipsACloudInAnotherFrameAndRefusesBadAngles) {
  static const DepthFrame depth_frame = [] {
    SyntheticDepthConfig c;
    c.frames = 1;
    return generate_depth_sequence(c).front();
  }();
  testing::NodeUnderTest node(category(), "pointcloud_to_laserscan/convert",
                              {{"target_frame", "camera_link"}});
  auto& scans = node.output<msgs::LaserScan>("scan");
  auto cloud = node.input<msgs::PointCloud2>("cloud_in");
  node.start();
  msgs::PointCloud2 elsewhere = stamped(depth_frame.cloud, 1);
  elsewhere.header.frame_id = "camera_depth_optical_frame";
  cloud->publish(elsewhere);
  cloud->publish(stamped(depth_frame.cloud, 2));
  ASSERT_TRUE(scans.wait([](const auto& so_far) { return has_stamp(so_far, 2); }));
  node.stop();
  EXPECT_EQ(scans.messages().size(), 1u);
  EXPECT_EQ(node.counters().at("rejected_clouds"), 1u);
  try {
    testing::NodeUnderTest bad(category(), "pointcloud_to_laserscan/convert",
                               {{"angle_increment", "-0.01"}});
    ADD_FAILURE() << "a negative angle_increment was taken";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("angle_increment must be positive"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace robotperf::perception
