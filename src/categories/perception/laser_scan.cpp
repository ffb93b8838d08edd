#include "robotperf/perception/laser_scan.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <stdexcept>
#include <vector>

#include "cloud_fields.hpp"
#include "robotperf/perception/image_proc.hpp"

namespace robotperf::perception {
namespace {

void require(bool ok, const char* who, const std::string& what) {
  if (!ok) throw std::invalid_argument(std::string(who) + ": " + what);
}

// ---------------------------------------------------------------------------------------------
// depthimage_to_laserscan
// ---------------------------------------------------------------------------------------------

constexpr const char* kDepthScan = "depthimage_to_laserscan";

// image_geometry's PinholeCameraModel, the part DepthImageToLaserScan uses.
class ScanCamera {
 public:
  explicit ScanCamera(const msgs::CameraInfo& info) : info_(info) {}
  double fx() const { return info_.p[0]; }
  double fy() const { return info_.p[5]; }
  double cx() const { return info_.p[2]; }
  double cy() const { return info_.p[6]; }

  // rectifyPoint then projectPixelTo3dRay.
  cv::Vec3d ray(double u, double v) const {
    cv::Point2d rectified(u, v);
    if (std::any_of(info_.d.begin(), info_.d.end(), [](double d) { return d != 0.0; })) {
      const std::vector<cv::Point2d> raw{rectified};
      std::vector<cv::Point2d> out;
      cv::undistortPoints(raw, out, cv::Matx33d(info_.k.data()), info_.d,
                          cv::Matx33d(info_.r.data()), cv::Matx34d(info_.p.data()));
      rectified = out.front();
    }
    return {(rectified.x - cx() - info_.p[3]) / fx(), (rectified.y - cy() - info_.p[7]) / fy(),
            1.0};
  }

 private:
  const msgs::CameraInfo& info_;
};

double angle_between(const cv::Vec3d& a, const cv::Vec3d& b) {
  return std::acos(a.dot(b) / (cv::norm(a) * cv::norm(b)));
}

template <class T>
struct DepthTraits;
template <>
struct DepthTraits<float> {
  static bool valid(float depth) { return std::isfinite(depth); }
  static float metres(float depth) { return depth; }
};
template <>
struct DepthTraits<uint16_t> {
  static bool valid(uint16_t depth) { return depth != 0; }
  static float metres(uint16_t depth) { return depth * 0.001f; }
};

// Whether `new_value` replaces a beam's `old_value`: a finite range within the limits beats a
// non-finite one and a longer one; of two non-finite ones, +-inf beats NaN.
bool use_point(float new_value, float old_value, float range_min, float range_max) {
  const bool new_finite = std::isfinite(new_value);
  const bool old_finite = std::isfinite(old_value);
  if (!new_finite && !old_finite) return !std::isnan(new_value);
  if (!(range_min <= new_value && new_value <= range_max)) return false;
  return !old_finite || new_value < old_value;
}

// The per-column minimum over `rows` rows from `first`, in the arithmetic DepthImageToLaserScan
// uses: the principal point and the x scale in float, the angle and range in double.
template <class T>
void fill_ranges(const cv::Mat& depth, const ScanCamera& camera, int first, int rows,
                 msgs::LaserScan& scan) {
  const float center_x = static_cast<float>(camera.cx());
  const double unit_scaling = DepthTraits<T>::metres(T(1));
  const float constant_x = static_cast<float>(unit_scaling / camera.fx());
  const auto beams = static_cast<double>(scan.ranges.size());
  for (int v = first; v < first + rows; ++v) {
    const T* row = depth.ptr<T>(v);
    for (int u = 0; u < depth.cols; ++u) {
      const T d = row[u];
      const float column = static_cast<float>(u) - center_x;
      double range = d;  // NaN and inf pass through
      if (DepthTraits<T>::valid(d)) {
        const double x = column * d * constant_x;
        const double z = DepthTraits<T>::metres(d);
        range = std::sqrt(x * x + z * z);
      }
      const double th = -std::atan2(static_cast<double>(column) * constant_x, unit_scaling);
      const double beam = (th - scan.angle_min) / scan.angle_increment;
      // Truncated toward zero as the node's int conversion; outside the scan (which the node
      // would write past) it is dropped.
      if (!(beam > -1.0 && beam < beams)) continue;
      float& old = scan.ranges[static_cast<std::size_t>(beam)];
      if (use_point(static_cast<float>(range), old, scan.range_min, scan.range_max)) {
        old = static_cast<float>(range);
      }
    }
  }
}

}  // namespace

void depth_image_to_laser_scan(const msgs::Image& depth, const msgs::CameraInfo& info,
                               const DepthToScanParams& params, msgs::LaserScan& scan) {
  const bool metres = depth.encoding == "32FC1";
  require(
      metres || depth.encoding == "16UC1", kDepthScan,
      "depth encoding '" + depth.encoding + "' is not supported (32FC1 metres, 16UC1 millimetres)");
  const cv::Mat image = image_view(depth);
  require(image.cols >= 2, kDepthScan,
          "the depth image has " + std::to_string(image.cols) + " columns, at least 2 make a scan");
  const ScanCamera camera(info);
  require(camera.fx() != 0.0 && camera.fy() != 0.0 && std::isfinite(camera.fx()) &&
              std::isfinite(camera.fy()) && std::isfinite(camera.cx()) &&
              std::isfinite(camera.cy()),
          kDepthScan, "CameraInfo has no focal length or principal point (P[0], P[5], P[2], P[6])");
  const int half = params.scan_height / 2;
  const auto first = static_cast<int>(camera.cy() - params.scan_height / 2.0);
  require(params.scan_height >= 1 && half <= camera.cy() && half <= image.rows - camera.cy() &&
              first >= 0 && first + params.scan_height <= image.rows,
          kDepthScan,
          "scan_height (" + std::to_string(params.scan_height) +
              " pixels) is too large for the image height (" + std::to_string(image.rows) +
              ", cy " + std::to_string(camera.cy()) + ")");

  // The angles of the outermost columns of the principal row, from the centre's ray.
  const cv::Vec3d centre = camera.ray(camera.cx(), camera.cy());
  scan.header = depth.header;
  if (!params.output_frame.empty()) scan.header.frame_id = params.output_frame;
  scan.angle_max = static_cast<float>(angle_between(camera.ray(0, camera.cy()), centre));
  scan.angle_min =
      static_cast<float>(-angle_between(centre, camera.ray(image.cols - 1, camera.cy())));
  scan.angle_increment = (scan.angle_max - scan.angle_min) / static_cast<float>(image.cols - 1);
  scan.time_increment = 0.0f;
  scan.scan_time = static_cast<float>(params.scan_time);
  scan.range_min = static_cast<float>(params.range_min);
  scan.range_max = static_cast<float>(params.range_max);
  scan.ranges.assign(static_cast<std::size_t>(image.cols), std::nanf(""));
  scan.intensities.clear();
  if (metres) {
    fill_ranges<float>(image, camera, first, params.scan_height, scan);
  } else {
    fill_ranges<uint16_t>(image, camera, first, params.scan_height, scan);
  }
}

namespace {

// ---------------------------------------------------------------------------------------------
// pointcloud_to_laserscan
// ---------------------------------------------------------------------------------------------

constexpr const char* kCloudScan = "pointcloud_to_laserscan";

// The beams of a scan over the message's (float) angles, as the node counts them.
double beam_count(float angle_min, float angle_max, float angle_increment) {
  return std::ceil((angle_max - angle_min) / angle_increment);
}

}  // namespace

void check(const CloudToScanParams& p) {
  require(std::isfinite(p.angle_min) && std::isfinite(p.angle_max) && p.angle_max > p.angle_min,
          kCloudScan, "angle_max must be finite and above a finite angle_min");
  require(p.angle_increment > 0.0, kCloudScan, "angle_increment must be positive");
  const double beams = beam_count(static_cast<float>(p.angle_min), static_cast<float>(p.angle_max),
                                  static_cast<float>(p.angle_increment));
  require(beams >= 1.0 && beams <= double{1 << 20}, kCloudScan,
          "angle_min .. angle_max in steps of angle_increment make " + std::to_string(beams) +
              " beams, not 1 to 2^20");
  require(!(p.min_height > p.max_height), kCloudScan, "min_height is above max_height");
  require(!(p.range_min > p.range_max), kCloudScan, "range_min is above range_max");
}

void point_cloud_to_laser_scan(const msgs::PointCloud2& cloud, const CloudToScanParams& params,
                               msgs::LaserScan& scan) {
  check(params);
  require(params.target_frame.empty() || params.target_frame == cloud.header.frame_id, kCloudScan,
          "target_frame '" + params.target_frame + "' is not the cloud's frame '" +
              cloud.header.frame_id + "', and the graph has no tf to transform the cloud");
  const msgs::PointField* fx = float32_field(cloud, "x");
  const msgs::PointField* fy = float32_field(cloud, "y");
  const msgs::PointField* fz = float32_field(cloud, "z");
  require(fx && fy && fz, kCloudScan, "the cloud has no float32 fields x, y and z");
  require(holds_its_points(cloud), kCloudScan,
          "the cloud is big-endian or its data does not hold its " + std::to_string(cloud.width) +
              "x" + std::to_string(cloud.height) + " points");

  scan.header = cloud.header;
  if (!params.target_frame.empty()) scan.header.frame_id = params.target_frame;
  scan.angle_min = static_cast<float>(params.angle_min);
  scan.angle_max = static_cast<float>(params.angle_max);
  scan.angle_increment = static_cast<float>(params.angle_increment);
  scan.time_increment = 0.0f;
  scan.scan_time = static_cast<float>(params.scan_time);
  scan.range_min = static_cast<float>(params.range_min);
  scan.range_max = static_cast<float>(params.range_max);
  const auto beams =
      static_cast<std::size_t>(beam_count(scan.angle_min, scan.angle_max, scan.angle_increment));
  scan.ranges.assign(beams, params.use_inf
                                ? std::numeric_limits<float>::infinity()
                                : static_cast<float>(scan.range_max + params.inf_epsilon));
  scan.intensities.clear();

  for (uint32_t v = 0; v < cloud.height; ++v) {
    const uint8_t* point = cloud.data.data() + uint64_t{v} * cloud.row_step;
    for (uint32_t u = 0; u < cloud.width; ++u, point += cloud.point_step) {
      const float x = read_float(point, *fx), y = read_float(point, *fy),
                  z = read_float(point, *fz);
      if (std::isnan(x) || std::isnan(y) || std::isnan(z)) continue;
      if (z > params.max_height || z < params.min_height) continue;
      const double range = std::hypot(double{x}, double{y});
      if (range < params.range_min || range > params.range_max) continue;
      const double angle = std::atan2(double{y}, double{x});
      if (angle < scan.angle_min || angle > scan.angle_max) continue;
      const auto beam = static_cast<std::size_t>((angle - scan.angle_min) / scan.angle_increment);
      // angle_max itself falls one past the last beam when the span is whole beams.
      if (beam >= beams) continue;
      if (range < scan.ranges[beam]) scan.ranges[beam] = static_cast<float>(range);
    }
  }
}

}  // namespace robotperf::perception
