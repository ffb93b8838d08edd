// Functional evaluators of the perception benchmarks.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "category.hpp"
#include "robotperf/msgs/stereo_msgs.hpp"
#include "robotperf/perception/image_proc.hpp"

namespace robotperf::perception {
namespace {

using plugin::DatasetStream;
using plugin::FunctionalEvaluator;

std::string number(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

// The float32 field `name` of a cloud's points, if it has one inside its point_step.
const msgs::PointField* field(const msgs::PointCloud2& cloud, const char* name) {
  for (const auto& f : cloud.fields) {
    if (f.name == name && f.datatype == msgs::PointField::kFloat32 && f.count == 1 &&
        uint64_t{f.offset} + 4 <= cloud.point_step) {
      return &f;
    }
  }
  return nullptr;
}

float read_float(const uint8_t* point, const msgs::PointField& f) {
  float value;
  std::memcpy(&value, point + f.offset, sizeof value);
  return value;
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
  XyzFields f{field(cloud, "x"), field(cloud, "y"), field(cloud, "z"), {}};
  if (!f.x || !f.y || !f.z || cloud.is_bigendian ||
      uint64_t{cloud.row_step} * cloud.height > cloud.data.size() ||
      uint64_t{cloud.point_step} * cloud.width > cloud.row_step) {
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
    const msgs::PointField* frgb = field(cloud, "rgb");
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
}

}  // namespace robotperf::perception
