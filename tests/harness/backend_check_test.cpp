// How answers of two backends are compared (the tolerances of docs/design.md §6).
#include "robotperf/harness/backend_check.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

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

// A one-row image of `encoding` holding `values` as T.
template <class T>
msgs::Image image_of(const std::string& encoding, std::vector<T> values) {
  msgs::Image i;
  i.width = static_cast<uint32_t>(values.size());
  i.height = 1;
  i.encoding = encoding;
  i.step = static_cast<uint32_t>(sizeof(T) * values.size());
  i.data.resize(i.step);
  std::memcpy(i.data.data(), values.data(), i.step);
  return i;
}

TEST(BackendCheck, ImageChannelsAreComparedAsTheirEncodingsType) {
  const std::string type = "sensor_msgs/msg/Image";
  // 256 against 0 is one byte a level apart, and 256 levels.
  const msgs::Image s32 = image_of<int32_t>("32SC1", {256}),
                    s32_zero = image_of<int32_t>("32SC1", {0});
  EXPECT_EQ(share(type, &s32, &s32_zero), 0.0);
  // -1 against 0 is a level, not 65535.
  const msgs::Image s16 = image_of<int16_t>("16SC1", {-1}),
                    s16_zero = image_of<int16_t>("16SC1", {0});
  EXPECT_EQ(share(type, &s16, &s16_zero), 1.0);
  const msgs::Image s8 = image_of<int8_t>("8SC2", {-1, 127}),
                    s8_near = image_of<int8_t>("8SC2", {0, 126});
  EXPECT_EQ(share(type, &s8, &s8_near), 1.0);
  const msgs::Image bayer = image_of<uint16_t>("bayer_rggb16", {256}),
                    bayer_zero = image_of<uint16_t>("bayer_rggb16", {0});
  EXPECT_EQ(share(type, &bayer, &bayer_zero), 0.0);
  const msgs::Image f64 = image_of<double>("64FC1", {2.0}),
                    f64_off = image_of<double>("64FC1", {2.5});
  EXPECT_EQ(share(type, &f64, &f64_off), 0.0);
  EXPECT_NE(compare_answers(type, &f64, &f64)->criterion.find("1e-4"), std::string::npos);
}

TEST(BackendCheck, ImagesOfAnEncodingItCannotReadAgreeNowhere) {
  const std::string type = "sensor_msgs/msg/Image";
  for (const std::string encoding : {"rgb12", "12UC1", "8UC", "8UC0", "32UC1", "16FC1", "mono8x"}) {
    const msgs::Image i = image_of<uint8_t>(encoding, {7, 7});
    const auto r = compare_answers(type, &i, &i);
    ASSERT_TRUE(r.has_value());
    EXPECT_EQ(r->share, 0.0) << encoding;
    EXPECT_NE(r->criterion.find("'" + encoding + "' is not one of"), std::string::npos)
        << r->criterion;
  }
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

// A disparity image of `values`, searched from min_disparity 0: the node's value for no disparity
// is -1 less the principal points' x offset (left cx - right cx).
msgs::DisparityImage disparities(std::vector<float> values) {
  msgs::DisparityImage d;
  d.min_disparity = 0;
  d.max_disparity = 63;
  d.image.width = static_cast<uint32_t>(values.size());
  d.image.height = 1;
  d.image.encoding = "32FC1";
  d.image.step = 4 * d.image.width;
  d.image.data.resize(d.image.step);
  std::memcpy(d.image.data.data(), values.data(), d.image.step);
  return d;
}

double disparity_share(const std::vector<float>& other, const std::vector<float>& cpu) {
  const msgs::DisparityImage a = disparities(other), b = disparities(cpu);
  return share("stereo_msgs/msg/DisparityImage", &a, &b);
}

TEST(BackendCheck, DisparitiesAgreeWithinOnePixelWhereEitherBackendHasOne) {
  constexpr float kNone = -1.0f;
  EXPECT_DOUBLE_EQ(disparity_share({kNone, 10.9f, 22.0f, 30.0f}, {kNone, 10.0f, 20.0f, 30.0f}),
                   2.0 / 3.0);
  // A disparity where the cpu filtered the pixel (StereoBM's texture, uniqueness and speckle
  // checks only take disparities away): a backend leaving them out disagrees there.
  EXPECT_DOUBLE_EQ(disparity_share({55.0f, 10.0f}, {kNone, 10.0f}), 0.5);
  // None where the cpu has one, however near the value for none is.
  EXPECT_DOUBLE_EQ(disparity_share({kNone, kNone, 10.0f}, {kNone, 0.0f, 10.0f}), 0.5);
  EXPECT_DOUBLE_EQ(disparity_share({kNone, kNone}, {kNone, kNone}), 1.0);
}

// With the principal points apart in x, every pixel is shifted, the value for none too; the
// message's min_disparity says nothing of which pixels have a disparity.
TEST(BackendCheck, DisparitiesAreValidAboveTheNodesValueForNoneWhereverThePrincipalPointsAre) {
  // Right cx 3 px right of the left's: none is -1 + 3 = 2, the least disparity 3.
  EXPECT_DOUBLE_EQ(disparity_share({2.0f, 13.0f, 2.0f}, {2.0f, 13.0f, 2.0f}), 1.0);
  EXPECT_DOUBLE_EQ(disparity_share({2.0f, 13.0f, 3.0f}, {2.0f, 13.0f, 2.0f}), 0.5);
  // Right cx 3 px left: none is -4, and -2.5 a disparity (0.5 before the shift).
  EXPECT_DOUBLE_EQ(disparity_share({-4.0f, 7.0f, -4.0f}, {-4.0f, 7.0f, -2.5f}), 0.5);
}

TEST(BackendCheck, TypesWithoutAComparisonAreNotCompared) {
  EXPECT_FALSE(has_comparison("nav_msgs/msg/Odometry"));
  EXPECT_TRUE(has_comparison("sensor_msgs/msg/Image"));
  int unused = 0;
  EXPECT_FALSE(compare_answers("nav_msgs/msg/Odometry", &unused, &unused).has_value());
}

}  // namespace
}  // namespace robotperf::harness
