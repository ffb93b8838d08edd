#include "robotperf/perception/image_proc.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <iostream>
#include <memory>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <stdexcept>
#include <utility>
#include <vector>

#include "../command_line.hpp"
#include "cuda_test_support.hpp"
#include "robotperf/harness/backend_check.hpp"
#include "robotperf/perception/camera_model.hpp"
#include "robotperf/perception/opencl_device.hpp"
#include "robotperf/perception/synthetic_camera.hpp"

namespace robotperf::perception {
namespace {

using perception::CameraFrame;
using perception::kCheckerTilePx;
using perception::SyntheticCameraConfig;

msgs::Image make_image(const std::string& encoding, uint32_t width, uint32_t height,
                       uint32_t bytes_per_pixel) {
  msgs::Image image;
  image.header.frame_id = "cam";
  image.header.stamp = msgs::Time{12, 345};
  image.encoding = encoding;
  image.width = width;
  image.height = height;
  image.step = width * bytes_per_pixel;
  image.data.resize(size_t{image.step} * height);
  for (size_t i = 0; i < image.data.size(); ++i) image.data[i] = static_cast<uint8_t>(i * 7);
  return image;
}

cv::Mat to_gray(const msgs::Image& rgb) {
  cv::Mat gray;
  cv::cvtColor(image_view(rgb), gray, cv::COLOR_RGB2GRAY);
  return gray;
}

// Sub-pixel corner position found by cv::cornerSubPix starting from `guess`.
cv::Point2f refine_corner(const cv::Mat& gray, cv::Point2f guess) {
  std::vector<cv::Point2f> corners{guess};
  cv::cornerSubPix(gray, corners, cv::Size(6, 6), cv::Size(-1, -1),
                   cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 50, 1e-3));
  return corners[0];
}

// Checkerboard corners (ideal pixel coordinates) near the image border, where the lens moves
// them most, and away from the box in frame 0.
std::vector<cv::Point2f> border_corners() {
  std::vector<cv::Point2f> corners;
  for (const int i : {2, 4, 12, 14}) {
    for (const int j : {2, 10}) {
      corners.emplace_back(kCheckerTilePx * i - 0.5f, kCheckerTilePx * j - 0.5f);
    }
  }
  return corners;
}

// ---------------------------------------------------------------------------------------------
// Encodings and views
// ---------------------------------------------------------------------------------------------

TEST(ImageEncodings, MapsRosEncodingsToOpenCvTypes) {
  EXPECT_EQ(cv_type_from_encoding("rgb8"), CV_8UC3);
  EXPECT_EQ(cv_type_from_encoding("bgr8"), CV_8UC3);
  EXPECT_EQ(cv_type_from_encoding("rgba8"), CV_8UC4);
  EXPECT_EQ(cv_type_from_encoding("bgra8"), CV_8UC4);
  EXPECT_EQ(cv_type_from_encoding("mono8"), CV_8UC1);
  EXPECT_EQ(cv_type_from_encoding("mono16"), CV_16UC1);
  EXPECT_EQ(cv_type_from_encoding("16UC1"), CV_16UC1);
  EXPECT_EQ(cv_type_from_encoding("32FC1"), CV_32FC1);
  EXPECT_EQ(cv_type_from_encoding("8UC3"), CV_8UC3);
  EXPECT_EQ(cv_type_from_encoding("64FC2"), CV_64FC2);
  EXPECT_EQ(cv_type_from_encoding("bayer_rggb8"), CV_8UC1);
  EXPECT_EQ(cv_type_from_encoding("bayer_grbg16"), CV_16UC1);
  EXPECT_EQ(cv_type_from_encoding("yuv422"), CV_8UC2);
  for (const char* bad : {"", "rgb", "jpeg", "32FC", "32FC0", "12UC1", "8UC1x", "bayer_rggb12"}) {
    EXPECT_THROW(cv_type_from_encoding(bad), std::invalid_argument) << bad;
  }
}

TEST(ImageView, IsZeroCopyAndHonoursStep) {
  msgs::Image image = make_image("mono8", 5, 3, 1);
  image.step = 8;  // padded rows
  image.data.assign(24, 0);
  image.data[8 + 2] = 42;
  cv::Mat view = image_view(image);
  EXPECT_EQ(view.data, image.data.data());
  EXPECT_EQ(view.cols, 5);
  EXPECT_EQ(view.rows, 3);
  EXPECT_EQ(view.step[0], 8u);
  EXPECT_EQ(view.at<uint8_t>(1, 2), 42);
  view.at<uint8_t>(2, 4) = 9;
  EXPECT_EQ(image.data[16 + 4], 9);
}

TEST(ImageView, RejectsInconsistentImages) {
  const msgs::Image good = make_image("rgb8", 4, 2, 3);
  EXPECT_NO_THROW(image_view(good));

  msgs::Image short_data = good;
  short_data.data.pop_back();
  EXPECT_THROW(image_view(short_data), std::invalid_argument);

  msgs::Image long_data = good;
  long_data.data.push_back(0);
  EXPECT_THROW(image_view(long_data), std::invalid_argument);

  msgs::Image short_step = good;
  short_step.step = 11;
  short_step.data.resize(22);
  EXPECT_THROW(image_view(short_step), std::invalid_argument);

  msgs::Image unknown = good;
  unknown.encoding = "rgb9";
  EXPECT_THROW(image_view(unknown), std::invalid_argument);

  msgs::Image misaligned = make_image("32FC1", 2, 2, 4);
  misaligned.step = 10;
  misaligned.data.resize(20);
  EXPECT_THROW(image_view(misaligned), std::invalid_argument);

  msgs::Image big_endian = make_image("mono16", 2, 2, 2);
  big_endian.is_bigendian = 1;
  EXPECT_THROW(image_view(big_endian), std::invalid_argument);

  msgs::Image huge = good;
  huge.height = 0x80000000u;  // step * height overflows 32 bits, data is tiny
  EXPECT_THROW(image_view(huge), std::invalid_argument);
}

TEST(ImageView, PrepareImageReusesTheBuffer) {
  msgs::Image image;
  msgs::Header header;
  header.frame_id = "f";
  cv::Mat first = prepare_image(image, header, "32FC1", 16, 8);
  EXPECT_EQ(image.step, 64u);
  EXPECT_EQ(image.data.size(), 512u);
  EXPECT_EQ(image.encoding, "32FC1");
  EXPECT_EQ(image.header.frame_id, "f");
  EXPECT_EQ(first.type(), CV_32FC1);
  const uint8_t* buffer = image.data.data();
  cv::Mat second = prepare_image(image, header, "mono8", 20, 10);
  EXPECT_EQ(image.data.data(), buffer);
  EXPECT_EQ(second.data, buffer);
}

// to_mono8 into memory of the caller's (the cuda backend's pinned upload memory): the same grey
// pixels, written where they were asked for, or one line saying what is wrong.
TEST(Mono8, WriteMono8WritesTheGreyPixelsInPlace) {
  msgs::Image rgb;
  cv::randu(prepare_image(rgb, {}, "rgb8", 7, 5), 0, 256);
  cv::Mat expected;
  to_mono8(rgb, "left", expected);
  std::vector<uint8_t> memory(7 * 5, 0);
  cv::Mat into(5, 7, CV_8UC1, memory.data());
  write_mono8(rgb, "left", into);
  EXPECT_EQ(into.data, memory.data());
  EXPECT_EQ(cv::norm(into, expected, cv::NORM_INF), 0.0);
  EXPECT_GT(cv::countNonZero(into), 0);

  msgs::Image mono;
  cv::randu(prepare_image(mono, {}, "mono8", 7, 5), 1, 256);
  write_mono8(mono, "left", into);
  EXPECT_EQ(into.data, memory.data());
  EXPECT_EQ(std::memcmp(memory.data(), mono.data.data(), memory.size()), 0);
  EXPECT_NE(memory.data(), mono.data.data());
}

TEST(Mono8, WriteMono8RefusesAnotherSizeAndEncodingsWithoutGrey) {
  msgs::Image rgb;
  prepare_image(rgb, {}, "rgb8", 7, 5);
  std::vector<uint8_t> memory(8 * 5, 0);
  cv::Mat wider(5, 8, CV_8UC1, memory.data());
  EXPECT_THROW(write_mono8(rgb, "left", wider), std::logic_error);
  EXPECT_TRUE(std::all_of(memory.begin(), memory.end(), [](uint8_t b) { return b == 0; }));
  msgs::Image depth;
  prepare_image(depth, {}, "32FC1", 8, 5);
  try {
    write_mono8(depth, "disparity: right image", wider);
    ADD_FAILURE() << "a 32FC1 image was written as mono8";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("disparity: right image encoding '32FC1'"),
              std::string::npos)
        << e.what();
  }
}

// ---------------------------------------------------------------------------------------------
// Rectify
// ---------------------------------------------------------------------------------------------

class RectifySynthetic : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    config_ = new SyntheticCameraConfig();
    config_->frames = 10;
    frames_ = new std::vector<CameraFrame>(perception::generate_camera_sequence(*config_));
  }
  static void TearDownTestSuite() {
    delete frames_;
    delete config_;
  }
  static SyntheticCameraConfig* config_;
  static std::vector<CameraFrame>* frames_;
};
SyntheticCameraConfig* RectifySynthetic::config_ = nullptr;
std::vector<CameraFrame>* RectifySynthetic::frames_ = nullptr;

TEST_F(RectifySynthetic, PutsCheckerboardCornersWhereThePinholeModelDoes) {
  const CameraFrame& frame = frames_->front();
  Rectifier rectifier;
  const msgs::Image rectified = rectifier.rectify(frame.image, frame.info);
  const cv::Mat rectified_gray = to_gray(rectified);
  const cv::Mat raw_gray = to_gray(frame.image);

  const cv::Matx33d k(frame.info.k.data());
  const cv::Mat d(frame.info.d);
  for (const cv::Point2f ideal : border_corners()) {
    // Rectified: the corner is where the ideal pinhole camera sees it.
    const cv::Point2f found = refine_corner(rectified_gray, ideal + cv::Point2f(1.5f, -1.5f));
    EXPECT_LT(cv::norm(found - ideal), 0.5) << "ideal " << ideal << " found " << found;

    // Raw: the corner is where the forward lens model puts it, far from the ideal position.
    std::vector<cv::Point3d> ray{
        {(ideal.x - k(0, 2)) / k(0, 0), (ideal.y - k(1, 2)) / k(1, 1), 1.0}};
    std::vector<cv::Point2d> distorted;
    cv::projectPoints(ray, cv::Vec3d::all(0), cv::Vec3d::all(0), k, d, distorted);
    const cv::Point2f expected_raw(distorted[0]);
    EXPECT_GT(cv::norm(expected_raw - ideal), 8.0) << "lens should move " << ideal;
    const cv::Point2f found_raw = refine_corner(raw_gray, expected_raw + cv::Point2f(1.5f, -1.5f));
    EXPECT_LT(cv::norm(found_raw - expected_raw), 0.5)
        << "expected " << expected_raw << " found " << found_raw;
  }
}

TEST_F(RectifySynthetic, MatchesTheIdealRenderInTheInterior) {
  Rectifier rectifier;
  for (const uint32_t index : {0u, 9u}) {
    const CameraFrame& frame = (*frames_)[index];
    const msgs::Image rectified = rectifier.rectify(frame.image, frame.info);
    const msgs::Image ideal = perception::render_ideal_camera_frame(*config_, index);
    const cv::Rect interior(8, 8, 640 - 16, 480 - 16);
    const double rectified_error =
        cv::norm(image_view(rectified)(interior), image_view(ideal)(interior), cv::NORM_L1) /
        (interior.area() * 3.0);
    const double raw_error =
        cv::norm(image_view(frame.image)(interior), image_view(ideal)(interior), cv::NORM_L1) /
        (interior.area() * 3.0);
    RecordProperty("rectified_vs_ideal_frame" + std::to_string(index),
                   std::to_string(rectified_error));
    RecordProperty("raw_vs_ideal_frame" + std::to_string(index), std::to_string(raw_error));
    EXPECT_LT(rectified_error, 4.0) << "frame " << index;
    EXPECT_GT(raw_error, 5.0 * rectified_error) << "frame " << index;
  }
}

TEST_F(RectifySynthetic, KeepsHeaderEncodingAndSize) {
  const CameraFrame& frame = (*frames_)[3];
  Rectifier rectifier;
  const msgs::Image rectified = rectifier.rectify(frame.image, frame.info);
  EXPECT_EQ(rectified.header, frame.image.header);
  EXPECT_EQ(rectified.encoding, "rgb8");
  EXPECT_EQ(rectified.width, 640u);
  EXPECT_EQ(rectified.height, 480u);
  EXPECT_EQ(rectified.step, 640u * 3);
  EXPECT_NE(rectified.data, frame.image.data);
}

TEST_F(RectifySynthetic, ComputesTheMapOncePerCameraModel) {
  Rectifier rectifier;
  msgs::Image rectified;
  for (const CameraFrame& frame : *frames_) rectifier.rectify(frame.image, frame.info, rectified);
  EXPECT_EQ(rectifier.map_computations(), 1u);

  // A new header (stamp) alone does not invalidate the map.
  msgs::CameraInfo info = frames_->front().info;
  info.header.stamp = msgs::Time{99, 0};
  rectifier.rectify(frames_->front().image, info, rectified);
  EXPECT_EQ(rectifier.map_computations(), 1u);

  info.k[0] += 1.0;
  const msgs::Image changed = rectifier.rectify(frames_->front().image, info);
  EXPECT_EQ(rectifier.map_computations(), 2u);
  EXPECT_NE(changed.data, rectified.data);

  info.d[0] = -0.2;
  rectifier.rectify(frames_->front().image, info, rectified);
  EXPECT_EQ(rectifier.map_computations(), 3u);
  rectifier.rectify(frames_->front().image, info, rectified);
  EXPECT_EQ(rectifier.map_computations(), 3u);
}

TEST_F(RectifySynthetic, ReusesTheOutputBuffer) {
  Rectifier rectifier;
  msgs::Image rectified;
  rectifier.rectify((*frames_)[0].image, (*frames_)[0].info, rectified);
  const uint8_t* buffer = rectified.data.data();
  rectifier.rectify((*frames_)[1].image, (*frames_)[1].info, rectified);
  EXPECT_EQ(rectified.data.data(), buffer);
  EXPECT_EQ(rectified.header.stamp, (*frames_)[1].image.header.stamp);
}

TEST_F(RectifySynthetic, RoiRectifiesTheMatchingPartOfTheFullImage) {
  const CameraFrame& frame = frames_->front();
  Rectifier rectifier;
  const msgs::Image full = rectifier.rectify(frame.image, frame.info);

  // A raw image cropped to the ROI rectifies like the full image inside the ROI, except where
  // the full image's source pixels lie outside the crop.
  const cv::Rect roi(160, 120, 320, 240);
  msgs::CameraInfo info = frame.info;
  info.roi = msgs::RegionOfInterest{160, 120, 240, 320, false};
  msgs::Image cropped;
  image_view(frame.image)(roi).copyTo(prepare_image(cropped, frame.image.header, "rgb8", 320, 240));
  const msgs::Image rectified_crop = rectifier.rectify(cropped, info);
  EXPECT_EQ(rectifier.map_computations(), 1u);
  ASSERT_EQ(rectified_crop.width, 320u);
  const cv::Rect inner(20, 20, 280, 200);
  EXPECT_EQ(cv::norm(image_view(rectified_crop)(inner), image_view(full)(roi)(inner), cv::NORM_INF),
            0.0);

  // The image must have the ROI's size.
  EXPECT_THROW(rectifier.rectify(frame.image, info), std::invalid_argument);
  // A ROI outside the image is rejected.
  info.roi.x_offset = 400;
  EXPECT_THROW(rectifier.rectify(cropped, info), std::invalid_argument);
}

TEST_F(RectifySynthetic, BinningRectifiesAtTheBinnedResolution) {
  const CameraFrame& frame = frames_->front();
  msgs::CameraInfo info = frame.info;
  info.binning_x = 2;
  info.binning_y = 2;
  msgs::Image binned;
  cv::resize(image_view(frame.image), prepare_image(binned, frame.image.header, "rgb8", 320, 240),
             cv::Size(320, 240), 0, 0, cv::INTER_AREA);
  Rectifier rectifier;
  const msgs::Image rectified = rectifier.rectify(binned, info);
  ASSERT_EQ(rectified.width, 320u);
  ASSERT_EQ(rectified.height, 240u);
  // Same geometry at half resolution: a corner lands at half its full-resolution position.
  const cv::Point2f ideal(kCheckerTilePx * 14.0f, kCheckerTilePx * 10.0f);
  const cv::Point2f expected = ideal * 0.5f - cv::Point2f(0.5f, 0.5f);
  const cv::Point2f found = refine_corner(to_gray(rectified), expected + cv::Point2f(1, 1));
  EXPECT_LT(cv::norm(found - expected), 0.5) << found;
  EXPECT_THROW(rectifier.rectify(frame.image, info), std::invalid_argument);
}

TEST_F(RectifySynthetic, WorksOnMono8AndFloatImages) {
  const CameraFrame& frame = frames_->front();
  Rectifier rectifier;
  const msgs::Image rgb_rectified = rectifier.rectify(frame.image, frame.info);

  msgs::Image mono;
  cv::cvtColor(image_view(frame.image), prepare_image(mono, frame.image.header, "mono8", 640, 480),
               cv::COLOR_RGB2GRAY);
  const msgs::Image mono_rectified = rectifier.rectify(mono, frame.info);
  EXPECT_EQ(mono_rectified.encoding, "mono8");
  EXPECT_LE(cv::norm(image_view(mono_rectified), to_gray(rgb_rectified), cv::NORM_INF), 2.0);

  msgs::Image depth;
  image_view(mono).convertTo(prepare_image(depth, frame.image.header, "32FC1", 640, 480), CV_32F,
                             1.0 / 255.0);
  const msgs::Image depth_rectified = rectifier.rectify(depth, frame.info);
  EXPECT_EQ(depth_rectified.encoding, "32FC1");
  const cv::Mat depth_view = image_view(depth_rectified);
  const cv::Mat mono_view = image_view(mono_rectified);
  EXPECT_NEAR(depth_view.at<float>(240, 320) * 255.0f, mono_view.at<uint8_t>(240, 320), 1.0);
  EXPECT_EQ(rectifier.map_computations(), 1u);
}

TEST(Rectify, FloatImagesGetNanOutsideTheFieldOfView) {
  // Strong pincushion distortion: the rectified corners see outside the raw image.
  const msgs::CameraInfo info =
      make_pinhole_camera_info(64, 48, 1.2, {0.6, 0.3, 0.0, 0.0, 0.0}, "cam");
  msgs::Image depth;
  prepare_image(depth, info.header, "32FC1", 64, 48).setTo(2.0f);
  Rectifier rectifier;
  const msgs::Image rectified = rectifier.rectify(depth, info);
  const cv::Mat view = image_view(rectified);
  EXPECT_TRUE(std::isnan(view.at<float>(0, 0)));
  EXPECT_FLOAT_EQ(view.at<float>(24, 32), 2.0f);

  msgs::Image mono;
  prepare_image(mono, info.header, "mono8", 64, 48).setTo(200);
  EXPECT_EQ(image_view(rectifier.rectify(mono, info)).at<uint8_t>(0, 0), 0);
}

TEST(Rectify, PassesThroughWhenDistortionIsZero) {
  const msgs::Image image = make_image("rgb8", 64, 48, 3);
  msgs::CameraInfo info = make_pinhole_camera_info(64, 48, 1.0, {0, 0, 0, 0, 0}, "cam");
  // image_proc passes through on zero D alone, even with a rectifying R.
  info.r = {0.9, 0.1, 0, -0.1, 0.9, 0, 0, 0, 1};
  Rectifier rectifier;
  EXPECT_EQ(rectifier.rectify(image, info), image);
  info.d.clear();
  EXPECT_EQ(rectifier.rectify(image, info), image);
  EXPECT_EQ(rectifier.map_computations(), 0u);
}

TEST(Rectify, RejectsBadInput) {
  const msgs::Image image = make_image("rgb8", 64, 48, 3);
  const msgs::CameraInfo info = make_pinhole_camera_info(64, 48, 1.0, {-0.2, 0.05, 0, 0, 0}, "cam");
  Rectifier rectifier;
  EXPECT_NO_THROW(rectifier.rectify(image, info));

  msgs::CameraInfo uncalibrated = info;
  uncalibrated.k[0] = 0.0;
  EXPECT_THROW(rectifier.rectify(image, uncalibrated), std::invalid_argument);

  msgs::CameraInfo unknown_model = info;
  unknown_model.distortion_model = "fancy";
  EXPECT_THROW(rectifier.rectify(image, unknown_model), std::invalid_argument);

  msgs::CameraInfo wrong_d_size = info;
  wrong_d_size.distortion_model = std::string(kRationalPolynomial);
  EXPECT_THROW(rectifier.rectify(image, wrong_d_size), std::invalid_argument);

  msgs::Image short_data = image;
  short_data.data.resize(100);
  EXPECT_THROW(rectifier.rectify(short_data, info), std::invalid_argument);

  msgs::Image unknown_encoding = image;
  unknown_encoding.encoding = "hsv8";
  EXPECT_THROW(rectifier.rectify(unknown_encoding, info), std::invalid_argument);

  msgs::Image wrong_size = make_image("rgb8", 32, 48, 3);
  EXPECT_THROW(rectifier.rectify(wrong_size, info), std::invalid_argument);

  msgs::Image in_place = image;
  EXPECT_THROW(rectifier.rectify(in_place, info, in_place), std::invalid_argument);

  EXPECT_THROW(Rectifier(7), std::invalid_argument);
}

TEST(Rectify, RationalPolynomialUsesAllEightCoefficients) {
  const msgs::Image image = make_image("mono8", 64, 48, 1);
  msgs::CameraInfo info = make_pinhole_camera_info(64, 48, 1.0, {-0.2, 0.05, 0, 0, 0, 0, 0, 0},
                                                   "cam", kRationalPolynomial);
  Rectifier rectifier;
  const msgs::Image without_k4 = rectifier.rectify(image, info);
  info.d[5] = 0.3;  // k4, in the denominator
  const msgs::Image with_k4 = rectifier.rectify(image, info);
  EXPECT_EQ(rectifier.map_computations(), 2u);
  EXPECT_NE(without_k4.data, with_k4.data);
}

// ---------------------------------------------------------------------------------------------
// Resize
// ---------------------------------------------------------------------------------------------

msgs::CameraInfo make_stereo_right_info() {
  msgs::CameraInfo info =
      make_pinhole_camera_info(640, 480, 1.047, {-0.25, 0.12, -0.00028, -5e-5, 0}, "cam");
  info.k = {500.0, 0.0, 321.5, 0.0, 502.0, 239.25, 0.0, 0.0, 1.0};
  info.p = {510.0, 0.0, 322.0, -51.0, 0.0, 511.0, 241.0, 7.0, 0.0, 0.0, 1.0, 0.0};
  info.roi = msgs::RegionOfInterest{10, 20, 300, 400, true};
  return info;
}

TEST(Resize, ScalesImageAndCameraInfoByTwo) {
  const msgs::Image image = make_image("rgb8", 640, 480, 3);
  const msgs::CameraInfo info = make_stereo_right_info();
  ResizeParams params;
  params.scale_width = 2.0;
  params.scale_height = 2.0;
  msgs::Image out;
  msgs::CameraInfo out_info;
  resize(image, info, params, out, out_info);

  EXPECT_EQ(out.width, 1280u);
  EXPECT_EQ(out.height, 960u);
  EXPECT_EQ(out.step, 1280u * 3);
  EXPECT_EQ(out.data.size(), 1280u * 960 * 3);
  EXPECT_EQ(out.header, image.header);
  EXPECT_EQ(out.encoding, "rgb8");
  cv::Mat expected;
  cv::resize(image_view(image), expected, cv::Size(1280, 960), 0, 0, cv::INTER_LINEAR);
  EXPECT_EQ(cv::norm(image_view(out), expected, cv::NORM_INF), 0.0);

  EXPECT_EQ(out_info.width, 1280u);
  EXPECT_EQ(out_info.height, 960u);
  const std::array<double, 9> k{1000.0, 0.0, 643.0, 0.0, 1004.0, 478.5, 0.0, 0.0, 1.0};
  EXPECT_EQ(out_info.k, k);
  // P[7] (Ty) is not scaled by image_proc.
  const std::array<double, 12> p{1020.0, 0.0, 644.0, -102.0, 0.0, 1022.0,
                                 482.0,  7.0, 0.0,   0.0,    1.0, 0.0};
  EXPECT_EQ(out_info.p, p);
  EXPECT_EQ(out_info.roi, (msgs::RegionOfInterest{20, 40, 600, 800, true}));
  EXPECT_EQ(out_info.d, info.d);
  EXPECT_EQ(out_info.r, info.r);
  EXPECT_EQ(out_info.header, info.header);
  EXPECT_EQ(out_info.distortion_model, info.distortion_model);
}

TEST(Resize, ExplicitSizeWithoutScale) {
  const msgs::Image image = make_image("mono8", 640, 480, 1);
  const msgs::CameraInfo info = make_stereo_right_info();
  ResizeParams params;
  params.use_scale = false;
  params.width = 320;
  params.height = 360;
  params.interpolation = cv::INTER_NEAREST;
  msgs::Image out;
  msgs::CameraInfo out_info;
  resize(image, info, params, out, out_info);
  EXPECT_EQ(out.width, 320u);
  EXPECT_EQ(out.height, 360u);
  EXPECT_EQ(out.step, 320u);
  cv::Mat expected;
  cv::resize(image_view(image), expected, cv::Size(320, 360), 0, 0, cv::INTER_NEAREST);
  EXPECT_EQ(cv::norm(image_view(out), expected, cv::NORM_INF), 0.0);
  EXPECT_EQ(out_info.width, 320u);
  EXPECT_EQ(out_info.height, 360u);
  EXPECT_DOUBLE_EQ(out_info.k[0], 250.0);
  EXPECT_DOUBLE_EQ(out_info.k[4], 502.0 * 0.75);
  EXPECT_DOUBLE_EQ(out_info.p[3], -25.5);
  EXPECT_EQ(out_info.roi, (msgs::RegionOfInterest{5, 15, 225, 200, true}));

  // -1 keeps that dimension.
  params.width = -1;
  resize(image, info, params, out, out_info);
  EXPECT_EQ(out.width, 640u);
  EXPECT_EQ(out.height, 360u);
  EXPECT_EQ(out_info.width, 640u);
  EXPECT_DOUBLE_EQ(out_info.k[0], 500.0);
}

TEST(Resize, HandlesFloatAndFractionalScales) {
  msgs::Image image;
  cv::Mat view = prepare_image(image, msgs::Header{}, "32FC1", 101, 53);
  cv::randu(view, 0.0, 10.0);
  const msgs::CameraInfo info = make_pinhole_camera_info(101, 53, 1.0, {0, 0, 0, 0, 0}, "cam");
  ResizeParams params;
  params.scale_width = 0.55;
  params.scale_height = 1.5;
  msgs::Image out;
  msgs::CameraInfo out_info;
  resize(image, info, params, out, out_info);
  // cv::resize rounds the image size (55.55 -> 56, 79.5 -> 80, half to even); image_proc
  // truncates the CameraInfo size.
  EXPECT_EQ(out.width, 56u);
  EXPECT_EQ(out.height, 80u);
  EXPECT_EQ(out.encoding, "32FC1");
  EXPECT_EQ(out_info.width, 55u);
  EXPECT_EQ(out_info.height, 79u);
  EXPECT_DOUBLE_EQ(out_info.k[0], info.k[0] * 0.55);
  cv::Mat expected;
  cv::resize(image_view(image), expected, cv::Size(), 0.55, 1.5, cv::INTER_LINEAR);
  EXPECT_EQ(cv::norm(image_view(out), expected, cv::NORM_INF), 0.0);
}

TEST(Resize, ReusesOutputBuffersAndAllowsInfoInPlace) {
  const msgs::Image image = make_image("rgb8", 64, 48, 3);
  msgs::CameraInfo info = make_pinhole_camera_info(64, 48, 1.0, {0, 0, 0, 0, 0}, "cam");
  const double fx = info.k[0];
  ResizeParams params;
  params.scale_width = 2.0;
  params.scale_height = 2.0;
  msgs::Image out;
  resize(image, info, params, out, info);
  const uint8_t* buffer = out.data.data();
  EXPECT_DOUBLE_EQ(info.k[0], 2.0 * fx);
  EXPECT_EQ(info.width, 128u);
  info.width = 64;
  info.height = 48;
  resize(image, info, params, out, info);
  EXPECT_EQ(out.data.data(), buffer);
}

TEST(Resize, RejectsBadInput) {
  const msgs::Image image = make_image("rgb8", 64, 48, 3);
  const msgs::CameraInfo info = make_pinhole_camera_info(64, 48, 1.0, {0, 0, 0, 0, 0}, "cam");
  msgs::Image out;
  msgs::CameraInfo out_info;
  ResizeParams params;
  params.scale_width = 0.0;
  EXPECT_THROW(resize(image, info, params, out, out_info), std::invalid_argument);
  params = ResizeParams{};
  params.use_scale = false;
  params.width = 0;
  EXPECT_THROW(resize(image, info, params, out, out_info), std::invalid_argument);
  params = ResizeParams{};
  params.interpolation = 9;
  EXPECT_THROW(resize(image, info, params, out, out_info), std::invalid_argument);

  msgs::Image short_data = image;
  short_data.data.resize(10);
  EXPECT_THROW(resize(short_data, info, ResizeParams{}, out, out_info), std::invalid_argument);
  msgs::Image unknown = image;
  unknown.encoding = "cmyk8";
  EXPECT_THROW(resize(unknown, info, ResizeParams{}, out, out_info), std::invalid_argument);
  msgs::Image same = image;
  EXPECT_THROW(resize(same, info, ResizeParams{}, same, out_info), std::invalid_argument);
}

// ---------------------------------------------------------------------------------------------
// The OpenCL backend: the CPU's answer on the same inputs (docs/design.md §6)
// ---------------------------------------------------------------------------------------------

// How a backend's image agrees with the cpu's: the share of channels the run's own backend check
// accepts (harness::compare_answers) against the share it requires, and the share identical (a
// NaN matching a NaN).
struct Agreement {
  double accepted = 0.0;
  double required = 1.0;
  double identical = 0.0;
};

Agreement agreement(const msgs::Image& got, const msgs::Image& cpu) {
  const auto checked =
      harness::compare_answers(std::string(msgs::MessageTraits<msgs::Image>::ros_type), &got, &cpu);
  cv::Mat x, y;
  image_view(got).convertTo(x, CV_64F);
  image_view(cpu).convertTo(y, CV_64F);
  x = x.reshape(1, 1);
  y = y.reshape(1, 1);
  std::size_t identical = 0;
  for (int i = 0; i < x.cols; ++i) {
    const double u = x.at<double>(i), v = y.at<double>(i);
    identical += u == v || (std::isnan(u) && std::isnan(v)) ? 1 : 0;
  }
  return {checked->share, checked->required,
          static_cast<double>(identical) / static_cast<double>(x.cols)};
}

// The frame's rgb8 image as `encoding`: bgra8, or its grey as mono8, mono16 or 32FC1 (0..1).
msgs::Image as_encoding(const msgs::Image& rgb, const std::string& encoding) {
  msgs::Image out;
  cv::Mat view = prepare_image(out, rgb.header, encoding, static_cast<int>(rgb.width),
                               static_cast<int>(rgb.height));
  const cv::Mat in = image_view(rgb);
  if (encoding == "bgra8") {
    cv::cvtColor(in, view, cv::COLOR_RGB2BGRA);
    return out;
  }
  cv::Mat grey;
  cv::cvtColor(in, grey, cv::COLOR_RGB2GRAY);
  const double scale = encoding == "mono16" ? 257.0 : (encoding == "32FC1" ? 1.0 / 255 : 1.0);
  grey.convertTo(view, view.type(), scale);
  return out;
}

// The backend's answer against the cpu's: the run's backend check accepts it, and at least
// `identical_share` of the channels are identical (for kernels that claim OpenCV's own
// arithmetic); the share identical is printed for the record.
void expect_the_cpus_answer(const msgs::Image& got, const msgs::Image& expected,
                            const std::string& what, double identical_share = 0.0) {
  EXPECT_EQ(got.header, expected.header) << what;
  EXPECT_EQ(got.encoding, expected.encoding) << what;
  ASSERT_EQ(got.data.size(), expected.data.size()) << what;
  const Agreement a = agreement(got, expected);
  EXPECT_GE(a.accepted, a.required) << what;
  EXPECT_GE(a.identical, identical_share) << what;
  std::cout << "[          ] " << what << ": " << a.identical * 100 << " % of channels identical\n";
}

// The cuda kernels follow OpenCV's CPU arithmetic (integer weights and shifts for 8-bit images,
// float weights in OpenCV's order, no fused multiply-adds): their images are the cpu's.
constexpr double kCudaIdentical = 0.999;

// The reason to skip when this machine has no OpenCL device, else empty.
std::string without_opencl() {
  try {
    opencl_device();
    return "";
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
}

TEST_F(RectifySynthetic, OpenClRectifiesAsTheCpuDoes) {
  if (const std::string why = without_opencl(); !why.empty()) GTEST_SKIP() << why;
  Rectifier cpu, device(cv::INTER_LINEAR, "opencl");
  for (const uint32_t index : {0u, 5u, 9u}) {
    const CameraFrame& frame = (*frames_)[index];
    for (const std::string encoding : {"rgb8", "mono16", "32FC1"}) {
      const msgs::Image raw = encoding == "rgb8" ? frame.image : as_encoding(frame.image, encoding);
      expect_the_cpus_answer(device.rectify(raw, frame.info), cpu.rectify(raw, frame.info),
                             "rectify frame " + std::to_string(index) + " " + encoding);
    }
  }
  EXPECT_EQ(device.map_computations(), 1u) << "the device keeps the map of one camera model";
}

TEST_F(RectifySynthetic, OpenClResizesAsTheCpuDoes) {
  if (const std::string why = without_opencl(); !why.empty()) GTEST_SKIP() << why;
  const CameraFrame& frame = frames_->front();
  for (const double scale : {0.5, 0.37, 2.0}) {
    ResizeParams p;
    p.scale_width = p.scale_height = scale;
    for (const std::string encoding : {"rgb8", "mono16", "32FC1"}) {
      const msgs::Image image =
          encoding == "rgb8" ? frame.image : as_encoding(frame.image, encoding);
      msgs::Image expected, got;
      msgs::CameraInfo expected_info, got_info;
      resize(image, frame.info, p, expected, expected_info);
      resize(image, frame.info, p, got, got_info, "opencl");
      ASSERT_EQ(got.width, expected.width);
      ASSERT_EQ(got.height, expected.height);
      EXPECT_EQ(got_info.k, expected_info.k);
      expect_the_cpus_answer(got, expected,
                             "resize scale " + std::to_string(scale) + " " + encoding);
    }
  }
}

#ifdef OPENCL_DEVICE_PROBE
// OPENCV_OPENCL_DEVICE set to what matches no device, on any machine: the one line names the
// variable and its value, not a driver to install. In a process of its own, as OpenCV reads the
// variable once per process.
TEST(OpenClDevice, AChoiceThatMatchesNoDeviceIsNamedInTheLine) {
  const std::string choice = "robotperf-no-such-platform:GPU:";
  const test_support::Outcome o =
      test_support::shell("OPENCV_OPENCL_DEVICE='" + choice + "' " + OPENCL_DEVICE_PROBE);
  EXPECT_EQ(o.exit_code, 2) << o.out;
  const std::size_t at = o.out.find("the opencl backend has no OpenCL device");
  ASSERT_NE(at, std::string::npos) << o.out;
  const std::string line = o.out.substr(at, o.out.find('\n', at) - at);
  EXPECT_NE(line.find("OPENCV_OPENCL_DEVICE='" + choice + "'"), std::string::npos) << line;
  EXPECT_EQ(line.find("install"), std::string::npos) << line;
}

// A kernel built on the opencl backend without a node (as a plug-in may) asks for its device
// too: without one it is refused in the same line, not run wherever OpenCV falls back to.
TEST(OpenClDevice, AKernelBuiltWithoutANodeNeedsTheDevice) {
  for (const char* kernel : {"rectifier", "resizer", "disparity", "point_cloud"}) {
    const test_support::Outcome o =
        test_support::shell(std::string("OPENCV_OPENCL_DEVICE='robotperf-no-such-platform:GPU:' ") +
                            OPENCL_DEVICE_PROBE + " " + kernel);
    EXPECT_EQ(o.exit_code, 2) << kernel << ": " << o.out;
    EXPECT_NE(o.out.find("the opencl backend has no OpenCL device"), std::string::npos)
        << kernel << ": " << o.out;
  }
}
#endif

// OpenCV's OpenCL remap computes INTER_NEAREST and INTER_LINEAR, its resize those and INTER_AREA
// to shrink; it hands any other interpolation to the CPU without saying. The opencl backend
// refuses those when it is built, in one line naming the interpolation, whatever the machine.
TEST(ImageBackend, OpenClHasTheInterpolationsOpenCvsOpenClKernelsCompute) {
  const auto expect_refused = [](const std::function<void()>& make, const std::string& named) {
    try {
      make();
      ADD_FAILURE() << named << " was accepted on opencl";
    } catch (const std::invalid_argument& e) {
      const std::string line = e.what();
      EXPECT_NE(line.find(named), std::string::npos) << line;
      EXPECT_NE(line.find("opencl"), std::string::npos) << line;
      EXPECT_EQ(line.find('\n'), std::string::npos) << line;
    }
  };
  for (const int interpolation : {cv::INTER_CUBIC, cv::INTER_AREA, cv::INTER_LANCZOS4}) {
    expect_refused([&] { Rectifier(interpolation, "opencl"); },
                   "interpolation " + std::to_string(interpolation));
  }
  for (const int interpolation : {cv::INTER_CUBIC, cv::INTER_LANCZOS4}) {
    ResizeParams params;
    params.interpolation = interpolation;
    expect_refused([&] { Resizer(params, "opencl"); },
                   "interpolation " + std::to_string(interpolation));
  }
  ResizeParams area;
  area.interpolation = cv::INTER_AREA;
  area.scale_width = 2.0;
  expect_refused([&] { Resizer(area, "opencl"); }, "interpolation 3 (INTER_AREA)");
  EXPECT_THROW(Rectifier(cv::INTER_CUBIC, "opencl"), std::invalid_argument);
  ResizeParams lanczos;
  lanczos.interpolation = cv::INTER_LANCZOS4;
  EXPECT_THROW(Resizer(lanczos, "opencl"), std::invalid_argument);

  for (const int interpolation : {cv::INTER_NEAREST, cv::INTER_LINEAR}) {
    EXPECT_NO_THROW(Rectifier(interpolation, "opencl"));
    ResizeParams params;
    params.interpolation = interpolation;
    params.scale_width = params.scale_height = 2.0;
    EXPECT_NO_THROW(Resizer(params, "opencl"));
  }
  area.scale_width = area.scale_height = 0.5;
  EXPECT_NO_THROW(Resizer(area, "opencl"));
}

// What OpenCV's OpenCL remap and resize would compute on the CPU is refused image by image (the
// node skips it, saying why), never timed as opencl: doubles, more than 4 channels, a resize of
// an image of 10 px or less either way, INTER_AREA enlarging to a given size. An image just over
// those limits is computed, as the cpu computes it.
TEST_F(RectifySynthetic, OpenClRefusesTheImagesOpenCvWouldComputeOnTheCpu) {
  // The device is chosen before the first OpenCL work (making a processor on opencl does so), else
  // OpenCV settles on its default, GPUs only; the refusals need none.
  const std::string without_device = without_opencl();
  const CameraFrame& frame = frames_->front();
  const auto expect_refused = [](const std::function<void()>& compute, const std::string& named) {
    try {
      compute();
      ADD_FAILURE() << named << " was computed on opencl";
    } catch (const std::invalid_argument& e) {
      const std::string line = e.what();
      EXPECT_NE(line.find(named), std::string::npos) << line;
      EXPECT_NE(line.find("opencl"), std::string::npos) << line;
      EXPECT_EQ(line.find('\n'), std::string::npos) << line;
    }
  };
  msgs::Image doubles;
  image_view(as_encoding(frame.image, "32FC1"))
      .convertTo(prepare_image(doubles, frame.image.header, "64FC1", 640, 480), CV_64F);
  const msgs::Image five_channels = make_image("8UC5", 640, 480, 5);
  Rectifier rectifier(cv::INTER_LINEAR, "opencl");
  Resizer resizer(ResizeParams{}, "opencl");
  for (const msgs::Image* image : {&std::as_const(doubles), &five_channels}) {
    msgs::Image out;
    msgs::CameraInfo out_info;
    expect_refused([&] { rectifier.rectify(*image, frame.info, out); },
                   "rectify: encoding '" + image->encoding + "'");
    expect_refused([&] { resizer.resize(*image, frame.info, out, out_info); },
                   "resize: encoding '" + image->encoding + "'");
  }

  ResizeParams twice;
  twice.scale_width = twice.scale_height = 2.0;
  Resizer enlarging(twice, "opencl");
  ResizeParams area_to_size;
  area_to_size.interpolation = cv::INTER_AREA;
  area_to_size.use_scale = false;
  area_to_size.width = 20;
  area_to_size.height = 12;
  Resizer area(area_to_size, "opencl");
  msgs::CameraInfo small_info = make_pinhole_camera_info(10, 30, 1.0, {}, "cam");
  for (const auto& [width, height] : {std::pair{10u, 30u}, {30u, 10u}}) {
    small_info.width = width;
    small_info.height = height;
    const msgs::Image small = make_image("rgb8", width, height, 3);
    msgs::Image out;
    msgs::CameraInfo out_info;
    expect_refused([&] { enlarging.resize(small, small_info, out, out_info); },
                   "a " + std::to_string(width) + "x" + std::to_string(height) + " image");
  }
  small_info.width = small_info.height = 11;
  const msgs::Image eleven = make_image("rgb8", 11, 11, 3);
  msgs::Image out;
  msgs::CameraInfo out_info;
  expect_refused([&] { area.resize(eleven, small_info, out, out_info); },
                 "INTER_AREA) enlarging 11x11 to 20x12");

  if (!without_device.empty()) GTEST_SKIP() << without_device;
  msgs::Image expected;
  msgs::CameraInfo expected_info;
  enlarging.resize(eleven, small_info, out, out_info);
  resize(eleven, small_info, twice, expected, expected_info);
  expect_the_cpus_answer(out, expected, "resize 11x11 to 22x22");
  area_to_size.width = area_to_size.height = 10;
  Resizer(area_to_size, "opencl").resize(eleven, small_info, out, out_info);
  resize(eleven, small_info, area_to_size, expected, expected_info);
  expect_the_cpus_answer(out, expected, "INTER_AREA 11x11 to 10x10");
}

// ---------------------------------------------------------------------------------------------
// The cuda backend: the CPU's answer on the same inputs (docs/design.md §6)
// ---------------------------------------------------------------------------------------------

TEST_F(RectifySynthetic, CudaRectifiesAsTheCpuDoes) {
  if (const std::string why = without_cuda(); !why.empty()) GTEST_SKIP() << why;
  Rectifier cpu, device(cv::INTER_LINEAR, "cuda");
  for (const uint32_t index : {0u, 5u, 9u}) {
    const CameraFrame& frame = (*frames_)[index];
    for (const std::string encoding : {"rgb8", "bgra8", "mono8", "mono16", "32FC1"}) {
      const msgs::Image raw = encoding == "rgb8" ? frame.image : as_encoding(frame.image, encoding);
      expect_the_cpus_answer(device.rectify(raw, frame.info), cpu.rectify(raw, frame.info),
                             "rectify frame " + std::to_string(index) + " " + encoding,
                             kCudaIdentical);
    }
  }
  EXPECT_EQ(device.map_computations(), 1u) << "the device keeps the map of one camera model";
}

TEST_F(RectifySynthetic, CudaResizesAsTheCpuDoes) {
  if (const std::string why = without_cuda(); !why.empty()) GTEST_SKIP() << why;
  const CameraFrame& frame = frames_->front();
  ResizeParams to_size;
  to_size.use_scale = false;
  to_size.width = 500;
  to_size.height = 300;
  std::vector<std::pair<std::string, ResizeParams>> cases{{"to 500x300", to_size}};
  for (const double scale : {0.5, 0.37, 2.0, 1.0}) {
    ResizeParams p;
    p.scale_width = p.scale_height = scale;
    cases.emplace_back("scale " + std::to_string(scale), p);
  }
  for (const auto& [name, params] : cases) {
    // One Resizer per geometry, as a node has: its taps are computed once.
    Resizer device(params, "cuda");
    for (const std::string encoding : {"rgb8", "bgra8", "mono8", "mono16", "32FC1"}) {
      const msgs::Image image =
          encoding == "rgb8" ? frame.image : as_encoding(frame.image, encoding);
      msgs::Image expected, got;
      msgs::CameraInfo expected_info, got_info;
      resize(image, frame.info, params, expected, expected_info);
      device.resize(image, frame.info, got, got_info);
      ASSERT_EQ(got.width, expected.width) << name;
      ASSERT_EQ(got.height, expected.height) << name;
      EXPECT_EQ(got_info, expected_info) << name;
      // At exactly half the size OpenCV's INTER_LINEAR is its INTER_AREA, whose 16-bit sums round
      // halves up where the kernel's float weights round them to even: about 1.5 % of mono16's
      // channels differ, by 1.
      const bool cpu_averages = encoding == "mono16" && params.use_scale &&
                                params.scale_width == 0.5 && params.scale_height == 0.5;
      expect_the_cpus_answer(got, expected, "resize " + name + " " + encoding,
                             cpu_averages ? 0.0 : kCudaIdentical);
    }
  }
}

// A device-resident hand-over (a1 --device-resident): rectify leaves its image on the device,
// resize takes it there, and the answer is the cpu's rectify then resize.
TEST_F(RectifySynthetic, CudaHandsTheRectifiedImageToResizeOnTheDevice) {
  if (const std::string why = without_cuda(); !why.empty()) GTEST_SKIP() << why;
  Rectifier cpu, device(cv::INTER_LINEAR, "cuda");
  ResizeParams twice;
  twice.scale_width = twice.scale_height = 2.0;
  Resizer device_resizer(twice, "cuda");
  for (const uint32_t index : {0u, 7u}) {
    const CameraFrame& frame = (*frames_)[index];
    msgs::Image header_only;
    std::optional<ResidentPixels> pixels =
        device.rectify_on_device(frame.image, frame.info, header_only);
    ASSERT_TRUE(pixels.has_value());
    const std::shared_ptr<const msgs::Image> message =
        resident_image_message(std::move(header_only), std::move(*pixels));
    const msgs::Image on_host = cpu.rectify(frame.image, frame.info);
    EXPECT_TRUE(message->data.empty()) << "the pixels stay on the device";
    EXPECT_EQ(message->header, on_host.header);
    EXPECT_EQ(message->width, on_host.width);
    EXPECT_EQ(message->height, on_host.height);
    EXPECT_EQ(message->step, on_host.step);
    EXPECT_EQ(message->encoding, on_host.encoding);
    // As a subscriber gets it: through the transport's type-erased pointer.
    const auto delivered =
        std::static_pointer_cast<const msgs::Image>(std::shared_ptr<const void>(message));
    const ResidentPixels* found = resident_pixels(delivered);
    ASSERT_NE(found, nullptr);
    msgs::Image got, expected;
    msgs::CameraInfo got_info, expected_info;
    device_resizer.resize(*delivered, frame.info, got, got_info, found);
    resize(on_host, frame.info, twice, expected, expected_info);
    EXPECT_EQ(got_info, expected_info);
    expect_the_cpus_answer(got, expected,
                           "rectify then resize on the device, frame " + std::to_string(index),
                           kCudaIdentical);
  }
  // Where rectifying is a copy, the pixels stay on the host.
  msgs::CameraInfo ideal = (*frames_)[0].info;
  std::fill(ideal.d.begin(), ideal.d.end(), 0.0);
  msgs::Image copied;
  EXPECT_FALSE(device.rectify_on_device((*frames_)[0].image, ideal, copied).has_value());
  EXPECT_EQ(copied.data, (*frames_)[0].image.data);
}

// Only the cuda backend hands images over; an ordinary message has no pixels on a device.
TEST_F(RectifySynthetic, ResidentImagesAreCudasOnly) {
  const CameraFrame& frame = frames_->front();
  Rectifier cpu;
  msgs::Image out;
  EXPECT_THROW(cpu.rectify_on_device(frame.image, frame.info, out), std::logic_error);
  Resizer cpu_resizer{ResizeParams{}};
  ResidentPixels pixels{nullptr, static_cast<int>(frame.image.height),
                        static_cast<int>(frame.image.width), CV_8UC3};
  msgs::CameraInfo out_info;
  EXPECT_THROW(cpu_resizer.resize(frame.image, frame.info, out, out_info, &pixels),
               std::logic_error);
  EXPECT_EQ(resident_pixels(std::make_shared<const msgs::Image>(frame.image)), nullptr);
}

TEST(ImageBackend, CudaHasInterLinearOnly) {
  for (const int interpolation :
       {cv::INTER_NEAREST, cv::INTER_CUBIC, cv::INTER_AREA, cv::INTER_LANCZOS4}) {
    ResizeParams params;
    params.interpolation = interpolation;
    const std::string named = "interpolation " + std::to_string(interpolation);
    for (const auto& make : std::vector<std::function<void()>>{
             [&] { Rectifier(interpolation, "cuda"); }, [&] { Resizer(params, "cuda"); }}) {
      try {
        make();
        ADD_FAILURE() << named << " was accepted on cuda";
      } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find(named), std::string::npos) << e.what();
      }
    }
  }
}

TEST(ImageBackend, CudaWithoutItsBuildOrDeviceIsOneLine) {
  if (without_cuda().empty()) GTEST_SKIP() << "a CUDA device is there: " << cuda_device().name;
  expect_cuda_missing_line([] { cuda_device(); }, "the cuda backend's device");
  expect_cuda_missing_line([] { Rectifier(cv::INTER_LINEAR, "cuda"); }, "Rectifier");
  expect_cuda_missing_line([] { Resizer(ResizeParams{}, "cuda"); }, "Resizer");
  expect_cuda_missing_line([] { cuda_transfer_floor(1024, 1); }, "cuda_transfer_floor");
}

// bench_backends' floor under the cuda rows: each way moves the bytes there and back (it checks
// that itself, and throws), and each takes some time. On the emulation a download that read
// before its wait, or a way that moved nothing, would bring other bytes back.
TEST(CudaTransferFloor, EachWayMovesTheBytesThereAndBack) {
  if (const std::string why = without_cuda(); !why.empty()) GTEST_SKIP() << why;
  const CudaTransferFloor f = cuda_transfer_floor(640 * 480 * 3, 3);
  EXPECT_EQ(f.bytes, 640u * 480u * 3u);
  EXPECT_EQ(f.repetitions, 3);
  for (const double us : {f.pinned_upload_us, f.pinned_download_us, f.staged_upload_us,
                          f.staged_download_us, f.pageable_upload_us, f.pageable_download_us})
    EXPECT_GT(us, 0.0);
  EXPECT_THROW(cuda_transfer_floor(0, 3), std::invalid_argument);
  EXPECT_THROW(cuda_transfer_floor(1024, 0), std::invalid_argument);
}

// Each processor's implementations are found by backend name, cpu first; a name none has is
// refused naming those there are.
TEST(ImageBackend, ImplementationsAreFoundByName) {
  const auto names = [](const auto& table) {
    std::vector<std::string> out;
    for (const auto& i : table) out.emplace_back(i.backend);
    return out;
  };
  const std::vector<std::string> all{"cpu", "opencl", "cuda"};
  EXPECT_EQ(names(rectify_implementations()), all);
  EXPECT_EQ(names(resize_implementations()), all);
  EXPECT_EQ(&implementation_on(rectify_implementations(), "opencl"), &rectify_implementations()[1]);
  EXPECT_EQ(rectify_implementations()[0].device, nullptr);
  if (!cuda_backend_built()) {
    expect_cuda_missing_line([] { Rectifier(cv::INTER_LINEAR, "cuda"); }, "Rectifier on cuda");
  }
  try {
    Rectifier(cv::INTER_LINEAR, "vulkan");
    ADD_FAILURE() << "no vulkan backend, yet a Rectifier was made on it";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "no image backend 'vulkan' (cpu, opencl, cuda)");
  }
}

// ---------------------------------------------------------------------------------------------
// Camera model
// ---------------------------------------------------------------------------------------------

TEST(CameraModel, PinholeFromHorizontalFieldOfView) {
  const msgs::CameraInfo info = make_pinhole_camera_info(
      640, 480, 1.047, {-0.25, 0.12, -0.00028, -5e-5, 0.0}, "camera_optical_frame");
  EXPECT_NEAR(info.k[0], 554.38, 0.01);
  EXPECT_DOUBLE_EQ(info.k[0], 320.0 / std::tan(0.5235));
  EXPECT_DOUBLE_EQ(info.k[4], info.k[0]);
  EXPECT_DOUBLE_EQ(info.k[2], 320.0);
  EXPECT_DOUBLE_EQ(info.k[5], 240.0);
  EXPECT_DOUBLE_EQ(info.k[8], 1.0);
  EXPECT_EQ(info.r, (std::array<double, 9>{1, 0, 0, 0, 1, 0, 0, 0, 1}));
  EXPECT_EQ(info.p,
            (std::array<double, 12>{info.k[0], 0, 320, 0, 0, info.k[0], 240, 0, 0, 0, 1, 0}));
  EXPECT_EQ(info.distortion_model, "plumb_bob");
  EXPECT_EQ(info.d, (std::vector<double>{-0.25, 0.12, -0.00028, -5e-5, 0.0}));
  EXPECT_EQ(info.header.frame_id, "camera_optical_frame");
  EXPECT_EQ(info.width, 640u);
  EXPECT_EQ(info.height, 480u);
  EXPECT_EQ(info.binning_x, 0u);
  EXPECT_EQ(info.roi, msgs::RegionOfInterest{});

  EXPECT_THROW(make_pinhole_camera_info(0, 480, 1.0, {}, "c"), std::invalid_argument);
  EXPECT_THROW(make_pinhole_camera_info(640, 480, 0.0, {}, "c"), std::invalid_argument);
  EXPECT_THROW(make_pinhole_camera_info(640, 480, 3.2, {}, "c"), std::invalid_argument);
}

}  // namespace
}  // namespace robotperf::perception
