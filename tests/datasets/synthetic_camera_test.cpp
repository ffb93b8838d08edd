#include "robotperf/perception/synthetic_camera.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <opencv2/core.hpp>
#include <stdexcept>

#include "robotperf/perception/image_proc.hpp"

namespace robotperf::perception {
namespace {

class SyntheticCamera : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const auto start = std::chrono::steady_clock::now();
    frames_ = new std::vector<CameraFrame>(generate_camera_sequence());
    generation_seconds_ =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  static void TearDownTestSuite() { delete frames_; }
  static std::vector<CameraFrame>* frames_;
  static double generation_seconds_;
};
std::vector<CameraFrame>* SyntheticCamera::frames_ = nullptr;
double SyntheticCamera::generation_seconds_ = 0.0;

TEST_F(SyntheticCamera, Has68FramesOf640x480Rgb8) {
  ASSERT_EQ(frames_->size(), 68u);
  for (const CameraFrame& frame : *frames_) {
    EXPECT_EQ(frame.image.width, 640u);
    EXPECT_EQ(frame.image.height, 480u);
    EXPECT_EQ(frame.image.encoding, "rgb8");
    EXPECT_EQ(frame.image.step, 640u * 3);
    EXPECT_EQ(frame.image.data.size(), 640u * 480 * 3);
    EXPECT_EQ(frame.image.is_bigendian, 0);
    EXPECT_EQ(frame.image.header.frame_id, "camera_optical_frame");
    EXPECT_EQ(frame.info.header, frame.image.header);
  }
  // Well under the time it takes to play them (2.3 s), even unoptimised.
  EXPECT_LT(generation_seconds_, 2.0);
}

TEST_F(SyntheticCamera, StampsFramesAt30Hz) {
  EXPECT_EQ(frames_->at(0).image.header.stamp.to_ns(), 0);
  EXPECT_EQ(frames_->at(1).image.header.stamp.to_ns(), 33'333'333);
  EXPECT_EQ(frames_->at(2).image.header.stamp.to_ns(), 66'666'667);
  EXPECT_EQ(frames_->at(3).image.header.stamp.to_ns(), 100'000'000);
  EXPECT_EQ(frames_->at(30).image.header.stamp, (msgs::Time{1, 0}));
  EXPECT_EQ(frames_->at(67).image.header.stamp.to_ns(), 2'233'333'333);
}

TEST_F(SyntheticCamera, CarriesThePinholePlumbBobModel) {
  const msgs::CameraInfo& info = frames_->front().info;
  EXPECT_EQ(info.width, 640u);
  EXPECT_EQ(info.height, 480u);
  EXPECT_EQ(info.distortion_model, "plumb_bob");
  EXPECT_EQ(info.d, (std::vector<double>{-0.25, 0.12, -0.00028, -5e-5, 0.0}));
  EXPECT_NEAR(info.k[0], 554.38, 0.01);
  EXPECT_DOUBLE_EQ(info.k[4], info.k[0]);
  EXPECT_DOUBLE_EQ(info.k[2], 320.0);
  EXPECT_DOUBLE_EQ(info.k[5], 240.0);
  EXPECT_DOUBLE_EQ(info.p[0], info.k[0]);
  EXPECT_DOUBLE_EQ(info.p[3], 0.0);
  for (const CameraFrame& frame : *frames_) {
    msgs::CameraInfo same = frame.info;
    same.header = info.header;
    EXPECT_EQ(same, info);
  }
}

TEST_F(SyntheticCamera, ShowsAMovingBoxOverATexturedScene) {
  const cv::Mat first = perception::image_view(frames_->front().image);
  const cv::Mat last = perception::image_view(frames_->back().image);
  // Consecutive frames differ (the box moves) but only in part of the image.
  const cv::Mat second = perception::image_view(frames_->at(1).image);
  cv::Mat changed;
  cv::compare(first, second, changed, cv::CMP_NE);
  const double changed_fraction =
      cv::countNonZero(changed.reshape(1)) / static_cast<double>(changed.total() * 3);
  EXPECT_GT(changed_fraction, 0.001);
  EXPECT_LT(changed_fraction, 0.2);
  EXPECT_GT(cv::norm(first, last, cv::NORM_L1) / first.total(), 10.0);
  // Texture: strong contrast and all channels used differently.
  cv::Scalar mean, stddev;
  cv::meanStdDev(first, mean, stddev);
  for (int c = 0; c < 3; ++c) EXPECT_GT(stddev[c], 50.0);
  EXPECT_NE(mean[0], mean[1]);
  // Barrel distortion: the raw frame's corners see beyond the ideal image, which is still scene
  // (not black border).
  EXPECT_GT(cv::norm(first.at<cv::Vec3b>(0, 0)), 20.0);
  EXPECT_GT(cv::norm(first.at<cv::Vec3b>(479, 639)), 20.0);
}

TEST_F(SyntheticCamera, IsDeterministic) {
  const std::vector<CameraFrame> again = generate_camera_sequence();
  ASSERT_EQ(again.size(), frames_->size());
  for (size_t i = 0; i < again.size(); ++i) {
    EXPECT_EQ(again[i].image, (*frames_)[i].image) << "frame " << i;
    EXPECT_EQ(again[i].info, (*frames_)[i].info) << "frame " << i;
  }
  EXPECT_EQ(camera_sequence_hash(again), camera_sequence_hash(*frames_));
  // Pinned: a change here changes every recorded result's dataset identity.
  EXPECT_EQ(camera_sequence_hash(*frames_), "fnv1a64:0d85d775e626862f");
}

TEST_F(SyntheticCamera, DoesNotDependOnTheThreadCount) {
  const int threads = cv::getNumThreads();
  cv::setNumThreads(1);
  const std::vector<CameraFrame> single_threaded = generate_camera_sequence();
  cv::setNumThreads(threads);
  EXPECT_EQ(camera_sequence_hash(single_threaded), camera_sequence_hash(*frames_));
}

TEST_F(SyntheticCamera, HashSeesEveryByte) {
  std::vector<CameraFrame> changed(frames_->begin(), frames_->begin() + 2);
  const std::string original = camera_sequence_hash(changed);
  changed[1].image.data[12345] ^= 1;
  EXPECT_NE(camera_sequence_hash(changed), original);
  changed[1].image.data[12345] ^= 1;
  EXPECT_EQ(camera_sequence_hash(changed), original);
  changed[0].info.k[0] = std::nextafter(changed[0].info.k[0], 1e9);
  EXPECT_NE(camera_sequence_hash(changed), original);
}

TEST(SyntheticCameraConfig, HonoursSizeRateAndFrames) {
  SyntheticCameraConfig config;
  config.width = 320;
  config.height = 200;
  config.frames = 5;
  config.rate_hz = 10.0;
  config.frame_id = "cam";
  const std::vector<CameraFrame> frames = generate_camera_sequence(config);
  ASSERT_EQ(frames.size(), 5u);
  EXPECT_EQ(frames[4].image.width, 320u);
  EXPECT_EQ(frames[4].image.height, 200u);
  EXPECT_EQ(frames[4].image.header.stamp.to_ns(), 400'000'000);
  EXPECT_EQ(frames[4].info.header.frame_id, "cam");
  EXPECT_DOUBLE_EQ(frames[4].info.k[2], 160.0);

  const msgs::Image ideal = render_ideal_camera_frame(config, 4);
  EXPECT_EQ(ideal.width, 320u);
  EXPECT_EQ(ideal.header, frames[4].image.header);
  EXPECT_NE(ideal.data, frames[4].image.data);

  config.rate_hz = 0.0;
  EXPECT_THROW(generate_camera_sequence(config), std::invalid_argument);
  config.rate_hz = 10.0;
  config.distortion = {0.1, 0.2, 0.3};
  EXPECT_THROW(generate_camera_sequence(config), std::invalid_argument);
  config.distortion = {0.1, 0.0, 0.0, 0.0};
  config.width = 0;
  EXPECT_THROW(generate_camera_sequence(config), std::invalid_argument);
}

TEST(SyntheticCameraConfig, WithoutDistortionRawEqualsIdeal) {
  SyntheticCameraConfig config;
  config.frames = 3;
  config.distortion = {0.0, 0.0, 0.0, 0.0, 0.0};
  const std::vector<CameraFrame> frames = generate_camera_sequence(config);
  EXPECT_EQ(frames[2].image.data, render_ideal_camera_frame(config, 2).data);
}

}  // namespace
}  // namespace robotperf::perception
