// stereo_image_proc/point_cloud: the cloud's layout, its points against the scene's truth and
// OpenCV's reprojectImageTo3D, its refusals, and the opencl backend against the cpu's.
#include "robotperf/perception/stereo_point_cloud.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <opencv2/calib3d.hpp>

#include "robotperf/perception/opencl_device.hpp"
#include "robotperf/perception/synthetic_stereo.hpp"

namespace robotperf::perception {
namespace {

const StereoFrame& frame() {
  static const StereoFrame f = [] {
    SyntheticStereoConfig c;
    c.frames = 1;
    return generate_stereo_sequence(c).front();
  }();
  return f;
}

float float_at(const msgs::PointCloud2& c, uint32_t u, uint32_t v, uint32_t offset) {
  float value;
  std::memcpy(&value, c.data.data() + v * c.row_step + u * c.point_step + offset, 4);
  return value;
}

msgs::PointCloud2 cloud_of(const msgs::Image& left, const msgs::DisparityImage& disparity,
                           StereoPointCloudParams params = {}, std::string_view backend = "cpu") {
  msgs::PointCloud2 cloud;
  StereoPointCloudProcessor(backend).compute(left, frame().left_info, frame().right_info, disparity,
                                             params, cloud);
  return cloud;
}

TEST(StereoPointCloud, LaysOutFieldsAsPointCloudNodeDoes) {
  struct Layout {
    bool colour, packed;
    uint32_t step, rgb;
  };
  for (const Layout l : {Layout{true, false, 32, 16}, Layout{false, false, 16, 0},
                         Layout{true, true, 16, 12}, Layout{false, true, 12, 0}}) {
    const msgs::PointCloud2 c = cloud_of(frame().left, frame().disparity, {l.colour, l.packed});
    EXPECT_EQ(c.point_step, l.step);
    EXPECT_EQ(c.row_step, l.step * 640);
    EXPECT_EQ(c.width, 640u);
    EXPECT_EQ(c.height, 480u);
    EXPECT_EQ(c.data.size(), std::size_t{l.step} * 640 * 480);
    EXPECT_FALSE(c.is_dense);
    EXPECT_EQ(c.header, frame().disparity.header);
    ASSERT_EQ(c.fields.size(), l.colour ? 4u : 3u);
    EXPECT_EQ(c.fields[2].name, "z");
    EXPECT_EQ(c.fields[2].offset, 8u);
    if (l.colour) {
      EXPECT_EQ(c.fields[3].name, "rgb");
      EXPECT_EQ(c.fields[3].offset, l.rgb);
    }
  }
}

// Every pixel with a true disparity has its true point, within what 1/16 px of rounding moves
// it; every other pixel (the disparity's -1) is a NaN point. Colours are the left image's.
TEST(StereoPointCloud, ScenePointsMatchTheTruth) {
  const StereoFrame& f = frame();
  const msgs::PointCloud2 c = cloud_of(f.left, f.disparity);
  const cv::Mat truth = image_view(f.truth.image);
  const cv::Mat left = image_view(f.left);
  const double fx = f.left_info.p[0], cx = f.left_info.p[2], cy = f.left_info.p[6];
  const double baseline = -f.right_info.p[3] / f.right_info.p[0];
  double worst = 0;
  std::size_t valid = 0;
  for (uint32_t v = 0; v < c.height; ++v) {
    for (uint32_t u = 0; u < c.width; ++u) {
      const float d = truth.at<float>(static_cast<int>(v), static_cast<int>(u));
      const float z = float_at(c, u, v, 8);
      ASSERT_EQ(std::isnan(d), std::isnan(z)) << u << "," << v;
      if (std::isnan(d)) continue;
      ++valid;
      const double tz = fx * baseline / d;
      const double tx = (u - cx) * tz / fx, ty = (v - cy) * tz / fx;
      const double error = std::hypot(float_at(c, u, v, 0) - tx, float_at(c, u, v, 4) - ty, z - tz);
      worst = std::max(worst, error / std::hypot(tx, ty, tz));
      const uint8_t* rgb = c.data.data() + v * c.row_step + u * c.point_step + 16;
      const uint8_t* px = left.ptr<uint8_t>(static_cast<int>(v)) + 3 * u;
      ASSERT_TRUE(rgb[0] == px[2] && rgb[1] == px[1] && rgb[2] == px[0] && rgb[3] == 0);
    }
  }
  EXPECT_GT(valid, c.width * c.height / 2);
  EXPECT_GT(worst, 0.0);     // the disparity is rounded ...
  EXPECT_LT(worst, 0.0036);  // ... by at most 1/32 px, at the farthest 8.8 px
}

// The cpu's points are OpenCV's reprojectImageTo3D with image_geometry's Q, written out directly
// here: a principal point offset between the cameras moves every point.
TEST(StereoPointCloud, ReprojectsWithImageGeometrysQ) {
  msgs::CameraInfo right = frame().right_info;
  right.p[2] -= 2.0;  // cx_right = cx_left - 2
  const msgs::DisparityImage& disparity = frame().disparity;
  msgs::PointCloud2 c;
  StereoPointCloudProcessor().compute(frame().left, frame().left_info, right, disparity, {}, c);
  const auto& l = frame().left_info.p;
  const double tx = right.p[3] / right.p[0];
  const cv::Matx44d q(l[5] * tx, 0, 0, -l[5] * l[2] * tx,  //
                      0, l[0] * tx, 0, -l[0] * l[6] * tx,  //
                      0, 0, 0, l[0] * l[5] * tx,           //
                      0, 0, -l[5], l[5] * (l[2] - right.p[2]));
  cv::Mat xyz;
  cv::reprojectImageTo3D(image_view(disparity.image), xyz, q, true);
  for (uint32_t v = 0; v < c.height; v += 5) {
    for (uint32_t u = 0; u < c.width; u += 5) {
      const cv::Vec3f p = xyz.at<cv::Vec3f>(static_cast<int>(v), static_cast<int>(u));
      if (p[2] == kMissingZ || std::isinf(p[2])) {
        ASSERT_TRUE(std::isnan(float_at(c, u, v, 8)));
        continue;
      }
      for (int i = 0; i < 3; ++i) ASSERT_EQ(float_at(c, u, v, 4 * i), p[i]) << u << "," << v;
    }
  }
}

// The smallest disparity of the image is missing (reprojectImageTo3D's handling), and a zero
// disparity is a point at infinity: both are NaN points, as PointCloudNode's isValidPoint says.
TEST(StereoPointCloud, MissingAndZeroDisparitiesAreNanPoints) {
  msgs::DisparityImage disparity = frame().disparity;
  cv::Mat d = image_view(disparity.image);
  d.setTo(20.0f);
  d.at<float>(0, 0) = -1.0f;
  d.at<float>(1, 1) = 0.0f;
  const msgs::PointCloud2 c = cloud_of(frame().left, disparity, {false, false});
  EXPECT_TRUE(std::isnan(float_at(c, 0, 0, 0)) && std::isnan(float_at(c, 0, 0, 8)));
  EXPECT_TRUE(std::isnan(float_at(c, 1, 1, 4)) && std::isnan(float_at(c, 1, 1, 8)));
  EXPECT_NEAR(float_at(c, 2, 2, 8), frame().truth.f * frame().truth.t / 20.0, 1e-5);
  // Without a missing value every disparity is the smallest: nothing is left.
  d.setTo(20.0f);
  const msgs::PointCloud2 flat = cloud_of(frame().left, disparity, {false, false});
  EXPECT_TRUE(std::isnan(float_at(flat, 2, 2, 8)));
}

TEST(StereoPointCloud, ColoursEachEncodingAsBgrBytes) {
  for (const char* encoding : {"rgb8", "bgra8", "mono8"}) {
    msgs::Image left;
    cv::Mat m = prepare_image(left, frame().left.header, encoding, 640, 480);
    m.setTo(cv::Scalar(10, 20, 30, 40));
    const msgs::PointCloud2 c = cloud_of(left, frame().disparity);
    const uint8_t* rgb = c.data.data() + 16;
    const bool red_first = std::string(encoding) == "rgb8";
    const bool mono = std::string(encoding) == "mono8";
    EXPECT_EQ(rgb[0], mono ? 10 : red_first ? 30 : 10) << encoding;
    EXPECT_EQ(rgb[1], mono ? 10 : 20) << encoding;
    EXPECT_EQ(rgb[2], mono ? 10 : red_first ? 10 : 30) << encoding;
  }
}

TEST(StereoPointCloud, RefusesWhatItCannotReproject) {
  auto error = [](const msgs::Image& left, const msgs::CameraInfo& left_info,
                  const msgs::CameraInfo& right_info, const msgs::DisparityImage& disparity,
                  StereoPointCloudParams params = {}) -> std::string {
    msgs::PointCloud2 c;
    try {
      StereoPointCloudProcessor().compute(left, left_info, right_info, disparity, params, c);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  const StereoFrame& f = frame();
  msgs::DisparityImage mm = f.disparity;
  prepare_image(mm.image, mm.header, "16UC1", 640, 480);
  EXPECT_NE(error(f.left, f.left_info, f.right_info, mm).find("'16UC1' is not 32FC1"),
            std::string::npos);
  msgs::Image small;
  prepare_image(small, f.left.header, "rgb8", 320, 240);
  EXPECT_NE(error(small, f.left_info, f.right_info, f.disparity).find("left image is 320x240"),
            std::string::npos);
  EXPECT_EQ(error(small, f.left_info, f.right_info, f.disparity, {false, false}), "");
  msgs::Image mono16;
  prepare_image(mono16, f.left.header, "mono16", 640, 480);
  EXPECT_NE(error(mono16, f.left_info, f.right_info, f.disparity).find("'mono16'"),
            std::string::npos);
  msgs::CameraInfo no_focal = f.left_info;
  no_focal.p[5] = 0;
  EXPECT_NE(error(f.left, no_focal, f.right_info, f.disparity).find("no focal length"),
            std::string::npos);
  msgs::CameraInfo no_baseline = f.right_info;
  no_baseline.p[3] = 0;
  EXPECT_NE(error(f.left, f.left_info, no_baseline, f.disparity).find("baseline"),
            std::string::npos);
}

// Where two clouds first differ by more than one float ulp in x, y or z, or at all in another
// byte ("" nowhere), for a failure to show.
std::string first_difference(const msgs::PointCloud2& a, const msgs::PointCloud2& b) {
  if (a.data.size() != b.data.size() || a.fields != b.fields || a.header != b.header)
    return "layout or header";
  for (std::size_t i = 0; i < a.data.size(); ++i) {
    const std::size_t point = i / a.point_step, byte = i % a.point_step;
    if (byte < 12 && byte % 4 == 0) {
      float x, y;
      std::memcpy(&x, &a.data[i], 4);
      std::memcpy(&y, &b.data[i], 4);
      const bool same = std::isnan(x) ? std::isnan(y) : std::nextafter(x, y) == y || x == y;
      if (!same)
        return "point " + std::to_string(point) + " coordinate " + std::to_string(byte / 4);
      i += 3;
    } else if (a.data[i] != b.data[i]) {
      return "point " + std::to_string(point) + " byte " + std::to_string(byte);
    }
  }
  return "";
}

// The opencl backend gives the cpu's cloud, coordinates within one float ulp, in every layout, and
// one processor serves clouds of different sizes in turn, as a node's does.
TEST(StereoPointCloudOpenCl, GivesTheCpusCloud) {
  try {
    opencl_device();
  } catch (const std::invalid_argument& e) {
    GTEST_SKIP() << e.what();
  }
  StereoPointCloudProcessor device("opencl");
  const StereoFrame& f = frame();
  msgs::DisparityImage rough = f.disparity;
  image_view(rough.image).at<float>(10, 100) = 0.0f;  // a point at infinity
  const msgs::DisparityImage* disparities[] = {&f.disparity, &rough};
  for (const msgs::DisparityImage* disparity : disparities) {
    for (const StereoPointCloudParams p :
         {StereoPointCloudParams{true, false}, StereoPointCloudParams{false, false},
          StereoPointCloudParams{true, true}, StereoPointCloudParams{false, true}}) {
      msgs::PointCloud2 on_device;
      device.compute(f.left, f.left_info, f.right_info, *disparity, p, on_device);
      EXPECT_EQ(first_difference(on_device, cloud_of(f.left, *disparity, p)), "")
          << p.use_color << " " << p.avoid_point_cloud_padding;
    }
  }
  msgs::Image left;
  prepare_image(left, f.left.header, "bgr8", 7, 5).setTo(cv::Scalar(1, 2, 3));
  msgs::DisparityImage tiny = f.disparity;
  cv::Mat d = prepare_image(tiny.image, tiny.header, "32FC1", 7, 5);
  for (int v = 0; v < 5; ++v)
    for (int u = 0; u < 7; ++u) d.at<float>(v, u) = static_cast<float>(u + v) - 1.0f;
  msgs::PointCloud2 on_device;
  device.compute(left, f.left_info, f.right_info, tiny, {}, on_device);
  EXPECT_EQ(first_difference(on_device, cloud_of(left, tiny)), "");
}

}  // namespace
}  // namespace robotperf::perception
