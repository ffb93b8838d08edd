// depthimage_to_laserscan: the scan's geometry, its ranges against a known wall and the rendered
// room's truth, from metres and millimetres, its range limits and refusals;
// pointcloud_to_laserscan: its beams, which points each keeps, and its refusals.
#include "robotperf/perception/laser_scan.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "robotperf/perception/image_proc.hpp"
#include "robotperf/perception/synthetic_depth.hpp"

namespace robotperf::perception {
namespace {

const DepthFrame& frame() {
  static const DepthFrame f = [] {
    SyntheticDepthConfig c;
    c.frames = 1;
    return generate_depth_sequence(c).front();
  }();
  return f;
}

msgs::LaserScan scan_of(const msgs::Image& depth, const DepthToScanParams& params = {}) {
  msgs::LaserScan scan;
  depth_image_to_laser_scan(depth, frame().info, params, scan);
  return scan;
}

// A 32FC1 image of the frame's size, every pixel `metres`.
msgs::Image flat(float metres) {
  msgs::Image depth;
  prepare_image(depth, frame().depth.header, "32FC1", 640, 480).setTo(metres);
  return depth;
}

TEST(DepthToScan, SpansTheCameraColumnsOneBeamEach) {
  const msgs::LaserScan scan = scan_of(frame().depth);
  const double fx = frame().info.p[0], cx = frame().info.p[2];
  EXPECT_EQ(scan.ranges.size(), 640u);
  EXPECT_NEAR(scan.angle_max, std::atan2(cx, fx), 1e-6);
  EXPECT_NEAR(scan.angle_min, -std::atan2(639 - cx, fx), 1e-6);
  EXPECT_FLOAT_EQ(scan.angle_increment, (scan.angle_max - scan.angle_min) / 639.0f);
  EXPECT_EQ(scan.header.stamp, frame().depth.header.stamp);
  EXPECT_EQ(scan.header.frame_id, "camera_depth_frame");
  EXPECT_FLOAT_EQ(scan.scan_time, 0.033f);
  EXPECT_FLOAT_EQ(scan.range_min, 0.45f);
  EXPECT_FLOAT_EQ(scan.range_max, 10.0f);
  EXPECT_TRUE(scan.intensities.empty());
  DepthToScanParams keep;
  keep.output_frame = "";
  EXPECT_EQ(scan_of(frame().depth, keep).header.frame_id, frame().depth.header.frame_id);
}

// A wall 2 m in front: the beam of each column holds that column's planar distance 2 / cos(th),
// th within the beam. Columns are spread evenly in tan(th), beams in th: beams near the centre,
// wider apart in columns, are left NaN, and near the edges several columns share a beam.
TEST(DepthToScan, GivesAWallsPlanarDistancePerBeam) {
  const msgs::LaserScan scan = scan_of(flat(2.0f));
  std::size_t with_range = 0;
  for (std::size_t i = 0; i < scan.ranges.size(); ++i) {
    const float r = scan.ranges[i];
    if (std::isnan(r)) continue;
    ++with_range;
    const double lo = scan.angle_min + i * double{scan.angle_increment};
    const double hi = lo + scan.angle_increment;
    // The shortest of the beam's columns: the one nearest the centre.
    const double nearest = std::min(std::abs(lo), std::abs(hi));
    const double farthest = std::max(std::abs(lo), std::abs(hi));
    EXPECT_GE(r, 2.0 / std::cos(lo * hi > 0 ? nearest : 0.0) - 1e-5) << i;
    EXPECT_LE(r, 2.0 / std::cos(farthest) + 1e-5) << i;
  }
  EXPECT_GT(with_range, 500u);
  EXPECT_LT(with_range, 640u);
}

// The range of beam 0, the rightmost, of a wall `metres` in front: its nearest column's.
void expect_first_beam_at(const msgs::LaserScan& scan, double metres) {
  EXPECT_GE(scan.ranges[0], metres / std::cos(scan.angle_min + scan.angle_increment) - 1e-5);
  EXPECT_LE(scan.ranges[0], metres / std::cos(scan.angle_min) + 1e-5);
}

// Each beam is the shortest over scan_height rows about cy (rows 238..240 for 3 at cy 240).
TEST(DepthToScan, TakesTheShortestRangeOverScanHeightRows) {
  msgs::Image depth = flat(3.0f);
  cv::Mat d = image_view(depth);
  d.row(238).setTo(2.0f);
  d.row(241).setTo(1.0f);  // outside the band
  DepthToScanParams three;
  three.scan_height = 3;
  expect_first_beam_at(scan_of(depth, three), 2.0);
  expect_first_beam_at(scan_of(depth), 3.0);  // row 239 only
}

// Ranges outside [range_min, range_max] are no return (NaN); inf depth passes through as inf,
// which beats NaN; millimetres give the metres' scan within their rounding, 0 being no depth.
// (The outermost columns lie on a beam edge, which the millimetres' scale in float moves them
// across: the two outermost beams each side are left out.)
TEST(DepthToScan, KeepsItsRangeLimitsAndReadsMillimetres) {
  for (const float near : {0.3f, 12.0f}) {
    for (const float r : scan_of(flat(near)).ranges) ASSERT_TRUE(std::isnan(r)) << near;
  }
  const float inf = std::numeric_limits<float>::infinity();
  std::size_t infinite = 0;
  for (const float r : scan_of(flat(inf)).ranges) infinite += std::isinf(r) && r > 0;
  EXPECT_GT(infinite, 500u);

  const msgs::LaserScan metres = scan_of(frame().depth);
  const msgs::LaserScan mm = scan_of(frame().depth_mm);
  std::size_t compared = 0;
  for (std::size_t i = 2; i + 2 < metres.ranges.size(); ++i) {
    ASSERT_EQ(std::isnan(metres.ranges[i]), std::isnan(mm.ranges[i])) << i;
    if (std::isnan(metres.ranges[i])) continue;
    ++compared;
    EXPECT_NEAR(mm.ranges[i], metres.ranges[i], 1e-3) << i;
  }
  EXPECT_GT(compared, 400u);  // the doorway's corridor is beyond the sensor
}

TEST(DepthToScan, RefusesWhatItCannotConvert) {
  auto error = [](const msgs::Image& depth, const msgs::CameraInfo& info,
                  DepthToScanParams params = {}) -> std::string {
    msgs::LaserScan scan;
    try {
      depth_image_to_laser_scan(depth, info, params, scan);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  const DepthFrame& f = frame();
  EXPECT_NE(error(f.colour, f.info).find("'rgb8' is not supported"), std::string::npos);
  DepthToScanParams tall;
  tall.scan_height = 482;
  EXPECT_NE(error(f.depth, f.info, tall).find("scan_height (482 pixels) is too large"),
            std::string::npos);
  msgs::CameraInfo no_focal = f.info;
  no_focal.p[0] = 0;
  EXPECT_NE(error(f.depth, no_focal).find("no focal length"), std::string::npos);
  msgs::Image column;
  prepare_image(column, f.depth.header, "32FC1", 1, 480);
  EXPECT_NE(error(column, f.info).find("at least 2"), std::string::npos);
}

// An unorganised xyz cloud (point_step 16, as PointCloud2Modifier lays out "xyz") in `frame`.
msgs::PointCloud2 cloud_of(const std::vector<BodyPoint>& points,
                           const std::string& frame = "camera_link") {
  msgs::PointCloud2 c;
  c.header.frame_id = frame;
  c.height = 1;
  c.width = static_cast<uint32_t>(points.size());
  c.fields = {{"x", 0, msgs::PointField::kFloat32, 1},
              {"y", 4, msgs::PointField::kFloat32, 1},
              {"z", 8, msgs::PointField::kFloat32, 1}};
  c.point_step = 16;
  c.row_step = 16 * c.width;
  c.data.assign(c.row_step, 0);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const float xyz[3] = {static_cast<float>(points[i].x), static_cast<float>(points[i].y),
                          static_cast<float>(points[i].z)};
    std::memcpy(c.data.data() + 16 * i, xyz, sizeof xyz);
  }
  return c;
}

// The graph's parameters (a7): a slab 1.1 m to 0.1 m below the camera, half a turn of beams.
CloudToScanParams slab() {
  CloudToScanParams p;
  p.min_height = -1.1;
  p.max_height = -0.1;
  p.angle_min = -1.5708;
  p.angle_max = 1.5708;
  p.angle_increment = 0.0087;
  p.range_min = 0.45;
  p.range_max = 10.0;
  return p;
}

msgs::LaserScan scan_of(const msgs::PointCloud2& cloud, const CloudToScanParams& params = slab()) {
  msgs::LaserScan scan;
  point_cloud_to_laser_scan(cloud, params, scan);
  return scan;
}

std::size_t beam_of(const msgs::LaserScan& scan, double angle) {
  return static_cast<std::size_t>((angle - scan.angle_min) / scan.angle_increment);
}

TEST(CloudToScan, CountsBeamsAsTheNodeDoesInItsOwnFrame) {
  const msgs::LaserScan scan = scan_of(cloud_of({}));
  EXPECT_EQ(scan.ranges.size(), 362u);  // ceil(3.1416 / 0.0087) in float
  EXPECT_EQ(scan.header.frame_id, "camera_link");
  for (const float r : scan.ranges) ASSERT_TRUE(std::isinf(r) && r > 0);
  EXPECT_FLOAT_EQ(scan.range_max, 10.0f);
  EXPECT_FLOAT_EQ(scan.scan_time, 1.0f / 30.0f);
  CloudToScanParams finite = slab();
  finite.use_inf = false;
  finite.inf_epsilon = 0.5;
  EXPECT_FLOAT_EQ(scan_of(cloud_of({}), finite).ranges[7], 10.5f);
  CloudToScanParams own = slab();
  own.target_frame = "camera_link";
  EXPECT_EQ(scan_of(cloud_of({}), own).header.frame_id, "camera_link");
  // The node's defaults: a whole turn in degrees.
  EXPECT_EQ(scan_of(cloud_of({}), CloudToScanParams{}).ranges.size(), 360u);
}

// Each beam keeps the shortest planar range of the points in the slab, the range limits and the
// angles; NaN points are skipped.
TEST(CloudToScan, KeepsTheNearestPointInTheSlabPerBeam) {
  const double nan = std::nan("");
  const msgs::LaserScan scan = scan_of(cloud_of({
      {3.0, 0.0, -0.5},     // ahead
      {2.0, 0.0, -0.5},     // nearer, same beam
      {1.0, 0.0, -1.15},    // below the slab
      {1.5, 0.0, 0.0},      // above it
      {nan, 0.0, -0.5},     // no point
      {1.0, 1.0, -0.5},     // 45 degrees left
      {0.3, 0.3, -0.5},     // the same beam, nearer than range_min
      {-5.0, -0.01, -0.5},  // behind, outside the angles
      {12.0, -1.0, -0.5},   // beyond range_max
  }));
  std::size_t with_range = 0;
  for (const float r : scan.ranges) with_range += std::isfinite(r);
  EXPECT_EQ(with_range, 2u);
  EXPECT_FLOAT_EQ(scan.ranges[beam_of(scan, 0.0)], 2.0f);
  EXPECT_FLOAT_EQ(scan.ranges[beam_of(scan, std::atan2(1.0, 1.0))],
                  static_cast<float>(std::sqrt(2.0)));
}

// The rendered room's cloud: a range for most beams within the camera's 1.089 rad, none outside,
// and each the planar range of a point of the cloud in the slab.
TEST(CloudToScan, ScansTheRoomWithinTheCamerasView) {
  const msgs::LaserScan scan = scan_of(frame().cloud);
  std::size_t inside = 0, outside = 0;
  for (std::size_t i = 0; i < scan.ranges.size(); ++i) {
    const double angle = scan.angle_min + (i + 0.5) * scan.angle_increment;
    const bool finite = std::isfinite(scan.ranges[i]);
    if (std::abs(angle) < 0.5) inside += finite;
    if (std::abs(angle) > 0.56) outside += finite;
  }
  EXPECT_GT(inside, 100u);
  EXPECT_EQ(outside, 0u);
}

TEST(CloudToScan, RefusesWhatItCannotConvert) {
  auto error = [](const msgs::PointCloud2& cloud, const CloudToScanParams& params) -> std::string {
    msgs::LaserScan scan;
    try {
      point_cloud_to_laser_scan(cloud, params, scan);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  const msgs::PointCloud2 ok = cloud_of({{1.0, 0.0, -0.5}});
  CloudToScanParams base = slab();
  base.target_frame = "base_link";
  EXPECT_NE(error(ok, base).find("no tf to transform"), std::string::npos);
  msgs::PointCloud2 flat = ok;
  flat.fields.pop_back();
  EXPECT_NE(error(flat, slab()).find("no float32 fields x, y and z"), std::string::npos);
  msgs::PointCloud2 short_data = ok;
  short_data.data.resize(8);
  EXPECT_NE(error(short_data, slab()).find("does not hold its 1x1 points"), std::string::npos);
  CloudToScanParams still = slab();
  still.angle_increment = 0.0;
  EXPECT_NE(error(ok, still).find("angle_increment must be positive"), std::string::npos);
  CloudToScanParams fine = slab();
  fine.angle_increment = 1e-7;
  EXPECT_NE(error(ok, fine).find("not 1 to 2^20"), std::string::npos);
  CloudToScanParams upside_down = slab();
  upside_down.min_height = 0.0;
  EXPECT_NE(error(ok, upside_down).find("min_height is above max_height"), std::string::npos);
}

}  // namespace
}  // namespace robotperf::perception
