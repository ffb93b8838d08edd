// Functional evaluators of the perception benchmarks.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <vector>

#include "category.hpp"
#include "cloud_fields.hpp"
#include "robotperf/msgs/stereo_msgs.hpp"
#include "robotperf/perception/image_proc.hpp"
#include "robotperf/perception/laser_scan.hpp"
#include "robotperf/perception/synthetic_depth.hpp"

namespace robotperf::perception {
namespace {

using plugin::DatasetStream;
using plugin::FunctionalEvaluator;

std::string number(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

// An organised cloud's x, y and z fields, or why it cannot be read: not width x height points,
// fields missing, or data that does not hold its points.
struct XyzFields {
  const msgs::PointField *x = nullptr, *y = nullptr, *z = nullptr;
  std::string problem;
};

XyzFields xyz_fields(const msgs::PointCloud2& cloud, uint32_t width, uint32_t height) {
  if (cloud.width != width || cloud.height != height) {
    return {.problem = "point cloud is " + std::to_string(cloud.width) + "x" +
                       std::to_string(cloud.height) + ", expected an organised " +
                       std::to_string(width) + "x" + std::to_string(height) + " cloud"};
  }
  XyzFields f{float32_field(cloud, "x"), float32_field(cloud, "y"), float32_field(cloud, "z"), {}};
  if (!f.x || !f.y || !f.z || !holds_its_points(cloud)) {
    f.problem = "point cloud lacks float32 fields x, y, z or its data does not hold its points";
  }
  return f;
}

// ---------------------------------------------------------------------------------------------
// stereo_disparity: DisparityImage against a ground-truth DisparityImage of the left view.
// ---------------------------------------------------------------------------------------------

class StereoDisparityEvaluator final : public FunctionalEvaluator {
 public:
  explicit StereoDisparityEvaluator(const DatasetStream& truth) : truth_(truth) {
    plugin::require_type<msgs::DisparityImage>(truth, "stereo_disparity");
  }

  void add(const void* output, std::size_t frame) override {
    const auto& out = *static_cast<const msgs::DisparityImage*>(output);
    const auto& truth = *static_cast<const msgs::DisparityImage*>(truth_.messages[frame].get());
    if (out.image.encoding != "32FC1" || out.image.width != truth.image.width ||
        out.image.height != truth.image.height) {
      problem("disparity image is " + std::to_string(out.image.width) + "x" +
              std::to_string(out.image.height) + " " + out.image.encoding + ", expected " +
              std::to_string(truth.image.width) + "x" + std::to_string(truth.image.height) +
              " 32FC1");
      return;
    }
    if (std::abs(out.f - truth.f) > 1e-3f * truth.f) {
      problem("DisparityImage.f is " + number(out.f) + " px, the camera's focal length is " +
              number(truth.f) + " px");
    }
    if (std::abs(out.t - truth.t) > 1e-3f * truth.t) {
      problem("DisparityImage.t is " + number(out.t) + " m, the stereo baseline is " +
              number(truth.t) + " m");
    }
    const auto& w = out.valid_window;
    const uint64_t area = uint64_t{truth.image.width} * truth.image.height;
    if (uint64_t{w.x_offset} + w.width > out.image.width ||
        uint64_t{w.y_offset} + w.height > out.image.height ||
        2 * uint64_t{w.width} * w.height < area) {
      problem("valid_window (x " + std::to_string(w.x_offset) + ", y " +
              std::to_string(w.y_offset) + ", " + std::to_string(w.width) + "x" +
              std::to_string(w.height) + ") is outside the image or covers less than half of it");
      return;
    }
    const cv::Mat d = perception::image_view(out.image);
    const cv::Mat gt = perception::image_view(truth.image);
    for (uint32_t v = w.y_offset; v < w.y_offset + w.height; ++v) {
      const float* d_row = d.ptr<float>(static_cast<int>(v));
      const float* gt_row = gt.ptr<float>(static_cast<int>(v));
      for (uint32_t u = w.x_offset; u < w.x_offset + w.width; ++u) {
        const float g = gt_row[u];
        // Every pixel with a true disparity: a search range narrower than the scene's (the
        // output says which it searched) misses those beyond it rather than leaving them out.
        if (std::isnan(g)) continue;
        ++evaluated_;
        const float x = d_row[u];
        if (!std::isfinite(x) || x < out.min_disparity || x > out.max_disparity) continue;
        ++valid_;
        const double error = std::abs(static_cast<double>(x) - g);
        error_sum_ += error;
        if (error > 1.0) ++bad_;
      }
    }
  }

  std::map<std::string, double> metrics() const override {
    const double nan = std::nan("");
    return {
        {"valid_fraction", evaluated_ ? static_cast<double>(valid_) / evaluated_ : nan},
        {"bad1", valid_ ? static_cast<double>(bad_) / valid_ : nan},
        {"mae_px", valid_ ? error_sum_ / valid_ : nan},
    };
  }

 private:
  const DatasetStream& truth_;
  uint64_t evaluated_ = 0, valid_ = 0, bad_ = 0;
  double error_sum_ = 0;
};

// ---------------------------------------------------------------------------------------------
// depth_point_cloud: an organised xyz(rgb) PointCloud2 against the scene's true depth.
// ---------------------------------------------------------------------------------------------

class DepthPointCloudEvaluator final : public FunctionalEvaluator {
 public:
  DepthPointCloudEvaluator(const DatasetStream& depth, const DatasetStream& info,
                           const DatasetStream& image)
      : depth_(depth), info_(info), image_(image) {
    plugin::require_type<msgs::Image>(depth, "depth_point_cloud");
    plugin::require_type<msgs::CameraInfo>(info, "depth_point_cloud");
    plugin::require_type<msgs::Image>(image, "depth_point_cloud");
  }

  void add(const void* output, std::size_t frame) override {
    const auto& cloud = *static_cast<const msgs::PointCloud2*>(output);
    const auto& truth = *static_cast<const msgs::Image*>(depth_.messages[frame].get());
    const auto& info = *static_cast<const msgs::CameraInfo*>(info_.messages[frame].get());
    const auto& image = *static_cast<const msgs::Image*>(image_.messages[frame].get());
    if (truth.encoding != "64FC1") {
      throw std::invalid_argument("depth_point_cloud: truth depth must be 64FC1 metres, is " +
                                  truth.encoding);
    }
    const XyzFields xyz = xyz_fields(cloud, truth.width, truth.height);
    if (!xyz.problem.empty()) {
      problem(xyz.problem);
      return;
    }
    const msgs::PointField* frgb = float32_field(cloud, "rgb");
    if (!frgb) problem("point cloud has no rgb field");
    const bool colour_ok = frgb && image.encoding == "rgb8";
    const cv::Mat gt = perception::image_view(truth);
    const cv::Mat colour = perception::image_view(image);
    const double fxp = info.p[0], fyp = info.p[5], cx = info.p[2], cy = info.p[6];
    for (uint32_t v = 0; v < cloud.height; ++v) {
      const double* gt_row = gt.ptr<double>(static_cast<int>(v));
      const uint8_t* row = cloud.data.data() + uint64_t{v} * cloud.row_step;
      for (uint32_t u = 0; u < cloud.width; ++u) {
        const uint8_t* point = row + uint64_t{u} * cloud.point_step;
        const float x = read_float(point, *xyz.x), y = read_float(point, *xyz.y),
                    z = read_float(point, *xyz.z);
        const bool valid = std::isfinite(x) && std::isfinite(y) && std::isfinite(z);
        const double true_z = gt_row[u];
        if (std::isnan(true_z)) {
          ++truth_invalid_;
          if (valid) ++spurious_;
          continue;
        }
        ++truth_valid_;
        if (!valid) continue;
        ++valid_;
        const double tx = (u - cx) * true_z / fxp;
        const double ty = (v - cy) * true_z / fyp;
        const double error =
            std::sqrt((x - tx) * (x - tx) + (y - ty) * (y - ty) + (z - true_z) * (z - true_z));
        error_sum_ += error;
        error_max_ = std::max(error_max_, error);
        if (colour_ok && frgb->offset + 3 <= cloud.point_step) {
          const uint8_t* px = colour.ptr<uint8_t>(static_cast<int>(v)) + 3 * u;
          const uint8_t* packed = point + frgb->offset;  // b, g, r
          if (packed[0] == px[2] && packed[1] == px[1] && packed[2] == px[0]) ++colour_match_;
        }
      }
    }
  }

  std::map<std::string, double> metrics() const override {
    const double nan = std::nan("");
    return {
        {"valid_fraction", truth_valid_ ? static_cast<double>(valid_) / truth_valid_ : nan},
        {"mean_error_m", valid_ ? error_sum_ / valid_ : nan},
        {"max_error_m", valid_ ? error_max_ : nan},
        {"spurious_fraction",
         truth_invalid_ ? static_cast<double>(spurious_) / truth_invalid_ : 0.0},
        {"colour_match", valid_ ? static_cast<double>(colour_match_) / valid_ : nan},
    };
  }

 private:
  const DatasetStream& depth_;
  const DatasetStream& info_;
  const DatasetStream& image_;
  uint64_t truth_valid_ = 0, truth_invalid_ = 0, valid_ = 0, spurious_ = 0, colour_match_ = 0;
  double error_sum_ = 0, error_max_ = 0;
};

// ---------------------------------------------------------------------------------------------
// stereo_point_cloud: an organised xyz PointCloud2 against the 3D points of the true disparity.
// ---------------------------------------------------------------------------------------------

class StereoPointCloudEvaluator final : public FunctionalEvaluator {
 public:
  StereoPointCloudEvaluator(const DatasetStream& disparity, const DatasetStream& info)
      : disparity_(disparity), info_(info) {
    plugin::require_type<msgs::DisparityImage>(disparity, "stereo_point_cloud");
    plugin::require_type<msgs::CameraInfo>(info, "stereo_point_cloud");
  }

  void add(const void* output, std::size_t frame) override {
    const auto& cloud = *static_cast<const msgs::PointCloud2*>(output);
    const auto& truth = *static_cast<const msgs::DisparityImage*>(disparity_.messages[frame].get());
    const auto& info = *static_cast<const msgs::CameraInfo*>(info_.messages[frame].get());
    if (truth.image.encoding != "32FC1") {
      throw std::invalid_argument("stereo_point_cloud: truth disparity must be 32FC1, is " +
                                  truth.image.encoding);
    }
    const XyzFields xyz = xyz_fields(cloud, truth.image.width, truth.image.height);
    if (!xyz.problem.empty()) {
      problem(xyz.problem);
      return;
    }
    const cv::Mat gt = perception::image_view(truth.image);
    const double fx = info.p[0], fy = info.p[5], cx = info.p[2], cy = info.p[6];
    for (uint32_t v = 0; v < cloud.height; ++v) {
      const float* gt_row = gt.ptr<float>(static_cast<int>(v));
      const uint8_t* row = cloud.data.data() + uint64_t{v} * cloud.row_step;
      for (uint32_t u = 0; u < cloud.width; ++u) {
        const uint8_t* point = row + uint64_t{u} * cloud.point_step;
        const double x = read_float(point, *xyz.x), y = read_float(point, *xyz.y),
                     z = read_float(point, *xyz.z);
        const bool valid = std::isfinite(x) && std::isfinite(y) && std::isfinite(z);
        const double d = gt_row[u];
        if (!(d > 0.0)) {
          ++truth_invalid_;
          if (valid) ++spurious_;
          continue;
        }
        ++truth_valid_;
        if (!valid) continue;
        ++valid_;
        // The true point: depth from the true disparity, f and baseline.
        const double tz = static_cast<double>(truth.f) * truth.t / d;
        const double tx = (u - cx) * tz / fx;
        const double ty = (v - cy) * tz / fy;
        const double error =
            std::sqrt((x - tx) * (x - tx) + (y - ty) * (y - ty) + (z - tz) * (z - tz));
        error_sum_ += error;
        relative_max_ = std::max(relative_max_, error / std::sqrt(tx * tx + ty * ty + tz * tz));
      }
    }
  }

  std::map<std::string, double> metrics() const override {
    const double nan = std::nan("");
    return {
        {"valid_fraction", truth_valid_ ? static_cast<double>(valid_) / truth_valid_ : nan},
        {"mean_error_m", valid_ ? error_sum_ / valid_ : nan},
        {"max_relative_error", valid_ ? relative_max_ : nan},
        {"spurious_fraction",
         truth_invalid_ ? static_cast<double>(spurious_) / truth_invalid_ : 0.0},
    };
  }

 private:
  const DatasetStream& disparity_;
  const DatasetStream& info_;
  uint64_t truth_valid_ = 0, truth_invalid_ = 0, valid_ = 0, spurious_ = 0;
  double error_sum_ = 0, relative_max_ = 0;
};

// ---------------------------------------------------------------------------------------------
// Laser scans against the true points of the scan plane.
// ---------------------------------------------------------------------------------------------

// What the scans of a run scored, over all their beams.
struct ScanScore {
  uint64_t with_truth = 0, found = 0, without_truth = 0, spurious = 0, returns = 0;
  double error_sum = 0, error_max = 0;

  std::map<std::string, double> metrics() const {
    const double nan = std::nan("");
    return {
        {"valid_fraction", with_truth ? static_cast<double>(found) / with_truth : nan},
        {"mean_error_m", returns ? error_sum / returns : nan},
        {"max_error_m", returns ? error_max : nan},
        {"spurious_fraction", without_truth ? static_cast<double>(spurious) / without_truth : 0.0},
    };
  }
};

const std::vector<plugin::MetricInfo> kScanMetrics = {
    {"valid_fraction", "fraction", "beams with a true return that the scan has a range for"},
    {"mean_error_m", "m", "mean distance of a range from the beam's true range"},
    {"max_error_m", "m", "largest distance of a range from the beam's true range"},
    {"spurious_fraction", "fraction", "beams without a true return that the scan has a range for"}};

// The true return of each beam of one scan: the shortest true planar range of the points whose
// angle falls in it. A point within a small margin of a beam's edge or of a range limit may land
// on either side in a kernel's float arithmetic, as may one a caller marks unsure: such a point
// may lower a beam's truth but need not. Each beam's truth is thus an interval, from the shortest
// of all its candidates to the shortest of its certain points.
class BeamTruth {
 public:
  explicit BeamTruth(const msgs::LaserScan& scan)
      : scan_(scan), shortest_(scan.ranges.size(), kNone), certain_(scan.ranges.size(), kNone) {}

  void add(double range, double angle, bool sure = true) {
    constexpr double kRangeMargin = 1e-3;  // m: a millimetre depth image's rounding
    constexpr double kBeamMargin = 1e-3;   // of a beam: float angles and their reciprocals
    if (range < scan_.range_min - kRangeMargin || range > scan_.range_max + kRangeMargin) return;
    sure =
        sure && range >= scan_.range_min + kRangeMargin && range <= scan_.range_max - kRangeMargin;
    const double beam = (angle - scan_.angle_min) / scan_.angle_increment;
    const double first = std::floor(beam - kBeamMargin), last = std::floor(beam + kBeamMargin);
    for (double b = std::max(first, 0.0); b <= last && b < static_cast<double>(shortest_.size());
         ++b) {
      const auto i = static_cast<std::size_t>(b);
      shortest_[i] = std::min(shortest_[i], range);
      if (sure && first == last) certain_[i] = std::min(certain_[i], range);
    }
  }

  void score(ScanScore& s) const {
    for (std::size_t i = 0; i < shortest_.size(); ++i) {
      const float r = scan_.ranges[i];
      const bool has_return = std::isfinite(r) && r >= scan_.range_min && r <= scan_.range_max;
      if (certain_[i] != kNone) {
        ++s.with_truth;
        if (has_return) ++s.found;
      }
      if (shortest_[i] == kNone) {
        ++s.without_truth;
        if (has_return) ++s.spurious;
        continue;
      }
      if (!has_return) continue;
      const double error = std::max({0.0, shortest_[i] - r, r - certain_[i]});
      ++s.returns;
      s.error_sum += error;
      s.error_max = std::max(s.error_max, error);
    }
  }

 private:
  static constexpr double kNone = std::numeric_limits<double>::infinity();
  const msgs::LaserScan& scan_;
  std::vector<double> shortest_, certain_;
};

// depth_laser_scan: the scan of a depth image's central rows against their true points.
class DepthLaserScanEvaluator final : public FunctionalEvaluator {
 public:
  DepthLaserScanEvaluator(const DatasetStream& depth, const DatasetStream& info, int scan_height)
      : depth_(depth), info_(info), scan_height_(scan_height) {
    plugin::require_type<msgs::Image>(depth, "depth_laser_scan");
    plugin::require_type<msgs::CameraInfo>(info, "depth_laser_scan");
  }

  void add(const void* output, std::size_t frame) override {
    const auto& scan = *static_cast<const msgs::LaserScan*>(output);
    const auto& truth = *static_cast<const msgs::Image*>(depth_.messages[frame].get());
    const auto& info = *static_cast<const msgs::CameraInfo*>(info_.messages[frame].get());
    if (truth.encoding != "64FC1") {
      throw std::invalid_argument("depth_laser_scan: truth depth must be 64FC1 metres, is " +
                                  truth.encoding);
    }
    if (scan.ranges.size() != truth.width) {
      problem("scan has " + std::to_string(scan.ranges.size()) +
              " beams, expected one per column (" + std::to_string(truth.width) + ")");
      return;
    }
    const double fx = info.p[0], cx = info.p[2], cy = info.p[6];
    // The outermost columns' angles of the ideal camera (D all zero).
    const double angle_max = std::atan2(cx, fx), angle_min = -std::atan2(truth.width - 1 - cx, fx);
    if (std::abs(scan.angle_max - angle_max) > 1e-5 ||
        std::abs(scan.angle_min - angle_min) > 1e-5) {
      problem("scan spans " + number(scan.angle_min) + " .. " + number(scan.angle_max) +
              " rad, the camera's columns " + number(angle_min) + " .. " + number(angle_max));
    }
    const cv::Mat gt = perception::image_view(truth);
    const auto first = static_cast<int>(cy - scan_height_ / 2.0);
    BeamTruth beams(scan);
    for (int v = std::max(first, 0); v < std::min(first + scan_height_, gt.rows); ++v) {
      const double* row = gt.ptr<double>(v);
      for (int u = 0; u < gt.cols; ++u) {
        const double z = row[u];
        if (std::isnan(z)) continue;
        beams.add(std::hypot((u - cx) * z / fx, z), std::atan2(cx - u, fx));
      }
    }
    beams.score(score_);
  }

  std::map<std::string, double> metrics() const override { return score_.metrics(); }

 private:
  const DatasetStream& depth_;
  const DatasetStream& info_;
  int scan_height_;
  ScanScore score_;
};

struct DepthScanScoring {
  int scan_height = 0;
};

const plugin::ParameterStruct<DepthScanScoring> kDepthScanScoring{plugin::field(
    &DepthScanScoring::scan_height, "scan_height", DepthToScanParams{}.scan_height,
    "the node's scan_height: rows about the principal point the scan covers", {.minimum = 1})};

struct CloudScanScoring {
  double min_height = 0, max_height = 0;
};

const plugin::ParameterStruct<CloudScanScoring> kCloudScanScoring{
    plugin::field(&CloudScanScoring::min_height, "min_height", CloudToScanParams{}.min_height,
                  "the node's min_height, m"),
    plugin::field(&CloudScanScoring::max_height, "max_height", CloudToScanParams{}.max_height,
                  "the node's max_height, m")};

// cloud_laser_scan: the scan of a depth camera's cloud in its body frame against the true points
// between two heights.
class CloudLaserScanEvaluator final : public FunctionalEvaluator {
 public:
  CloudLaserScanEvaluator(const DatasetStream& depth, const DatasetStream& info,
                          const CloudScanScoring& heights)
      : depth_(depth), info_(info), heights_(heights) {
    plugin::require_type<msgs::Image>(depth, "cloud_laser_scan");
    plugin::require_type<msgs::CameraInfo>(info, "cloud_laser_scan");
  }

  void add(const void* output, std::size_t frame) override {
    const auto& scan = *static_cast<const msgs::LaserScan*>(output);
    const auto& truth = *static_cast<const msgs::Image*>(depth_.messages[frame].get());
    const auto& info = *static_cast<const msgs::CameraInfo*>(info_.messages[frame].get());
    if (truth.encoding != "64FC1") {
      throw std::invalid_argument("cloud_laser_scan: truth depth must be 64FC1 metres, is " +
                                  truth.encoding);
    }
    const double beams = std::ceil((scan.angle_max - scan.angle_min) / scan.angle_increment);
    if (!(scan.angle_increment > 0) || static_cast<double>(scan.ranges.size()) != beams) {
      problem("scan has " + std::to_string(scan.ranges.size()) + " beams, its angles make " +
              number(beams));
      return;
    }
    // Margins of the float cloud's rounding, a metre's 1e-7, and of the float angles.
    constexpr double kHeightMargin = 1e-5, kAngleMargin = 1e-6;
    const cv::Mat gt = perception::image_view(truth);
    BeamTruth truth_beams(scan);
    for (int v = 0; v < gt.rows; ++v) {
      const double* row = gt.ptr<double>(v);
      for (int u = 0; u < gt.cols; ++u) {
        if (std::isnan(row[u])) continue;
        const BodyPoint p = camera_body_point(info, u, v, row[u]);
        if (p.z < heights_.min_height - kHeightMargin || p.z > heights_.max_height + kHeightMargin)
          continue;
        const double angle = std::atan2(p.y, p.x);
        if (angle < scan.angle_min - kAngleMargin || angle > scan.angle_max + kAngleMargin)
          continue;
        const bool sure = p.z >= heights_.min_height + kHeightMargin &&
                          p.z <= heights_.max_height - kHeightMargin &&
                          angle >= scan.angle_min + kAngleMargin &&
                          angle <= scan.angle_max - kAngleMargin;
        truth_beams.add(std::hypot(p.x, p.y), angle, sure);
      }
    }
    truth_beams.score(score_);
  }

  std::map<std::string, double> metrics() const override { return score_.metrics(); }

 private:
  const DatasetStream& depth_;
  const DatasetStream& info_;
  CloudScanScoring heights_;
  ScanScore score_;
};

}  // namespace

void register_evaluators(plugin::Registrar& registrar) {
  registrar.add_evaluator(
      {.name = "stereo_disparity",
       .description = "disparity against the true disparity of the left view, over the pixels of "
                      "the output's valid window whose true disparity is known and inside its "
                      "search range",
       .output_type = "stereo_msgs/msg/DisparityImage",
       .truth_roles = {"disparity"},
       .metrics = {{"valid_fraction", "fraction", "pixels with a disparity in the search range"},
                   {"bad1", "fraction", "valid pixels more than 1 px off the truth (bad-1)"},
                   {"mae_px", "px", "mean absolute disparity error of the valid pixels"}}},
      [](const plugin::TruthStreams& truth, const plugin::Parameters&) {
        return std::make_unique<StereoDisparityEvaluator>(truth["disparity"]);
      });
  registrar.add_evaluator(
      {.name = "depth_point_cloud",
       .description =
           "organised point cloud against the scene's true 3D points and the colour image",
       .output_type = "sensor_msgs/msg/PointCloud2",
       .truth_roles = {"depth", "camera_info", "image"},
       .metrics = {{"valid_fraction", "fraction",
                    "points with depth in the scene that the cloud has"},
                   {"mean_error_m", "m", "mean distance of valid points to the true point"},
                   {"max_error_m", "m", "largest distance of a valid point to the true point"},
                   {"spurious_fraction", "fraction",
                    "pixels without depth that the cloud has a point for"},
                   {"colour_match", "fraction", "valid points whose rgb equals the colour pixel"}}},
      [](const plugin::TruthStreams& truth, const plugin::Parameters&) {
        return std::make_unique<DepthPointCloudEvaluator>(truth["depth"], truth["camera_info"],
                                                          truth["image"]);
      });
  registrar.add_evaluator(
      {.name = "stereo_point_cloud",
       .description = "organised point cloud of a disparity image against the 3D points of the "
                      "true disparity",
       .output_type = "sensor_msgs/msg/PointCloud2",
       .truth_roles = {"disparity", "camera_info"},
       .metrics = {{"valid_fraction", "fraction",
                    "points with a true disparity that the cloud has"},
                   {"mean_error_m", "m", "mean distance of valid points to the true point"},
                   {"max_relative_error", "fraction",
                    "largest distance of a valid point to the true point, over the true point's "
                    "distance from the camera"},
                   {"spurious_fraction", "fraction",
                    "pixels without a true disparity that the cloud has a point for"}}},
      [](const plugin::TruthStreams& truth, const plugin::Parameters&) {
        return std::make_unique<StereoPointCloudEvaluator>(truth["disparity"],
                                                           truth["camera_info"]);
      });
  registrar.add_evaluator(
      {.name = "depth_laser_scan",
       .description = "LaserScan of a depth image's central rows against the true planar range "
                      "of their points, beam by beam",
       .output_type = "sensor_msgs/msg/LaserScan",
       .truth_roles = {"depth", "camera_info"},
       .metrics = kScanMetrics,
       .parameters = kDepthScanScoring.declarations()},
      [](const plugin::TruthStreams& truth, const plugin::Parameters& p) {
        return std::make_unique<DepthLaserScanEvaluator>(truth["depth"], truth["camera_info"],
                                                         kDepthScanScoring.read(p).scan_height);
      });
  registrar.add_evaluator(
      {.name = "cloud_laser_scan",
       .description = "LaserScan of a depth camera's cloud in its body frame against the true "
                      "planar range of the points between two heights, beam by beam",
       .output_type = "sensor_msgs/msg/LaserScan",
       .truth_roles = {"depth", "camera_info"},
       .metrics = kScanMetrics,
       .parameters = kCloudScanScoring.declarations()},
      [](const plugin::TruthStreams& truth, const plugin::Parameters& p) {
        return std::make_unique<CloudLaserScanEvaluator>(truth["depth"], truth["camera_info"],
                                                         kCloudScanScoring.read(p));
      });
}

}  // namespace robotperf::perception
