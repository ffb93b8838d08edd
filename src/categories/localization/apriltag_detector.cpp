#include "robotperf/localization/apriltag_detector.hpp"

#include <apriltag/apriltag.h>
#include <apriltag/tag16h5.h>
#include <apriltag/tag25h9.h>
#include <apriltag/tag36h11.h>

#include <cmath>
#include <opencv2/calib3d.hpp>
#include <stdexcept>
#include <vector>

#include "quaternion.hpp"
#include "robotperf/perception/image_proc.hpp"

namespace robotperf::localization {
namespace {

struct FamilyFunctions {
  const char* name;
  apriltag_family_t* (*create)();
  void (*destroy)(apriltag_family_t*);
};

constexpr FamilyFunctions kFamilies[] = {
    {"16h5", tag16h5_create, tag16h5_destroy},
    {"25h9", tag25h9_create, tag25h9_destroy},
    {"36h11", tag36h11_create, tag36h11_destroy},
};

const FamilyFunctions* find_family(const std::string& name) {
  for (const FamilyFunctions& f : kFamilies) {
    if (name == f.name) return &f;
  }
  return nullptr;
}

}  // namespace

void validate(const AprilTagParams& p) {
  if (find_family(p.family) == nullptr)
    throw std::invalid_argument("family '" + p.family + "' is not 16h5, 25h9 or 36h11");
  if (!(p.size > 0.0)) throw std::invalid_argument("size must be > 0 m");
  if (p.max_hamming < 0 || p.max_hamming > 2)
    throw std::invalid_argument("max_hamming must be 0, 1 or 2");
  if (!(p.decimate >= 1.0)) throw std::invalid_argument("decimate must be >= 1");
  if (p.threads < 1) throw std::invalid_argument("threads must be >= 1");
  if (!std::isfinite(p.blur) || !std::isfinite(p.sharpening))
    throw std::invalid_argument("blur and sharpening must be finite");
}

struct AprilTagDetector::Library {
  const FamilyFunctions* functions = nullptr;
  apriltag_family_t* family = nullptr;
  apriltag_detector_t* detector = nullptr;
  cv::Mat grey;
  perception::Rectifier rectifier;
  msgs::Image rectified;
  ~Library() {
    if (detector != nullptr) apriltag_detector_destroy(detector);
    if (family != nullptr) functions->destroy(family);
  }
};

AprilTagDetector::AprilTagDetector(const AprilTagParams& params)
    : params_(params), library_(std::make_unique<Library>()) {
  validate(params_);
  library_->functions = find_family(params_.family);
  library_->family = library_->functions->create();
  library_->detector = apriltag_detector_create();
  apriltag_detector_t* d = library_->detector;
  apriltag_detector_add_family_bits(d, library_->family, params_.max_hamming);
  d->quad_decimate = static_cast<float>(params_.decimate);
  d->quad_sigma = static_cast<float>(params_.blur);
  d->nthreads = params_.threads;
  d->refine_edges = params_.refine_edges;
  d->decode_sharpening = params_.sharpening;
}

AprilTagDetector::~AprilTagDetector() = default;

void AprilTagDetector::detect(const msgs::Image& image, const msgs::CameraInfo& info,
                              msgs::AprilTagDetectionArray& detections, msgs::PoseArray& poses) {
  if (info.p[0] == 0.0)
    throw std::invalid_argument("apriltag: camera is not calibrated (P[0] = 0)");
  if (image.width != info.width || image.height != info.height) {
    throw std::invalid_argument("apriltag: image is " + std::to_string(image.width) + "x" +
                                std::to_string(image.height) + " but its CameraInfo " +
                                std::to_string(info.width) + "x" + std::to_string(info.height));
  }
  cv::Mat& grey = library_->grey;
  if (params_.rectify) {
    // Rectified first (the cached undistortion map of image_proc), then grey.
    library_->rectifier.rectify(image, info, library_->rectified);
    perception::to_mono8(library_->rectified, "apriltag: image", grey);
  } else {
    perception::to_mono8(image, "apriltag: image", grey);
  }
  image_u8_t frame{grey.cols, grey.rows, static_cast<int32_t>(grey.step[0]), grey.data};
  zarray_t* found = apriltag_detector_detect(library_->detector, &frame);

  detections.header = image.header;
  detections.detections.clear();
  poses.header = image.header;
  poses.poses.clear();
  const cv::Matx33d camera(info.p[0], 0.0, info.p[2], 0.0, info.p[5], info.p[6], 0.0, 0.0, 1.0);
  const double half = 0.5 * params_.size;
  // IPPE_SQUARE's corner order in libapriltag's tag frame (x right, y down, z into the tag).
  const std::vector<cv::Point3d> square{
      {-half, half, 0.0}, {half, half, 0.0}, {half, -half, 0.0}, {-half, -half, 0.0}};
  std::vector<cv::Point2d> corners(4);
  for (int i = 0; i < zarray_size(found); ++i) {
    apriltag_detection_t* d = nullptr;
    zarray_get(found, i, &d);
    msgs::AprilTagDetection out;
    out.family = params_.family;
    out.id = d->id;
    out.hamming = d->hamming;
    out.decision_margin = d->decision_margin;
    // libapriltag puts the first pixel's centre at (0.5, 0.5).
    out.centre = {d->c[0] - 0.5, d->c[1] - 0.5};
    for (std::size_t c = 0; c < 4; ++c) {
      out.corners[c] = {d->p[c][0] - 0.5, d->p[c][1] - 0.5};
      corners[c] = {out.corners[c].x, out.corners[c].y};
    }
    const double* h = d->H->data;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) {
        const double shifted = r < 2 ? h[3 * r + c] - 0.5 * h[6 + c] : h[6 + c];
        out.homography[static_cast<std::size_t>(3 * r + c)] = shifted / h[8];
      }
    }
    detections.detections.push_back(std::move(out));

    cv::Vec3d rvec, tvec;
    cv::solvePnP(square, corners, camera, cv::noArray(), rvec, tvec, false,
                 cv::SOLVEPNP_IPPE_SQUARE);
    cv::Matx33d r;
    cv::Rodrigues(rvec, r);
    // To the tag frame with y up and z out of the face: flip y and z.
    for (int row = 0; row < 3; ++row) {
      r(row, 1) = -r(row, 1);
      r(row, 2) = -r(row, 2);
    }
    msgs::Pose pose;
    pose.position = {tvec[0], tvec[1], tvec[2]};
    pose.orientation = quaternion_from_matrix(r);
    poses.poses.push_back(pose);
  }
  apriltag_detections_destroy(found);
}

}  // namespace robotperf::localization
