// stereo_image_proc/disparity, depth_image_proc/point_cloud_xyzrgb and the input pairing.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <iostream>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/core/ocl.hpp>
#include <opencv2/imgproc.hpp>

#include "cuda_test_support.hpp"
#include "robotperf/perception/camera_model.hpp"
#include "robotperf/perception/depth_image_proc.hpp"
#include "robotperf/perception/image_proc.hpp"
#include "robotperf/perception/opencl_device.hpp"
#include "robotperf/perception/stereo_image_proc.hpp"
#include "robotperf/perception/synthetic_depth.hpp"
#include "robotperf/perception/synthetic_stereo.hpp"
#include "robotperf/plugin/message_sync.hpp"

namespace robotperf::perception {
namespace {

using plugin::MessageSync;
using plugin::SyncOptions;
using plugin::SyncPolicy;

// ---------------------------------------------------------------------------------------------
// MessageSync
// ---------------------------------------------------------------------------------------------

// Messages are their own stamps, so a test can see exactly what was paired.
std::shared_ptr<const void> msg(int64_t stamp) {
  return std::make_shared<const int64_t>(stamp);
}
int64_t stamp_of(const std::shared_ptr<const void>& m) {
  return *static_cast<const int64_t*>(m.get());
}

struct Recorder {
  std::vector<std::array<int64_t, 3>> sets;
  auto callback() {
    return [this](const MessageSync<3>::Set& s) {
      sets.push_back({stamp_of(s[0]), stamp_of(s[1]), stamp_of(s[2])});
    };
  }
};

TEST(MessageSync, ExactPairsOnlyIdenticalStampsAndDropsTheUnpaired) {
  Recorder r;
  MessageSync<3> sync({SyncPolicy::kExact, 10}, r.callback());
  for (int64_t k = 0; k < 10; ++k) {
    if (k != 4) sync.add(0, msg(k), k);  // input 0 loses frame 4
    sync.add(1, msg(k), k);
    if (k != 7) sync.add(2, msg(k), k);  // input 2 loses frame 7
  }
  ASSERT_EQ(r.sets.size(), 8u);
  for (const auto& s : r.sets) {
    EXPECT_EQ(s[0], s[1]);
    EXPECT_EQ(s[1], s[2]);
    EXPECT_NE(s[0], 4);
    EXPECT_NE(s[0], 7);
  }
  EXPECT_EQ(sync.emitted(), 8u);
  // Frame 4: inputs 1 and 2 dropped; frame 7: inputs 0 and 1.
  EXPECT_EQ(sync.dropped()[0], 1u);
  EXPECT_EQ(sync.dropped()[1], 2u);
  EXPECT_EQ(sync.dropped()[2], 1u);
}

TEST(MessageSync, ExactDropsTheOldestStampBeyondTheQueue) {
  Recorder r;
  MessageSync<3> sync({SyncPolicy::kExact, 2}, r.callback());
  for (int64_t k = 0; k < 5; ++k) sync.add(0, msg(k), k);  // inputs 1, 2 silent
  EXPECT_EQ(sync.dropped()[0], 3u);
  sync.add(1, msg(4), 4);
  sync.add(2, msg(4), 4);
  ASSERT_EQ(r.sets.size(), 1u);
  EXPECT_EQ(r.sets[0], (std::array<int64_t, 3>{4, 4, 4}));
  EXPECT_EQ(sync.dropped()[0], 4u);  // 3 was passed over
}

TEST(MessageSync, ApproximatePairsNearestStampsAcrossAnOffset) {
  Recorder r;
  MessageSync<3> sync({SyncPolicy::kApproximate, 5}, r.callback());
  // Colour and CameraInfo 5 ms after depth, frames 33 ms apart.
  for (int64_t k = 0; k < 6; ++k) {
    sync.add(0, msg(k * 33), k * 33);
    sync.add(1, msg(k * 33 + 5), k * 33 + 5);
    sync.add(2, msg(k * 33 + 5), k * 33 + 5);
  }
  // Each set waits for the next depth to be sure: 5 of 6 frames out, none mixed.
  ASSERT_EQ(r.sets.size(), 5u);
  for (std::size_t i = 0; i < r.sets.size(); ++i) {
    EXPECT_EQ(r.sets[i][0], static_cast<int64_t>(i) * 33);
    EXPECT_EQ(r.sets[i][1], r.sets[i][0] + 5);
    EXPECT_EQ(r.sets[i][2], r.sets[i][0] + 5);
  }
  EXPECT_EQ(sync.dropped_total(), 0u);
}

TEST(MessageSync, ApproximateWithIdenticalStampsEmitsAtOnceAndDropsALostFramesPartners) {
  Recorder r;
  MessageSync<3> sync({SyncPolicy::kApproximate, 5, 10}, r.callback());
  for (int64_t k = 0; k < 8; ++k) {
    const int64_t t = k * 100;
    sync.add(1, msg(t), t);
    sync.add(2, msg(t), t);
    if (k != 3) sync.add(0, msg(t), t);  // depth of frame 3 lost
    EXPECT_EQ(r.sets.size(), static_cast<std::size_t>(k < 3 ? k + 1 : k)) << "frame " << k;
  }
  for (const auto& s : r.sets) {
    EXPECT_EQ(s[0], s[1]);
    EXPECT_EQ(s[0], s[2]);
  }
  EXPECT_EQ(sync.dropped()[0], 0u);
  EXPECT_EQ(sync.dropped()[1], 1u);
  EXPECT_EQ(sync.dropped()[2], 1u);
}

TEST(MessageSync, ApproximateRespectsMaxInterval) {
  Recorder r;
  MessageSync<3> sync({SyncPolicy::kApproximate, 5, 10}, r.callback());
  sync.add(0, msg(0), 0);
  sync.add(1, msg(50), 50);
  sync.add(2, msg(50), 50);
  sync.add(0, msg(100), 100);
  sync.add(1, msg(100), 100);
  sync.add(2, msg(100), 100);
  ASSERT_EQ(r.sets.size(), 1u);  // 0 and 50 are too far apart; 50 and 100 too
  EXPECT_EQ(r.sets[0], (std::array<int64_t, 3>{100, 100, 100}));
  EXPECT_EQ(sync.dropped_total(), 3u);
}

// ---------------------------------------------------------------------------------------------
// Disparity
// ---------------------------------------------------------------------------------------------

class Disparity : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    perception::SyntheticStereoConfig c;
    c.frames = 2;
    frames_ = new std::vector<perception::StereoFrame>(perception::generate_stereo_sequence(c));
  }
  static void TearDownTestSuite() { delete frames_; }

  // bad-1 share and valid share against the truth inside the valid window.
  static std::pair<double, double> accuracy(const msgs::DisparityImage& out,
                                            const msgs::DisparityImage& truth) {
    const cv::Mat d = image_view(out.image), gt = image_view(truth.image);
    int evaluated = 0, valid = 0, bad = 0;
    const auto& w = out.valid_window;
    for (uint32_t v = w.y_offset; v < w.y_offset + w.height; ++v) {
      for (uint32_t u = w.x_offset; u < w.x_offset + w.width; ++u) {
        const float g = gt.at<float>(v, u);
        if (std::isnan(g)) continue;
        ++evaluated;
        const float x = d.at<float>(v, u);
        if (x < out.min_disparity) continue;
        ++valid;
        bad += std::abs(x - g) > 1.0f;
      }
    }
    return {static_cast<double>(bad) / valid, static_cast<double>(valid) / evaluated};
  }

  static std::vector<perception::StereoFrame>* frames_;
};
std::vector<perception::StereoFrame>* Disparity::frames_ = nullptr;

TEST_F(Disparity, FillsTheDisparityImageAsStereoImageProc) {
  const auto& f = (*frames_)[0];
  DisparityProcessor bm;
  msgs::DisparityImage out;
  bm.compute(f.left, f.right, f.left_info, f.right_info, out);
  EXPECT_EQ(out.header, f.left_info.header);
  EXPECT_EQ(out.image.header, f.left_info.header);
  EXPECT_EQ(out.image.encoding, "32FC1");
  EXPECT_EQ(out.image.width, 640u);
  EXPECT_EQ(out.image.height, 480u);
  EXPECT_EQ(out.image.step, 640u * 4);
  EXPECT_FLOAT_EQ(out.f, static_cast<float>(f.right_info.p[0]));
  EXPECT_NEAR(out.t, 0.10f, 1e-6);
  // Window 15 (border 7), range 64, min 0: x from 64 + 0 + 7 - 1 = 70 to 640 - 1 - 7 = 632.
  EXPECT_EQ(out.valid_window.x_offset, 70u);
  EXPECT_EQ(out.valid_window.y_offset, 7u);
  EXPECT_EQ(out.valid_window.width, 632u - 70u);
  EXPECT_EQ(out.valid_window.height, 472u - 7u);
  EXPECT_FLOAT_EQ(out.min_disparity, 0.0f);
  EXPECT_FLOAT_EQ(out.max_disparity, 63.0f);
  EXPECT_FLOAT_EQ(out.delta_d, 1.0f / 16);
  // Fixed-point values / 16: every disparity is a multiple of 1/16; invalid ones are -1.
  const cv::Mat d = image_view(out.image);
  int invalid = 0;
  for (int v = 0; v < d.rows; ++v) {
    for (int u = 0; u < d.cols; ++u) {
      const float x = d.at<float>(v, u);
      EXPECT_EQ(x * 16, std::round(x * 16));
      invalid += x == -1.0f;
    }
  }
  EXPECT_GT(invalid, 480 * 64);  // at least the band left of the search range
  const auto [bad1, valid] = accuracy(out, f.truth);
  EXPECT_LT(bad1, 0.05);
  EXPECT_GT(valid, 0.85);
}

// StereoBM as stereo_image_proc sets it up: its parameters, and no left-right check
// (disp12_max_diff is given to its StereoSGBM only), so OpenCV's default of -1.
TEST_F(Disparity, BlockMatchingIsStereoImageProcsStereoBm) {
  const auto& f = (*frames_)[0];
  StereoParams with_check;
  with_check.disp12_max_diff = 1;
  DisparityProcessor bm, bm_given_a_check(with_check);
  msgs::DisparityImage out, out_given_a_check;
  bm.compute(f.left, f.right, f.left_info, f.right_info, out);
  bm_given_a_check.compute(f.left, f.right, f.left_info, f.right_info, out_given_a_check);

  auto matcher = cv::StereoBM::create(64, 15);
  matcher->setPreFilterSize(9);
  matcher->setPreFilterCap(31);
  matcher->setTextureThreshold(10);
  matcher->setUniquenessRatio(15);
  matcher->setSpeckleWindowSize(100);
  matcher->setSpeckleRange(4);
  matcher->setMinDisparity(0);
  ASSERT_EQ(matcher->getDisp12MaxDiff(), -1);
  cv::Mat left, right, fixed, expected;
  cv::cvtColor(image_view(f.left), left, cv::COLOR_RGB2GRAY);
  cv::cvtColor(image_view(f.right), right, cv::COLOR_RGB2GRAY);
  matcher->compute(left, right, fixed);
  fixed.convertTo(expected, CV_32F, 1.0 / 16);
  EXPECT_EQ(cv::countNonZero(image_view(out.image) != expected), 0);
  EXPECT_EQ(out.image.data, out_given_a_check.image.data);
}

TEST_F(Disparity, SubtractsThePrincipalPointOffset) {
  const auto& f = (*frames_)[0];
  DisparityProcessor bm;
  msgs::DisparityImage plain, shifted;
  bm.compute(f.left, f.right, f.left_info, f.right_info, plain);
  msgs::CameraInfo right = f.right_info;
  right.p[2] -= 2.0;  // cx_left - cx_right = 2
  bm.compute(f.left, f.right, f.left_info, right, shifted);
  const cv::Mat a = image_view(plain.image), b = image_view(shifted.image);
  EXPECT_FLOAT_EQ(b.at<float>(240, 320), a.at<float>(240, 320) - 2.0f);
}

TEST_F(Disparity, SemiGlobalMatchingIsSelectableAndAccurate) {
  const auto& f = (*frames_)[1];
  StereoParams p;
  p.algorithm = StereoAlgorithm::kSemiGlobal;
  DisparityProcessor sgbm(p);
  msgs::DisparityImage out;
  sgbm.compute(f.left, f.right, f.left_info, f.right_info, out);
  const auto [bad1, valid] = accuracy(out, f.truth);
  EXPECT_LT(bad1, 0.05);
  EXPECT_GT(valid, 0.85);
}

TEST_F(Disparity, SwappedImagesGiveGarbage) {
  const auto& f = (*frames_)[0];
  DisparityProcessor bm;
  msgs::DisparityImage out;
  bm.compute(f.right, f.left, f.left_info, f.right_info, out);
  const auto [bad1, valid] = accuracy(out, f.truth);
  EXPECT_LT(valid, 0.5);
}

// A mono8 pair then an rgb8 pair on one processor: the grey conversion of the second goes into
// a buffer of its own, not into the first pair's messages, which the processor had viewed.
TEST_F(Disparity, ColourPairAfterAMonoPairLeavesTheMonoMessagesAlone) {
  auto grey = [](const msgs::Image& rgb) {
    msgs::Image out;
    cv::cvtColor(image_view(rgb), prepare_image(out, rgb.header, "mono8", 640, 480),
                 cv::COLOR_RGB2GRAY);
    return out;
  };
  const auto& first = (*frames_)[0];
  const auto& second = (*frames_)[1];
  ASSERT_EQ(second.left.encoding, "rgb8");
  const msgs::Image mono_left = grey(first.left), mono_right = grey(first.right);
  const msgs::Image left_before = mono_left, right_before = mono_right;
  DisparityProcessor bm;
  msgs::DisparityImage out;
  bm.compute(mono_left, mono_right, first.left_info, first.right_info, out);
  bm.compute(second.left, second.right, second.left_info, second.right_info, out);
  EXPECT_EQ(mono_left.data, left_before.data);
  EXPECT_EQ(mono_right.data, right_before.data);
}

TEST_F(Disparity, RejectsBadParametersAndInputs) {
  StereoParams p;
  p.disparity_range = 60;
  EXPECT_THROW(DisparityProcessor{p}, std::invalid_argument);
  p = {};
  p.correlation_window_size = 14;
  EXPECT_THROW(DisparityProcessor{p}, std::invalid_argument);
  p = {};
  p.algorithm = StereoAlgorithm::kSemiGlobal;
  p.p2 = p.p1;
  EXPECT_THROW(DisparityProcessor{p}, std::invalid_argument);

  const auto& f = (*frames_)[0];
  DisparityProcessor bm;
  msgs::DisparityImage out;
  msgs::Image small;
  prepare_image(small, f.right.header, "rgb8", 320, 240);
  EXPECT_THROW(bm.compute(f.left, small, f.left_info, f.right_info, out), std::invalid_argument);
  msgs::Image depth;
  prepare_image(depth, f.right.header, "32FC1", 640, 480);
  EXPECT_THROW(bm.compute(f.left, depth, f.left_info, f.right_info, out), std::invalid_argument);
}

// ---------------------------------------------------------------------------------------------
// Point cloud xyzrgb
// ---------------------------------------------------------------------------------------------

struct Point {
  float x, y, z;
  uint8_t b, g, r, a;
};
Point point_at(const msgs::PointCloud2& c, uint32_t u, uint32_t v) {
  Point p;
  const uint8_t* base = c.data.data() + v * c.row_step + u * c.point_step;
  std::memcpy(&p.x, base + 0, 4);
  std::memcpy(&p.y, base + 4, 4);
  std::memcpy(&p.z, base + 8, 4);
  p.b = base[16];
  p.g = base[17];
  p.r = base[18];
  p.a = base[19];
  return p;
}

// A 4x3 camera, fx = fy = 2, cx = 1.5, cy = 1.
struct Tiny {
  msgs::CameraInfo info;
  msgs::Image depth, colour;
  Tiny(const char* depth_encoding, const char* colour_encoding) {
    info.width = 4;
    info.height = 3;
    info.k = {2, 0, 1.5, 0, 2, 1, 0, 0, 1};
    info.p = {2, 0, 1.5, 0, 0, 2, 1, 0, 0, 0, 1, 0};
    msgs::Header h;
    h.stamp = {5, 6};
    h.frame_id = "cam";
    cv::Mat d = prepare_image(depth, h, depth_encoding, 4, 3);
    cv::Mat c = prepare_image(colour, h, colour_encoding, 4, 3);
    for (int v = 0; v < 3; ++v) {
      for (int u = 0; u < 4; ++u) {
        if (d.depth() == CV_32F) {
          d.at<float>(v, u) = 1.0f + u + 10 * v;
        } else {
          d.at<uint16_t>(v, u) = static_cast<uint16_t>(1000 * (1 + u + 10 * v));
        }
        for (int ch = 0; ch < c.channels(); ++ch)
          c.ptr<uint8_t>(v)[u * c.channels() + ch] = static_cast<uint8_t>(10 * u + v + 100 * ch);
      }
    }
  }
};

TEST(PointCloudXyzrgb, LaysOutAnOrganisedXyzRgbCloud) {
  Tiny t("32FC1", "rgb8");
  msgs::PointCloud2 c;
  point_cloud_xyzrgb(t.depth, t.colour, t.info, {}, c);
  EXPECT_EQ(c.header, t.depth.header);
  EXPECT_EQ(c.width, 4u);
  EXPECT_EQ(c.height, 3u);
  EXPECT_EQ(c.point_step, 32u);
  EXPECT_EQ(c.row_step, 128u);
  EXPECT_EQ(c.data.size(), 384u);
  EXPECT_FALSE(c.is_dense);
  EXPECT_FALSE(c.is_bigendian);
  ASSERT_EQ(c.fields.size(), 4u);
  const char* names[] = {"x", "y", "z", "rgb"};
  const uint32_t offsets[] = {0, 4, 8, 16};
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(c.fields[i].name, names[i]);
    EXPECT_EQ(c.fields[i].offset, offsets[i]);
    EXPECT_EQ(c.fields[i].datatype, msgs::PointField::kFloat32);
    EXPECT_EQ(c.fields[i].count, 1u);
  }
  const Point p = point_at(c, 3, 2);  // z = 1 + 3 + 20 = 24
  EXPECT_FLOAT_EQ(p.z, 24.0f);
  EXPECT_FLOAT_EQ(p.x, (3 - 1.5f) * 24 / 2);
  EXPECT_FLOAT_EQ(p.y, (2 - 1.0f) * 24 / 2);
  EXPECT_EQ(p.r, 32);  // rgb8 pixel (u 3, v 2): r = 32, g = 132, b = 232
  EXPECT_EQ(p.g, 132);
  EXPECT_EQ(p.b, 232);
  EXPECT_EQ(p.a, 0);
}

TEST(PointCloudXyzrgb, AReusedCloudEqualsAFreshOne) {
  Tiny a("32FC1", "rgb8");
  Tiny b("32FC1", "rgb8");
  image_view(b.depth).at<float>(1, 2) = std::numeric_limits<float>::quiet_NaN();
  image_view(b.colour).at<cv::Vec3b>(2, 0) = cv::Vec3b(1, 2, 3);
  msgs::PointCloud2 reused, fresh;
  point_cloud_xyzrgb(a.depth, a.colour, a.info, {}, reused);
  point_cloud_xyzrgb(b.depth, b.colour, b.info, {}, reused);
  point_cloud_xyzrgb(b.depth, b.colour, b.info, {}, fresh);
  EXPECT_EQ(reused, fresh);
}

TEST(PointCloudXyzrgb, MillimetreDepthAndBgrColour) {
  Tiny t("16UC1", "bgr8");
  msgs::PointCloud2 c;
  point_cloud_xyzrgb(t.depth, t.colour, t.info, {}, c);
  const Point p = point_at(c, 1, 1);  // 12000 mm
  EXPECT_FLOAT_EQ(p.z, 12.0f);
  EXPECT_FLOAT_EQ(p.x, (1 - 1.5f) * 12 / 2);
  EXPECT_EQ(p.b, 11);  // bgr8 pixel: b = 11, g = 111, r = 211
  EXPECT_EQ(p.r, 211);
}

TEST(PointCloudXyzrgb, InvalidDepthGivesNanOrRangeMax) {
  Tiny t("16UC1", "mono8");
  image_view(t.depth).at<uint16_t>(0, 0) = 0;
  Tiny f("32FC1", "rgb8");
  image_view(f.depth).at<float>(0, 1) = std::numeric_limits<float>::quiet_NaN();
  msgs::PointCloud2 c;
  point_cloud_xyzrgb(t.depth, t.colour, t.info, {}, c);
  EXPECT_TRUE(std::isnan(point_at(c, 0, 0).x) && std::isnan(point_at(c, 0, 0).z));
  EXPECT_EQ(point_at(c, 0, 0).g, point_at(c, 0, 0).r);  // mono8: grey
  point_cloud_xyzrgb(f.depth, f.colour, f.info, {}, c);
  EXPECT_TRUE(std::isnan(point_at(c, 1, 0).y));
  point_cloud_xyzrgb(f.depth, f.colour, f.info, {5.0}, c);
  EXPECT_FLOAT_EQ(point_at(c, 1, 0).z, 5.0f);
  // 16UC1 fills with range_max in whole millimetres, rounded as depth_image_proc rounds, and no
  // further than the encoding reaches.
  point_cloud_xyzrgb(t.depth, t.colour, t.info, {2.01}, c);
  EXPECT_EQ(point_at(c, 0, 0).z, 2010 * 0.001f);
  point_cloud_xyzrgb(t.depth, t.colour, t.info, {100.0}, c);
  EXPECT_EQ(point_at(c, 0, 0).z, 65535 * 0.001f);
}

TEST(PointCloudXyzrgb, RejectsWhatDepthImageProcRejects) {
  Tiny t("32FC1", "rgb8");
  msgs::PointCloud2 c;
  msgs::Image other = t.colour;
  other.header.frame_id = "elsewhere";
  EXPECT_THROW(point_cloud_xyzrgb(t.depth, other, t.info, {}, c), std::invalid_argument);
  msgs::Image wrong;
  prepare_image(wrong, t.depth.header, "8UC1", 4, 3);
  EXPECT_THROW(point_cloud_xyzrgb(wrong, t.colour, t.info, {}, c), std::invalid_argument);
  prepare_image(wrong, t.depth.header, "rgb16", 4, 3);
  EXPECT_THROW(point_cloud_xyzrgb(t.depth, wrong, t.info, {}, c), std::invalid_argument);
  msgs::CameraInfo uncalibrated = t.info;
  uncalibrated.p = {};
  EXPECT_THROW(point_cloud_xyzrgb(t.depth, t.colour, uncalibrated, {}, c), std::invalid_argument);
  msgs::Image empty;
  prepare_image(empty, t.depth.header, "rgb8", 0, 0);
  EXPECT_THROW(point_cloud_xyzrgb(t.depth, empty, t.info, {}, c), std::invalid_argument);
}

// depth_image_proc's constant of x is the unit in double over the focal length in double, then
// a float: with a4's fx that is one ulp from the unit over the focal length in float.
TEST(PointCloudXyzrgb, ScalesByDepthImageProcsConstants) {
  Tiny t("32FC1", "rgb8");
  const double fx = 528.4338, fy = 529.1;
  t.info.p[0] = fx;
  t.info.p[5] = fy;
  t.info.p[2] = 2.0;
  t.info.p[6] = 1.0;
  image_view(t.depth).at<float>(2, 3) = 1.0f;  // (u - cx) = (v - cy) = 1 at depth 1 m
  const float constant_x = static_cast<float>(1.0 / fx);
  const float constant_y = static_cast<float>(1.0 / fy);
  ASSERT_NE(constant_x, 1.0f / static_cast<float>(fx));
  msgs::PointCloud2 c;
  point_cloud_xyzrgb(t.depth, t.colour, t.info, {}, c);
  const Point p = point_at(c, 3, 2);
  EXPECT_EQ(p.x, constant_x);
  EXPECT_EQ(p.y, constant_y);
}

TEST(PointCloudXyzrgb, ScenePointsMatchTheTruth) {
  perception::SyntheticDepthConfig config;
  config.frames = 1;
  const auto frames = perception::generate_depth_sequence(config);
  const auto& f = frames[0];
  for (const msgs::Image* depth : {&f.depth, &f.depth_mm}) {
    msgs::PointCloud2 c;
    point_cloud_xyzrgb(*depth, f.colour, f.info, {}, c);
    const cv::Mat truth = image_view(f.truth_depth);
    double worst = 0;
    for (uint32_t v = 0; v < c.height; v += 7) {
      for (uint32_t u = 0; u < c.width; u += 7) {
        const Point p = point_at(c, u, v);
        const double z = truth.at<double>(v, u);
        ASSERT_EQ(std::isnan(z), std::isnan(p.z)) << u << "," << v;
        if (std::isnan(z)) continue;
        const double x = (u - f.info.p[2]) * z / f.info.p[0];
        const double y = (v - f.info.p[6]) * z / f.info.p[5];
        worst = std::max(worst, std::hypot(p.x - x, p.y - y, p.z - z));
      }
    }
    EXPECT_LT(worst, depth->encoding == "16UC1" ? 1e-3 : 1e-5) << depth->encoding;
  }
}

// A device backend gives the CPU's cloud bit for bit: float and millimetre depth, invalid pixels
// as NaN and as range_max, every colour layout, and the synthetic scene; a colour image of another
// size is resized on the device (coordinates still identical, colours within 1). One processor
// for all, as a node keeps one: its buffers are reused, and grown for larger images.
void expect_the_cpus_cloud(std::string_view backend) {
  PointCloudXyzrgbProcessor device_processor(backend);
  auto both = [&](const msgs::Image& depth, const msgs::Image& colour, const msgs::CameraInfo& info,
                  PointCloudXyzrgbParams params) {
    std::pair<msgs::PointCloud2, msgs::PointCloud2> c;
    point_cloud_xyzrgb(depth, colour, info, params, c.first);
    device_processor.compute(depth, colour, info, params, c.second);
    return c;
  };
  for (const char* depth_encoding : {"32FC1", "16UC1"}) {
    for (const char* colour_encoding : {"rgb8", "bgra8", "mono8"}) {
      Tiny t(depth_encoding, colour_encoding);
      if (image_view(t.depth).depth() == CV_32F) {
        image_view(t.depth).at<float>(1, 2) = std::numeric_limits<float>::quiet_NaN();
      } else {
        image_view(t.depth).at<uint16_t>(1, 2) = 0;
      }
      for (const double range_max : {0.0, 5.0}) {
        const auto [cpu, device] = both(t.depth, t.colour, t.info, {range_max});
        EXPECT_EQ(device, cpu) << depth_encoding << " " << colour_encoding << " " << range_max;
      }
    }
  }
  perception::SyntheticDepthConfig config;
  config.frames = 1;
  const auto frames = perception::generate_depth_sequence(config);
  const auto& f = frames[0];
  for (const msgs::Image* depth : {&f.depth, &f.depth_mm}) {
    const auto [cpu, device] = both(*depth, f.colour, f.info, {});
    EXPECT_EQ(device, cpu) << depth->encoding;
  }
  msgs::Image half;
  msgs::CameraInfo half_info;
  ResizeParams p;
  p.scale_width = p.scale_height = 0.5;
  resize(f.colour, f.info, p, half, half_info);
  const auto [cpu, device] = both(f.depth, half, half_info, {});
  ASSERT_EQ(device.data.size(), cpu.data.size());
  std::size_t colours_off = 0;
  for (uint32_t v = 0; v < cpu.height; ++v) {
    for (uint32_t u = 0; u < cpu.width; ++u) {
      const Point a = point_at(cpu, u, v), b = point_at(device, u, v);
      ASSERT_EQ(std::memcmp(&a, &b, 12), 0) << "x, y, z of " << u << "," << v;
      colours_off += std::abs(a.r - b.r) > 1 || std::abs(a.g - b.g) > 1 || std::abs(a.b - b.b) > 1;
    }
  }
  EXPECT_LE(colours_off, cpu.width * cpu.height / 1000);
  // Back to a small image after the large ones: the kept buffers and kernel serve it too.
  const Tiny t("32FC1", "rgb8");
  const auto [small_cpu, small_device] = both(t.depth, t.colour, t.info, {});
  EXPECT_EQ(small_device, small_cpu);
}

TEST(PointCloudXyzrgb, OpenClGivesTheCpusCloud) {
  try {
    opencl_device();
  } catch (const std::invalid_argument& e) {
    GTEST_SKIP() << e.what();
  }
  expect_the_cpus_cloud("opencl");
}

TEST(PointCloudXyzrgb, CudaGivesTheCpusCloud) {
  if (const std::string why = without_cuda(); !why.empty()) GTEST_SKIP() << why;
  expect_the_cpus_cloud("cuda");
}

TEST(PointCloudXyzrgb, CudaWithoutItsBuildOrDeviceIsOneLine) {
  if (without_cuda().empty()) GTEST_SKIP() << "a CUDA device is there: " << cuda_device().name;
  expect_cuda_missing_line([] { PointCloudXyzrgbProcessor("cuda"); }, "PointCloudXyzrgbProcessor");
  Tiny t("32FC1", "rgb8");
  msgs::PointCloud2 c;
  expect_cuda_missing_line([&] { point_cloud_xyzrgb(t.depth, t.colour, t.info, {}, c, "cuda"); },
                           "point_cloud_xyzrgb");
}

}  // namespace
}  // namespace robotperf::perception

namespace robotperf::perception {
namespace {

// How a device backend's disparities compare with the cpu's on one pair.
struct DisparityAgreement {
  std::size_t pixels = 0;            // in the image
  std::size_t valid = 0;             // where the cpu found a disparity
  std::size_t within = 0;            // of those, the device's within 1 px
  std::size_t identical = 0;         // of those, the device's the same
  std::size_t validity_differs = 0;  // one found a disparity, the other not
};

// StereoBM on a device backend against OpenCV's StereoBM on the CPU, on the synthetic pair (of
// `height` rows) at stereo_image_proc's defaults and with another window, range, texture and
// uniqueness; the valid window is the cpu's. One result per parameter set and frame.
std::vector<DisparityAgreement> device_disparity_agreement(std::string_view backend,
                                                           uint32_t height = 480) {
  SyntheticStereoConfig config;
  config.frames = 2;
  config.height = height;
  const auto frames = generate_stereo_sequence(config);
  StereoParams narrow;
  narrow.correlation_window_size = 9;
  narrow.disparity_range = 32;
  narrow.min_disparity = 4;
  narrow.texture_threshold = 40;
  narrow.uniqueness_ratio = 5;
  narrow.speckle_size = 0;
  std::vector<DisparityAgreement> out;
  for (const StereoParams& params : {StereoParams{}, narrow}) {
    DisparityProcessor cpu(params);
    DisparityProcessor device(params, backend);
    for (const auto& f : frames) {
      msgs::DisparityImage a, b;
      cpu.compute(f.left, f.right, f.left_info, f.right_info, a);
      device.compute(f.left, f.right, f.left_info, f.right_info, b);
      EXPECT_EQ(b.valid_window, a.valid_window);
      EXPECT_EQ(b.image.data.size(), a.image.data.size());
      if (a.image.data.size() != b.image.data.size()) return out;
      const float* x = reinterpret_cast<const float*>(a.image.data.data());
      const float* y = reinterpret_cast<const float*>(b.image.data.data());
      DisparityAgreement d;
      d.pixels = a.image.data.size() / sizeof(float);
      for (std::size_t i = 0; i < d.pixels; ++i) {
        const bool cpu_valid = x[i] >= a.min_disparity;
        d.validity_differs += cpu_valid != (y[i] >= b.min_disparity) ? 1 : 0;
        if (!cpu_valid) continue;
        ++d.valid;
        d.within += std::abs(x[i] - y[i]) <= 1.0f ? 1 : 0;
        d.identical += x[i] == y[i] ? 1 : 0;
      }
      EXPECT_GT(d.valid, d.pixels / 2) << params.correlation_window_size;
      out.push_back(d);
    }
  }
  return out;
}

// The same pixels get a disparity, and the same one (the kernels follow OpenCV's fixed-point
// arithmetic): measured identical at the defaults, 3 pixels of 307200 apart with the narrow
// window. SGBM is refused.
TEST(DisparityOpenCl, GivesTheCpusDisparity) {
  try {
    opencl_device();
  } catch (const std::invalid_argument& e) {
    GTEST_SKIP() << e.what();
  }
  const auto results = device_disparity_agreement("opencl");
  EXPECT_EQ(results.size(), 4u);
  for (const DisparityAgreement& d : results) {
    EXPECT_GE(d.within, d.valid - d.valid / 1000);
    EXPECT_GE(d.identical, d.valid - d.valid / 1000);
    EXPECT_LE(d.validity_differs, d.pixels / 1000);
  }
  StereoParams sgbm;
  sgbm.algorithm = StereoAlgorithm::kSemiGlobal;
  EXPECT_THROW(DisparityProcessor(sgbm, "opencl"), std::invalid_argument);
}

// A cols x rows mono8 pair of noise and its CameraInfo, for the disparity's input checks.
struct MonoPair {
  msgs::Image left, right;
  msgs::CameraInfo info;
};
MonoPair mono_pair(uint32_t cols, uint32_t rows) {
  MonoPair pair;
  pair.info = make_pinhole_camera_info(cols, rows, 1.0, {}, "cam");
  cv::randu(prepare_image(pair.left, pair.info.header, "mono8", cols, rows), 0, 256);
  cv::randu(prepare_image(pair.right, pair.info.header, "mono8", cols, rows), 0, 256);
  return pair;
}

// OpenCV's StereoBM refuses a window not smaller than the images' width and height; a device
// backend refuses it as the cpu does (its kernels gave an all-invalid image), in one line naming
// the window. A smaller window on the same pair is computed.
void expect_a_window_as_large_as_the_images_refused(std::string_view backend) {
  const MonoPair pair = mono_pair(12, 12);
  StereoParams window_15;  // stereo_image_proc's default window
  ASSERT_EQ(window_15.correlation_window_size, 15);
  StereoParams window_5;
  window_5.correlation_window_size = 5;
  window_5.disparity_range = 16;
  for (const std::string_view b : {backend, std::string_view("cpu")}) {
    const std::string name(b);
    msgs::DisparityImage out;
    DisparityProcessor matcher(window_15, b);
    try {
      matcher.compute(pair.left, pair.right, pair.info, pair.info, out);
      ADD_FAILURE() << "a 15 px window on a 12x12 pair was computed on " << name;
    } catch (const std::invalid_argument& e) {
      const std::string line = e.what();
      EXPECT_NE(line.find("correlation_window_size 15"), std::string::npos) << name << ": " << line;
      EXPECT_EQ(line.find('\n'), std::string::npos) << name << ": " << line;
    }
    DisparityProcessor small(window_5, b);
    EXPECT_NO_THROW(small.compute(pair.left, pair.right, pair.info, pair.info, out)) << name;
  }
}

TEST(DisparityOpenCl, RefusesAWindowAsLargeAsTheImagesAsTheCpuDoes) {
  try {
    opencl_device();
  } catch (const std::invalid_argument& e) {
    GTEST_SKIP() << e.what();
  }
  expect_a_window_as_large_as_the_images_refused("opencl");
}

TEST(DisparityCuda, RefusesAWindowAsLargeAsTheImagesAsTheCpuDoes) {
  if (const std::string why = without_cuda(); !why.empty()) GTEST_SKIP() << why;
  expect_a_window_as_large_as_the_images_refused("cuda");
}

// The opencl StereoBM keeps its two cost volumes (an int per pixel and disparity) whole on the
// device: a pair and range whose volume is more than the device allocates at once is refused in
// one line before anything is allocated. 1920x1200 at 1024 disparities, 2.36e9 ints, once
// overflowed an int and failed in OpenCV's allocation.
TEST(DisparityOpenCl, RefusesACostVolumeLargerThanTheDeviceAllocates) {
  try {
    opencl_device();
  } catch (const std::invalid_argument& e) {
    GTEST_SKIP() << e.what();
  }
  const std::size_t max_alloc = cv::ocl::Device::getDefault().maxMemAllocSize();
  const MonoPair pair = mono_pair(1920, 1200);
  StereoParams wide;
  wide.disparity_range = 1024;
  while ((wide.disparity_range + 1) * std::size_t{1920 * 1200 * 4} <= max_alloc)
    wide.disparity_range += 1024;
  DisparityProcessor matcher(wide, "opencl");
  msgs::DisparityImage out;
  try {
    matcher.compute(pair.left, pair.right, pair.info, pair.info, out);
    ADD_FAILURE() << "a " << wide.disparity_range << "-disparity cost volume for 1920x1200 was "
                  << "computed on a device allocating " << max_alloc << " bytes at most";
  } catch (const std::invalid_argument& e) {
    const std::string line = e.what();
    EXPECT_NE(line.find("CL_DEVICE_MAX_MEM_ALLOC_SIZE"), std::string::npos) << line;
    EXPECT_NE(line.find("disparity_range " + std::to_string(wide.disparity_range)),
              std::string::npos)
        << line;
    EXPECT_EQ(line.find('\n'), std::string::npos) << line;
  }
}

// An odd height: OpenCV's pre-filter leaves the last row at the cap (it filters rows in pairs),
// and so do the device kernels; at the defaults the disparities are then the cpu's (a pre-filter
// of that row made 339 pixels differ). A few pixels of slack for the cpu's own variation.
void expect_cpus_disparity_at_an_odd_height(std::string_view backend) {
  const auto results = device_disparity_agreement(backend, 479);
  ASSERT_EQ(results.size(), 4u);
  for (std::size_t i = 0; i < 2; ++i) {  // the defaults' two frames
    EXPECT_GE(results[i].identical, results[i].valid - results[i].valid / 10000) << i;
    EXPECT_LE(results[i].validity_differs, results[i].pixels / 10000) << i;
  }
}

TEST(DisparityOpenCl, GivesTheCpusDisparityAtAnOddHeight) {
  try {
    opencl_device();
  } catch (const std::invalid_argument& e) {
    GTEST_SKIP() << e.what();
  }
  expect_cpus_disparity_at_an_odd_height("opencl");
}

// The cuda kernels are the OpenCL kernels' port (the same integer arithmetic): held to the backend
// check's bar, within 1 px on >= 95 % of the pixels where the cpu found a disparity, and, as the
// opencl kernels, the same pixels found (the speckle filter on the device gives OpenCV's answer),
// with the share identical for the record.
TEST(DisparityCuda, GivesTheCpusDisparity) {
  if (const std::string why = without_cuda(); !why.empty()) GTEST_SKIP() << why;
  const auto results = device_disparity_agreement("cuda");
  EXPECT_EQ(results.size(), 4u);
  for (const DisparityAgreement& d : results) {
    EXPECT_GE(d.within, d.valid - d.valid / 20);
    EXPECT_LE(d.validity_differs, d.pixels / 1000);
    std::cout << "[          ] disparity: " << d.identical << " of " << d.valid
              << " valid pixels identical, validity differs at " << d.validity_differs << "\n";
  }
}

// As the opencl kernels, the last row of an odd height pre-filtered to the cap, as OpenCV does.
TEST(DisparityCuda, GivesTheCpusDisparityAtAnOddHeight) {
  if (const std::string why = without_cuda(); !why.empty()) GTEST_SKIP() << why;
  expect_cpus_disparity_at_an_odd_height("cuda");
}

// The pair is written as mono8 straight into the memory the device uploads from, the left image
// going up while the right one is written: an rgb8 pair (converted there) and its mono8 twin
// (copied there) give the same disparity, the cpu's own for the twin.
TEST(DisparityCuda, GivesAMono8PairTheDisparityOfItsRgb8Twin) {
  if (const std::string why = without_cuda(); !why.empty()) GTEST_SKIP() << why;
  SyntheticStereoConfig config;
  config.width = 160;
  config.height = 120;
  config.frames = 1;
  const StereoFrame frame = generate_stereo_sequence(config).front();
  ASSERT_EQ(frame.left.encoding, "rgb8");
  msgs::Image left_mono = frame.left, right_mono = frame.right;
  cv::Mat grey;
  to_mono8(frame.left, "left", grey);
  grey.copyTo(prepare_image(left_mono, frame.left.header, "mono8", 160, 120));
  to_mono8(frame.right, "right", grey);
  grey.copyTo(prepare_image(right_mono, frame.right.header, "mono8", 160, 120));
  StereoParams params;
  params.disparity_range = 32;
  DisparityProcessor device(params, "cuda");
  msgs::DisparityImage from_rgb, from_mono;
  // The twin first: its pixels are not in that memory already.
  device.compute(left_mono, right_mono, frame.left_info, frame.right_info, from_mono);
  device.compute(frame.left, frame.right, frame.left_info, frame.right_info, from_rgb);
  EXPECT_EQ(from_mono.image.data, from_rgb.image.data);
  // A right image it cannot convert is refused in one line once the left one went up, and the
  // next pair is computed as before.
  msgs::Image unconvertible = frame.right;
  unconvertible.encoding = "8UC3";
  msgs::DisparityImage refused, again;
  try {
    device.compute(frame.left, unconvertible, frame.left_info, frame.right_info, refused);
    ADD_FAILURE() << "an 8UC3 right image was matched";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("disparity: right image encoding '8UC3'"),
              std::string::npos)
        << e.what();
  }
  device.compute(frame.left, frame.right, frame.left_info, frame.right_info, again);
  EXPECT_EQ(again.image.data, from_rgb.image.data);
  msgs::DisparityImage on_cpu;
  DisparityProcessor(params).compute(left_mono, right_mono, frame.left_info, frame.right_info,
                                     on_cpu);
  const cv::Mat cpu = image_view(on_cpu.image), cuda = image_view(from_mono.image);
  EXPECT_GT(cv::countNonZero(cpu > 0), 160 * 120 / 4);
  EXPECT_GE(cv::countNonZero(cv::abs(cpu - cuda) <= 1.0), 160 * 120 * 95 / 100);
}

// Refused whatever the machine: the parameters are checked before the device is asked for.
TEST(DisparityCuda, HasStereoBmWithoutNegativeDisparitiesOnly) {
  StereoParams sgbm;
  sgbm.algorithm = StereoAlgorithm::kSemiGlobal;
  StereoParams negative;
  negative.min_disparity = -4;
  for (const auto& [params, named] : {std::pair{sgbm, "StereoSGBM"}, {negative, "min_disparity"}}) {
    try {
      DisparityProcessor(params, "cuda");
      ADD_FAILURE() << named << " was accepted on cuda";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(named), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("cuda"), std::string::npos) << e.what();
    }
  }
}

// A block takes its tile's windows into shared memory: a window and range too wide for it are
// refused in one line, whatever the machine, where the backend is built.
TEST(DisparityCuda, RefusesAWindowAndRangeItsTilesCannotHold) {
  if (!cuda_backend_built()) GTEST_SKIP() << "this robotperf is built without CUDA";
  StereoParams wide;
  wide.correlation_window_size = 121;
  wide.disparity_range = 256;
  try {
    DisparityProcessor(wide, "cuda");
    ADD_FAILURE() << "a window of 121 px with 256 disparities was accepted on cuda";
  } catch (const std::invalid_argument& e) {
    const std::string line = e.what();
    EXPECT_NE(line.find("shared memory"), std::string::npos) << line;
    EXPECT_NE(line.find("121 px"), std::string::npos) << line;
    EXPECT_EQ(line.find('\n'), std::string::npos) << line;
  }
  StereoParams a3_like;
  a3_like.correlation_window_size = 15;
  a3_like.disparity_range = 64;
  if (without_cuda().empty()) {
    EXPECT_NO_THROW(DisparityProcessor(a3_like, "cuda"));
  }
}

TEST(DisparityCuda, WithoutItsBuildOrDeviceIsOneLine) {
  if (without_cuda().empty()) GTEST_SKIP() << "a CUDA device is there: " << cuda_device().name;
  expect_cuda_missing_line([] { DisparityProcessor({}, "cuda"); }, "DisparityProcessor");
}

}  // namespace
}  // namespace robotperf::perception
