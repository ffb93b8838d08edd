// How answers of two backends are compared (the tolerances of DESIGN.md section 6).
#include "robotperf/harness/backend_check.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/msgs/stereo_msgs.hpp"

namespace robotperf::harness {
namespace {

msgs::Image rgb(uint8_t value) {
  msgs::Image i;
  i.width = 100;
  i.height = 10;
  i.encoding = "rgb8";
  i.step = 300;
  i.data.assign(3000, value);
  return i;
}

double share(const std::string& type, const void* a, const void* b) {
  const auto r = compare_answers(type, a, b);
  EXPECT_TRUE(r.has_value());
  return r ? r->share : -1.0;
}

TEST(BackendCheck, ImagesAgreeWithinOneGreyLevelPerChannel) {
  const std::string type = "sensor_msgs/msg/Image";
  const msgs::Image cpu = rgb(100);
  msgs::Image other = rgb(101);  // rounding one way everywhere: within the tolerance
  EXPECT_EQ(share(type, &other, &cpu), 1.0);
  other.data[7] = 103;  // one channel of 3000 two levels off
  EXPECT_DOUBLE_EQ(share(type, &other, &cpu), 2999.0 / 3000.0);
  EXPECT_GE(2999.0 / 3000.0, compare_answers(type, &other, &cpu)->required);
  other.data[8] = other.data[9] = other.data[10] = 0;  // four of 3000: 99.87 %, below 99.9 %
  EXPECT_LT(share(type, &other, &cpu), compare_answers(type, &other, &cpu)->required);
  msgs::Image smaller = cpu;
  smaller.width = 99;
  EXPECT_EQ(share(type, &smaller, &cpu), 0.0);
  msgs::Image bgr = cpu;
  bgr.encoding = "bgr8";
  EXPECT_EQ(share(type, &bgr, &cpu), 0.0);
}

// A depth image in metres, every pixel `metres`.
msgs::Image depth(float metres) {
  msgs::Image i;
  i.width = 10;
  i.height = 10;
  i.encoding = "32FC1";
  i.step = 40;
  i.data.resize(400);
  for (std::size_t p = 0; p < 100; ++p) std::memcpy(i.data.data() + 4 * p, &metres, 4);
  return i;
}

void set_pixel(msgs::Image& image, std::size_t p, float value) {
  std::memcpy(image.data.data() + 4 * p, &value, 4);
}

TEST(BackendCheck, FloatImagesAgreeWithinTheirRoundingNotWithinAUnit) {
  const std::string type = "sensor_msgs/msg/Image";
  const msgs::Image cpu = depth(2.0f);
  EXPECT_EQ(share(type, &cpu, &cpu), 1.0);
  const msgs::Image rounded = depth(2.0f * (1.0f + 4e-5f));  // 0.08 mm: rounding
  EXPECT_EQ(share(type, &rounded, &cpu), 1.0);
  const msgs::Image a_millimetre_off = depth(2.001f);
  EXPECT_EQ(share(type, &a_millimetre_off, &cpu), 0.0);
  const msgs::Image half_a_metre_off = depth(2.5f);
  EXPECT_EQ(share(type, &half_a_metre_off, &cpu), 0.0);
  msgs::Image with_none = cpu, other = cpu;
  set_pixel(with_none, 3, std::numeric_limits<float>::quiet_NaN());
  set_pixel(other, 3, std::numeric_limits<float>::quiet_NaN());
  set_pixel(with_none, 4, std::numeric_limits<float>::infinity());
  set_pixel(other, 4, std::numeric_limits<float>::infinity());
  EXPECT_EQ(share(type, &other, &with_none), 1.0);
  set_pixel(other, 3, 2.0f);  // a depth where the cpu has none
  EXPECT_DOUBLE_EQ(share(type, &other, &with_none), 0.99);
  EXPECT_NE(compare_answers(type, &other, &cpu)->criterion.find("1e-4"), std::string::npos);
}

// `points` zero points of x, y, z and a packed colour declared `rgb_type`, 16 bytes each.
msgs::PointCloud2 xyz_rgb_cloud(uint32_t points, uint8_t rgb_type) {
  msgs::PointCloud2 c;
  c.width = points;
  c.height = 1;
  c.point_step = 16;
  c.fields = {{"x", 0, msgs::PointField::kFloat32, 1},
              {"y", 4, msgs::PointField::kFloat32, 1},
              {"z", 8, msgs::PointField::kFloat32, 1},
              {"rgb", 12, rgb_type, 1}};
  c.data.assign(16 * points, 0);
  return c;
}

TEST(BackendCheck, PointCloudsAgreeWithinAMicrometreAndNanOnlyWithNan) {
  msgs::PointCloud2 cpu = xyz_rgb_cloud(2, msgs::PointField::kUint32);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::memcpy(cpu.data.data() + 16, &nan, 4);
  msgs::PointCloud2 other = cpu;
  const std::string type = "sensor_msgs/msg/PointCloud2";
  EXPECT_EQ(share(type, &other, &cpu), 1.0);
  const float off = 2e-6f;
  std::memcpy(other.data.data() + 4, &off, 4);  // the first point's y, 2 um off
  EXPECT_EQ(share(type, &other, &cpu), 0.5);
  other = cpu;
  other.data[12] = 1;  // the first point's blue one level off: as images, within the tolerance
  EXPECT_EQ(share(type, &other, &cpu), 1.0);
  other.data[13] = 2;  // and its green two
  EXPECT_EQ(share(type, &other, &cpu), 0.5);
  other = cpu;
  const float zero = 0.0f;
  std::memcpy(other.data.data() + 16, &zero, 4);  // a point where the cpu has none
  EXPECT_EQ(share(type, &other, &cpu), 0.5);
}

// PCL's rgb field is FLOAT32 holding the bytes b, g, r, 0: compared as a float, any two colours
// (tiny or denormal numbers) agreed within 1e-6; they are compared channel by channel.
TEST(BackendCheck, PointCloudColourDeclaredFloatIsComparedByChannel) {
  msgs::PointCloud2 cpu = xyz_rgb_cloud(1, msgs::PointField::kFloat32);
  const uint8_t bgr0[4] = {10, 200, 30, 0};
  std::memcpy(cpu.data.data() + 12, bgr0, 4);
  msgs::PointCloud2 swapped = cpu;
  const uint8_t rgb0[4] = {30, 200, 10, 0};  // red and blue exchanged
  std::memcpy(swapped.data.data() + 12, rgb0, 4);
  EXPECT_EQ(share("sensor_msgs/msg/PointCloud2", &swapped, &cpu), 0.0);
}

TEST(BackendCheck, DisparitiesAgreeWithinOnePixelWhereTheCpuHasOne) {
  msgs::DisparityImage cpu;
  cpu.min_disparity = 0;
  cpu.image.width = 4;
  cpu.image.height = 1;
  cpu.image.encoding = "32FC1";
  cpu.image.step = 16;
  const float cpu_values[4] = {-1.0f, 10.0f, 20.0f, 30.0f};  // the first: no disparity
  cpu.image.data.resize(16);
  std::memcpy(cpu.image.data.data(), cpu_values, 16);
  msgs::DisparityImage other = cpu;
  const float other_values[4] = {55.0f, 10.9f, 22.0f, 30.0f};
  std::memcpy(other.image.data.data(), other_values, 16);
  EXPECT_DOUBLE_EQ(share("stereo_msgs/msg/DisparityImage", &other, &cpu), 2.0 / 3.0);
}

TEST(BackendCheck, TypesWithoutAComparisonAreNotCompared) {
  EXPECT_FALSE(has_comparison("nav_msgs/msg/Odometry"));
  EXPECT_TRUE(has_comparison("sensor_msgs/msg/Image"));
  int unused = 0;
  EXPECT_FALSE(compare_answers("nav_msgs/msg/Odometry", &unused, &unused).has_value());
}

}  // namespace
}  // namespace robotperf::harness
