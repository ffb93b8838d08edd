// The generated stereo and depth datasets: geometry, ground truth, determinism.
#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "robotperf/perception/image_proc.hpp"
#include "robotperf/perception/synthetic_depth.hpp"
#include "robotperf/perception/synthetic_stereo.hpp"

namespace robotperf::perception {
namespace {

using perception::image_view;

SyntheticStereoConfig small_stereo() {
  SyntheticStereoConfig c;
  c.width = 320;
  c.height = 240;
  c.frames = 3;
  return c;
}

TEST(SyntheticStereo, CamerasFormARectifiedPairWithTheStatedBaselineAndFov) {
  const auto frames = generate_stereo_sequence(small_stereo());
  ASSERT_EQ(frames.size(), 3u);
  const StereoFrame& f = frames[1];
  const double fx = 160.0 / std::tan(1.089 / 2);
  EXPECT_NEAR(f.left_info.k[0], fx, 1e-9);
  EXPECT_EQ(f.left_info.k, f.right_info.k);
  EXPECT_DOUBLE_EQ(f.left_info.p[3], 0.0);
  EXPECT_NEAR(f.right_info.p[3], -fx * 0.10, 1e-9);
  EXPECT_EQ(f.left.encoding, "rgb8");
  EXPECT_EQ(f.left.header.stamp, f.right.header.stamp);
  EXPECT_EQ(f.left.header.stamp.to_ns(), 100'000'000);  // frame 1 at 10 Hz
  EXPECT_EQ(f.truth.header, f.left_info.header);
  EXPECT_NEAR(f.truth.f, fx, 1e-3);
  EXPECT_FLOAT_EQ(f.truth.t, 0.10f);
}

TEST(SyntheticStereo, TrueDisparityMapsLeftPixelsOntoTheSameRightPixels) {
  const auto frames = generate_stereo_sequence(small_stereo());
  const StereoFrame& f = frames[0];
  cv::Mat left, right;
  cv::cvtColor(image_view(f.left), left, cv::COLOR_RGB2GRAY);
  cv::cvtColor(image_view(f.right), right, cv::COLOR_RGB2GRAY);
  const cv::Mat truth = image_view(f.truth.image);
  // Warp the right image into the left view along the true disparity: where the truth is known
  // the two must agree, and far better than with a disparity off by 3 px.
  double error_true = 0, error_off = 0;
  int known = 0, unknown = 0;
  for (int v = 0; v < truth.rows; ++v) {
    for (int u = 0; u < truth.cols; ++u) {
      const float d = truth.at<float>(v, u);
      if (std::isnan(d)) {
        ++unknown;
        continue;
      }
      EXPECT_GT(d, 0.0f);
      EXPECT_LT(d, 64.0f / 2);  // half resolution: at most 32 px
      auto sample = [&](double x) {
        const int x0 = static_cast<int>(std::floor(x));
        if (x0 < 0 || x0 + 1 >= right.cols) return -1.0;
        const double a = x - x0;
        return (1 - a) * right.at<uint8_t>(v, x0) + a * right.at<uint8_t>(v, x0 + 1);
      };
      const double at_true = sample(u - d);
      const double at_off = sample(u - d - 3.0);
      if (at_true < 0 || at_off < 0) continue;
      error_true += std::abs(at_true - left.at<uint8_t>(v, u));
      error_off += std::abs(at_off - left.at<uint8_t>(v, u));
      ++known;
    }
  }
  ASSERT_GT(known, truth.rows * truth.cols / 2);
  EXPECT_GT(unknown, 0);  // the left border and occlusions behind the boxes
  EXPECT_LT(error_true / known, 6.0);
  EXPECT_GT(error_off / known, 3 * error_true / known);
}

TEST(SyntheticStereo, FullSizeDisparitiesFitStereoImageProcsDefaultRange) {
  SyntheticStereoConfig c;
  c.frames = 2;
  const auto frames = generate_stereo_sequence(c);
  for (const auto& f : frames) {
    EXPECT_GT(f.truth.min_disparity, 5.0f);
    EXPECT_LT(f.truth.max_disparity, 63.0f);
  }
}

TEST(SyntheticStereo, IsDeterministicAndMoves) {
  const auto a = generate_stereo_sequence(small_stereo());
  const auto b = generate_stereo_sequence(small_stereo());
  for (std::size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].left, b[k].left);
    EXPECT_EQ(a[k].right, b[k].right);
    EXPECT_EQ(a[k].truth.image.data, b[k].truth.image.data);
  }
  EXPECT_NE(a[0].left.data, a[1].left.data);
}

TEST(SyntheticStereo, RejectsBadConfigurations) {
  SyntheticStereoConfig c = small_stereo();
  c.baseline_m = 0;
  EXPECT_THROW(generate_stereo_sequence(c), std::invalid_argument);
  c = small_stereo();
  c.width = 0;
  EXPECT_THROW(generate_stereo_sequence(c), std::invalid_argument);
}

SyntheticDepthConfig small_depth() {
  SyntheticDepthConfig c;
  c.width = 320;
  c.height = 240;
  c.frames = 3;
  return c;
}

TEST(SyntheticDepth, DepthIsInRangeAndAllThreeEncodingsAgree) {
  const auto frames = generate_depth_sequence(small_depth());
  ASSERT_EQ(frames.size(), 3u);
  const DepthFrame& f = frames[2];
  EXPECT_EQ(f.depth.encoding, "32FC1");
  EXPECT_EQ(f.depth_mm.encoding, "16UC1");
  EXPECT_EQ(f.colour.encoding, "rgb8");
  EXPECT_EQ(f.truth_depth.encoding, "64FC1");
  EXPECT_EQ(f.depth.header.frame_id, f.colour.header.frame_id);
  EXPECT_EQ(f.depth.header.stamp.to_ns(), std::llround(2e9 / 30));
  const cv::Mat m = image_view(f.depth), mm = image_view(f.depth_mm), t = image_view(f.truth_depth);
  int valid = 0, invalid = 0;
  double nearest = 1e9, farthest = 0;
  for (int v = 0; v < m.rows; ++v) {
    for (int u = 0; u < m.cols; ++u) {
      const double z = t.at<double>(v, u);
      if (std::isnan(z)) {
        ++invalid;
        EXPECT_TRUE(std::isnan(m.at<float>(v, u)));
        EXPECT_EQ(mm.at<uint16_t>(v, u), 0);
        continue;
      }
      ++valid;
      nearest = std::min(nearest, z);
      farthest = std::max(farthest, z);
      EXPECT_EQ(m.at<float>(v, u), static_cast<float>(z));
      EXPECT_EQ(mm.at<uint16_t>(v, u), static_cast<uint16_t>(std::lround(z * 1000)));
    }
  }
  EXPECT_GT(invalid, 100);  // the corridor beyond 8 m through the doorway
  EXPECT_GT(valid, m.rows * m.cols * 9 / 10);
  EXPECT_GE(nearest, 0.05);
  EXPECT_LT(nearest, 1.0);  // the near box
  EXPECT_LE(farthest, 8.0);
  EXPECT_GT(farthest, 7.5);  // the corridor floor just inside the range
}

TEST(SyntheticDepth, IsDeterministicAndMoves) {
  const auto a = generate_depth_sequence(small_depth());
  const auto b = generate_depth_sequence(small_depth());
  for (std::size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].depth, b[k].depth);
    EXPECT_EQ(a[k].colour, b[k].colour);
  }
  EXPECT_NE(a[0].depth.data, a[1].depth.data);
}

TEST(SyntheticDepth, RejectsBadConfigurations) {
  SyntheticDepthConfig c = small_depth();
  c.max_range_m = c.min_range_m;
  EXPECT_THROW(generate_depth_sequence(c), std::invalid_argument);
  c = small_depth();
  c.rate_hz = 0;
  EXPECT_THROW(generate_depth_sequence(c), std::invalid_argument);
}

}  // namespace
}  // namespace robotperf::perception
