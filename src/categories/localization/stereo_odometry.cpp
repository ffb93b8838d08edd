#include "robotperf/localization/stereo_odometry.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <opencv2/calib3d.hpp>
#include <opencv2/features2d.hpp>
#include <stdexcept>
#include <string>
#include <vector>

namespace robotperf::localization {
namespace {

constexpr int kDescriptorBytes = 32;  // ORB: 256 bits
constexpr int kBorderPx = 16;         // keeps the 31 px descriptor patch inside the image
constexpr int kBlockRadius = 4;       // sub-pixel refinement window: 9 x 9
constexpr int kMinImageSide = 64;
constexpr double kMinDepthM = 0.05;  // points closer to a predicted camera are not searched

int hamming(const uint8_t* a, const uint8_t* b) {
  int distance = 0;
  for (int i = 0; i < kDescriptorBytes; i += 8) {
    uint64_t x = 0;
    uint64_t y = 0;
    std::memcpy(&x, a + i, 8);
    std::memcpy(&y, b + i, 8);
    distance += std::popcount(x ^ y);
  }
  return distance;
}

// The two closest candidates of a descriptor by Hamming distance, and whether the closest is a
// match: near enough, and clearly nearer than the second (the ratio test).
struct BestMatch {
  int best = std::numeric_limits<int>::max();
  int second = std::numeric_limits<int>::max();
  int index = -1;

  void offer(int distance, int candidate) {
    if (distance < best) {
      second = best;
      best = distance;
      index = candidate;
    } else if (distance < second) {
      second = distance;
    }
  }
  bool accepted(const StereoOdometryOptions& options) const {
    return index >= 0 && best <= options.max_descriptor_distance &&
           (second == std::numeric_limits<int>::max() || best < options.ratio * second);
  }
};

struct Features {
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;  // CV_8U, one row of kDescriptorBytes per keypoint
};

// Feature indices binned on a square grid, for the features near a point.
class FeatureGrid {
 public:
  FeatureGrid(const std::vector<cv::KeyPoint>& keypoints, cv::Size size, int cell_px)
      : cell_px_(cell_px),
        columns_((size.width + cell_px - 1) / cell_px),
        rows_((size.height + cell_px - 1) / cell_px),
        start_(static_cast<std::size_t>(columns_ * rows_) + 1, 0),
        index_(keypoints.size()) {
    std::vector<int> cell_of(keypoints.size());
    for (std::size_t i = 0; i < keypoints.size(); ++i) {
      cell_of[i] = cell(keypoints[i].pt);
      ++start_[static_cast<std::size_t>(cell_of[i]) + 1];
    }
    for (std::size_t c = 1; c < start_.size(); ++c) start_[c] += start_[c - 1];
    std::vector<int> fill(start_.begin(), start_.end() - 1);
    for (std::size_t i = 0; i < keypoints.size(); ++i) {
      index_[static_cast<std::size_t>(fill[static_cast<std::size_t>(cell_of[i])]++)] =
          static_cast<int>(i);
    }
  }

  // Calls visit(index) for every feature in the cells that overlap the square of half-side
  // `radius` around `centre` (a superset of those within the radius).
  template <class Visit>
  void for_each_near(cv::Point2f centre, double radius, Visit&& visit) const {
    const int c0 = std::max(0, static_cast<int>(std::floor((centre.x - radius) / cell_px_)));
    const int c1 =
        std::min(columns_ - 1, static_cast<int>(std::floor((centre.x + radius) / cell_px_)));
    const int r0 = std::max(0, static_cast<int>(std::floor((centre.y - radius) / cell_px_)));
    const int r1 =
        std::min(rows_ - 1, static_cast<int>(std::floor((centre.y + radius) / cell_px_)));
    for (int r = r0; r <= r1; ++r) {
      for (int c = c0; c <= c1; ++c) {
        const auto cell_index = static_cast<std::size_t>(r * columns_ + c);
        for (int k = start_[cell_index]; k < start_[cell_index + 1]; ++k) {
          visit(index_[static_cast<std::size_t>(k)]);
        }
      }
    }
  }

 private:
  int cell(cv::Point2f p) const {
    const int c = std::clamp(static_cast<int>(p.x) / cell_px_, 0, columns_ - 1);
    const int r = std::clamp(static_cast<int>(p.y) / cell_px_, 0, rows_ - 1);
    return r * columns_ + c;
  }

  int cell_px_, columns_, rows_;
  std::vector<int> start_;  // features of cell c: index_[start_[c] .. start_[c + 1])
  std::vector<int> index_;
};

// Sum of squared differences between the (2 kBlockRadius + 1)^2 blocks around left (u, v) and
// right (u - disparity, v); the caller keeps both blocks inside the images.
int block_ssd(const cv::Mat& left, const cv::Mat& right, int u, int v, int disparity) {
  int sum = 0;
  for (int dv = -kBlockRadius; dv <= kBlockRadius; ++dv) {
    const uint8_t* l = left.ptr<uint8_t>(v + dv) + u;
    const uint8_t* r = right.ptr<uint8_t>(v + dv) + u - disparity;
    for (int du = -kBlockRadius; du <= kBlockRadius; ++du) {
      const int d = l[du] - r[du];
      sum += d * d;
    }
  }
  return sum;
}

void validate(const StereoCalibration& c, const StereoOdometryOptions& o) {
  auto require = [](bool ok, const char* what) {
    if (!ok) throw std::invalid_argument(std::string("stereo odometry: ") + what);
  };
  require(std::isfinite(c.fx) && c.fx > 0.0, "fx must be positive and finite");
  require(std::isfinite(c.fy) && c.fy > 0.0, "fy must be positive and finite");
  require(std::isfinite(c.cx) && std::isfinite(c.cy) && std::isfinite(c.right_cx),
          "cx, cy and right_cx must be finite");
  require(std::isfinite(c.baseline_m) && c.baseline_m > 0.0,
          "baseline_m must be positive and finite");
  require(o.max_features > 0, "max_features must be positive");
  require(o.grid_columns > 0 && o.grid_rows > 0, "grid_columns and grid_rows must be positive");
  require(o.fast_threshold >= 1 && o.fast_threshold <= 255, "fast_threshold must be in 1 .. 255");
  require(o.max_row_offset_px >= 0.0, "max_row_offset_px must be >= 0");
  require(o.min_disparity_px > 0.0 && o.max_disparity_px > o.min_disparity_px,
          "disparities must satisfy 0 < min_disparity_px < max_disparity_px");
  require(o.max_descriptor_distance >= 0 && o.max_descriptor_distance <= 8 * kDescriptorBytes,
          "max_descriptor_distance must be in 0 .. 256");
  require(o.ratio > 0.0 && o.ratio <= 1.0, "ratio must be in (0, 1]");
  require(o.search_radius_px > 0.0 && o.unpredicted_search_radius_px > 0.0,
          "search radii must be positive");
  require(o.ransac_reprojection_px > 0.0, "ransac_reprojection_px must be positive");
  require(o.ransac_iterations > 0, "ransac_iterations must be positive");
  require(o.min_inliers >= 6, "min_inliers must be >= 6");
  require(o.keyframe_inlier_fraction >= 0.0 && o.keyframe_inlier_fraction <= 1.0,
          "keyframe_inlier_fraction must be in [0, 1]");
  require(o.keyframe_min_inliers >= 0, "keyframe_min_inliers must be >= 0");
}

Eigen::Isometry3d isometry_of(const cv::Mat& rvec, const cv::Mat& tvec) {
  cv::Mat r;
  cv::Rodrigues(rvec, r);
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) t.linear()(i, j) = r.at<double>(i, j);
    t.translation()(i) = tvec.at<double>(i);
  }
  return t;
}

void rvec_tvec_of(const Eigen::Isometry3d& t, cv::Mat& rvec, cv::Mat& tvec) {
  cv::Mat r(3, 3, CV_64F);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) r.at<double>(i, j) = t.linear()(i, j);
  }
  cv::Rodrigues(r, rvec);
  tvec = (cv::Mat_<double>(3, 1) << t.translation().x(), t.translation().y(), t.translation().z());
}

}  // namespace

struct StereoOdometry::State {
  struct Keyframe {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  // T_odom_keyframe
    std::vector<cv::Point3f> points;                         // in the keyframe's left camera
    cv::Mat descriptors;                                     // one row per point
  };

  double fx, fy, cx, cy, baseline_m;
  // What a left pixel's column less its match's is at infinite depth: cx - right_cx.
  double disparity_offset_px;
  StereoOdometryOptions options;
  cv::Ptr<cv::ORB> orb;
  cv::Mat camera_matrix;

  cv::Size image_size;  // of the first frame; empty before it
  bool started = false;
  Keyframe keyframe;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();      // T_odom_current
  Eigen::Isometry3d velocity = Eigen::Isometry3d::Identity();  // T_previous_current
  bool velocity_known = false;  // false: search with the unpredicted radius, then again

  State(const StereoCalibration& c, StereoOdometryOptions o)
      : fx(c.fx),
        fy(c.fy),
        cx(c.cx),
        cy(c.cy),
        baseline_m(c.baseline_m),
        disparity_offset_px(c.cx - c.right_cx),
        options(o) {
    // Upright descriptors on one level: keypoints come from our own FAST with angle 0.
    orb = cv::ORB::create(options.max_features, 1.2f, 1, kBorderPx, 0, 2, cv::ORB::HARRIS_SCORE, 31,
                          options.fast_threshold);
    camera_matrix = (cv::Mat_<double>(3, 3) << fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0);
  }

  // FAST corners at least kBorderPx inside, the strongest max_features / cells per grid cell
  // (at least one), with their descriptors.
  void detect(const cv::Mat& image, Features& out) const {
    std::vector<cv::KeyPoint> corners;
    cv::FAST(image, corners, options.fast_threshold, true);
    const int columns = options.grid_columns;
    const int rows = options.grid_rows;
    const int usable_w = image.cols - 2 * kBorderPx;
    const int usable_h = image.rows - 2 * kBorderPx;
    const auto per_cell =
        static_cast<std::size_t>(std::max(1, options.max_features / (columns * rows)));
    std::vector<std::vector<cv::KeyPoint>> cells(static_cast<std::size_t>(columns * rows));
    for (const cv::KeyPoint& k : corners) {
      const int x = static_cast<int>(k.pt.x) - kBorderPx;
      const int y = static_cast<int>(k.pt.y) - kBorderPx;
      if (x < 0 || y < 0 || x >= usable_w || y >= usable_h) continue;
      const int c = x * columns / usable_w;
      const int r = y * rows / usable_h;
      cells[static_cast<std::size_t>(r * columns + c)].push_back(k);
    }
    out.keypoints.clear();
    for (std::vector<cv::KeyPoint>& cell : cells) {
      if (cell.size() > per_cell) {
        std::nth_element(
            cell.begin(), cell.begin() + static_cast<std::ptrdiff_t>(per_cell), cell.end(),
            [](const cv::KeyPoint& a, const cv::KeyPoint& b) { return a.response > b.response; });
        cell.resize(per_cell);
      }
      for (cv::KeyPoint& k : cell) {
        k.angle = 0.0f;
        k.octave = 0;
        k.size = 31.0f;
        out.keypoints.push_back(k);
      }
    }
    // Fewer cells than max_features can leave more than it: keep the strongest.
    if (out.keypoints.size() > static_cast<std::size_t>(options.max_features)) {
      std::nth_element(
          out.keypoints.begin(), out.keypoints.begin() + options.max_features, out.keypoints.end(),
          [](const cv::KeyPoint& a, const cv::KeyPoint& b) { return a.response > b.response; });
      out.keypoints.resize(static_cast<std::size_t>(options.max_features));
    }
    orb->compute(image, out.keypoints, out.descriptors);
  }

  // Left-right matches of `left` among `right` features, one to one, triangulated in the left
  // camera: `matched` gets the left feature indices, `points` their 3-D points.
  void match_stereo(const Features& left, const Features& right, const cv::Mat& left_image,
                    const cv::Mat& right_image, std::vector<int>& matched,
                    std::vector<cv::Point3f>& points) const {
    matched.clear();
    points.clear();
    if (left.keypoints.empty() || right.keypoints.empty()) return;
    // Right features by row.
    const int height = right_image.rows;
    std::vector<int> row_start(static_cast<std::size_t>(height) + 1, 0);
    for (const cv::KeyPoint& k : right.keypoints) {
      ++row_start[static_cast<std::size_t>(std::clamp(cvRound(k.pt.y), 0, height - 1)) + 1];
    }
    for (std::size_t r = 1; r < row_start.size(); ++r) row_start[r] += row_start[r - 1];
    std::vector<int> by_row(right.keypoints.size());
    {
      std::vector<int> fill(row_start.begin(), row_start.end() - 1);
      for (std::size_t i = 0; i < right.keypoints.size(); ++i) {
        const int r = std::clamp(cvRound(right.keypoints[i].pt.y), 0, height - 1);
        by_row[static_cast<std::size_t>(fill[static_cast<std::size_t>(r)]++)] = static_cast<int>(i);
      }
    }
    // Best left feature for each right feature, so that matches are one to one.
    std::vector<int> owner(right.keypoints.size(), -1);
    std::vector<int> owner_distance(right.keypoints.size(), std::numeric_limits<int>::max());
    std::vector<int> choice(left.keypoints.size(), -1);
    const int row_reach = static_cast<int>(std::floor(options.max_row_offset_px));
    for (std::size_t i = 0; i < left.keypoints.size(); ++i) {
      const cv::Point2f p = left.keypoints[i].pt;
      const uint8_t* d = left.descriptors.ptr<uint8_t>(static_cast<int>(i));
      BestMatch match;
      const int v = cvRound(p.y);
      for (int r = std::max(0, v - row_reach); r <= std::min(height - 1, v + row_reach); ++r) {
        for (int k = row_start[static_cast<std::size_t>(r)];
             k < row_start[static_cast<std::size_t>(r) + 1]; ++k) {
          const int j = by_row[static_cast<std::size_t>(k)];
          const cv::Point2f q = right.keypoints[static_cast<std::size_t>(j)].pt;
          const double disparity = p.x - q.x - disparity_offset_px;
          if (disparity < options.min_disparity_px || disparity > options.max_disparity_px ||
              std::abs(p.y - q.y) > options.max_row_offset_px) {
            continue;
          }
          match.offer(hamming(d, right.descriptors.ptr<uint8_t>(j)), j);
        }
      }
      if (!match.accepted(options)) continue;
      choice[i] = match.index;
      const auto j = static_cast<std::size_t>(match.index);
      if (match.best < owner_distance[j]) {
        owner_distance[j] = match.best;
        owner[j] = static_cast<int>(i);
      }
    }
    for (std::size_t i = 0; i < left.keypoints.size(); ++i) {
      const int j = choice[i];
      if (j < 0 || owner[static_cast<std::size_t>(j)] != static_cast<int>(i)) continue;
      const cv::Point2f p = left.keypoints[i].pt;
      // In the images' columns until refined, then as it is triangulated.
      double disparity = p.x - right.keypoints[static_cast<std::size_t>(j)].pt.x;
      if (options.subpixel && !refine_disparity(left_image, right_image, cvRound(p.x), cvRound(p.y),
                                                cvRound(disparity), disparity)) {
        continue;
      }
      disparity -= disparity_offset_px;
      if (disparity < options.min_disparity_px || disparity > options.max_disparity_px) continue;
      const double z = fx * baseline_m / disparity;
      matched.push_back(static_cast<int>(i));
      points.emplace_back(static_cast<float>((p.x - cx) * z / fx),
                          static_cast<float>((p.y - cy) * z / fy), static_cast<float>(z));
    }
  }

  // The disparity of left pixel (u, v) near `initial`: the best of initial-2 .. initial+2 by
  // SSD, then a parabola through it and its neighbours. False when that best is no local
  // minimum (the match is not where the descriptors put it) or a block leaves an image.
  static bool refine_disparity(const cv::Mat& left, const cv::Mat& right, int u, int v, int initial,
                               double& disparity) {
    constexpr int kReach = 2;
    if (v - kBlockRadius < 0 || v + kBlockRadius >= left.rows || u - kBlockRadius < 0 ||
        u + kBlockRadius >= left.cols || u - initial - kReach - kBlockRadius - 1 < 0 ||
        u - initial + kReach + kBlockRadius + 1 >= right.cols) {
      return false;
    }
    int ssd[2 * kReach + 3];
    for (int k = -kReach - 1; k <= kReach + 1; ++k) {
      ssd[k + kReach + 1] = block_ssd(left, right, u, v, initial + k);
    }
    int best = 1;
    for (int k = 2; k <= 2 * kReach + 1; ++k) {
      if (ssd[k] < ssd[best]) best = k;
    }
    if (ssd[best - 1] < ssd[best] || ssd[best + 1] < ssd[best]) return false;
    const double before = ssd[best - 1];
    const double at = ssd[best];
    const double after = ssd[best + 1];
    const double curvature = before - 2.0 * at + after;
    const double offset = curvature > 0.0 ? 0.5 * (before - after) / curvature : 0.0;
    disparity = initial + (best - kReach - 1) + offset;
    return true;
  }

  void make_keyframe(const Features& left, const std::vector<int>& matched,
                     const std::vector<cv::Point3f>& points) {
    keyframe.pose = pose;
    keyframe.points = points;
    keyframe.descriptors.create(static_cast<int>(matched.size()), kDescriptorBytes, CV_8U);
    for (std::size_t i = 0; i < matched.size(); ++i) {
      left.descriptors.row(matched[i]).copyTo(keyframe.descriptors.row(static_cast<int>(i)));
    }
  }

  // Keyframe points matched to current features near their projection from the predicted pose
  // T_current_keyframe: (keyframe point, current feature) pairs.
  void track(const Features& current, const Eigen::Isometry3d& current_from_keyframe, double radius,
             std::vector<cv::Point3f>& object, std::vector<cv::Point2f>& image) const {
    object.clear();
    image.clear();
    if (keyframe.points.empty() || current.keypoints.empty()) return;
    const FeatureGrid grid(current.keypoints, image_size, 32);
    std::vector<int> owner(current.keypoints.size(), -1);
    std::vector<int> owner_distance(current.keypoints.size(), std::numeric_limits<int>::max());
    const double radius2 = radius * radius;
    for (std::size_t i = 0; i < keyframe.points.size(); ++i) {
      const cv::Point3f& x = keyframe.points[i];
      const Eigen::Vector3d p = current_from_keyframe * Eigen::Vector3d(x.x, x.y, x.z);
      if (p.z() < kMinDepthM) continue;
      const cv::Point2f projected(static_cast<float>(fx * p.x() / p.z() + cx),
                                  static_cast<float>(fy * p.y() / p.z() + cy));
      if (projected.x < -radius || projected.y < -radius ||
          projected.x > image_size.width + radius || projected.y > image_size.height + radius) {
        continue;
      }
      const uint8_t* d = keyframe.descriptors.ptr<uint8_t>(static_cast<int>(i));
      BestMatch match;
      grid.for_each_near(projected, radius, [&](int j) {
        const cv::Point2f q = current.keypoints[static_cast<std::size_t>(j)].pt;
        const double du = q.x - projected.x;
        const double dv = q.y - projected.y;
        if (du * du + dv * dv > radius2) return;
        match.offer(hamming(d, current.descriptors.ptr<uint8_t>(j)), j);
      });
      if (!match.accepted(options)) continue;
      const auto j = static_cast<std::size_t>(match.index);
      if (match.best < owner_distance[j]) {
        owner_distance[j] = match.best;
        owner[j] = static_cast<int>(i);
      }
    }
    for (std::size_t j = 0; j < owner.size(); ++j) {
      if (owner[j] < 0) continue;
      object.push_back(keyframe.points[static_cast<std::size_t>(owner[j])]);
      image.push_back(current.keypoints[j].pt);
    }
  }

  // T_current_keyframe by RANSAC PnP from the prediction, refined on the inliers and then on
  // every match within the RANSAC threshold of that refinement; the inlier count, 0 on failure.
  int estimate(const std::vector<cv::Point3f>& object, const std::vector<cv::Point2f>& image,
               Eigen::Isometry3d& current_from_keyframe) const {
    if (static_cast<int>(object.size()) < options.min_inliers) return 0;
    cv::Mat rvec;
    cv::Mat tvec;
    rvec_tvec_of(current_from_keyframe, rvec, tvec);
    std::vector<int> inliers;
    try {
      if (!cv::solvePnPRansac(object, image, camera_matrix, cv::noArray(), rvec, tvec, true,
                              options.ransac_iterations,
                              static_cast<float>(options.ransac_reprojection_px), 0.999, inliers,
                              cv::SOLVEPNP_ITERATIVE)) {
        return 0;
      }
      if (static_cast<int>(inliers.size()) < options.min_inliers) return 0;
      // Refine on the inliers, then once more on every match consistent with the refined pose.
      for (int pass = 0; pass < 2; ++pass) {
        std::vector<cv::Point3f> object_inliers;
        std::vector<cv::Point2f> image_inliers;
        for (const int i : inliers) {
          object_inliers.push_back(object[static_cast<std::size_t>(i)]);
          image_inliers.push_back(image[static_cast<std::size_t>(i)]);
        }
        cv::solvePnPRefineLM(object_inliers, image_inliers, camera_matrix, cv::noArray(), rvec,
                             tvec);
        if (pass == 1) break;
        std::vector<cv::Point2f> projected;
        cv::projectPoints(object, rvec, tvec, camera_matrix, cv::noArray(), projected);
        inliers.clear();
        const double limit2 = options.ransac_reprojection_px * options.ransac_reprojection_px;
        for (std::size_t i = 0; i < image.size(); ++i) {
          const cv::Point2f e = projected[i] - image[i];
          if (e.x * e.x + e.y * e.y <= limit2) inliers.push_back(static_cast<int>(i));
        }
        if (static_cast<int>(inliers.size()) < options.min_inliers) return 0;
      }
    } catch (const cv::Exception&) {
      return 0;  // degenerate geometry: treated as lost, never thrown
    }
    current_from_keyframe = isometry_of(rvec, tvec);
    if (!current_from_keyframe.matrix().allFinite()) return 0;
    return static_cast<int>(inliers.size());
  }

  StereoOdometryResult process(const cv::Mat& left_image, const cv::Mat& right_image) {
    Features left;
    Features right;
    detect(left_image, left);
    detect(right_image, right);
    std::vector<int> matched;
    std::vector<cv::Point3f> points;
    match_stereo(left, right, left_image, right_image, matched, points);

    StereoOdometryResult result;
    result.features = static_cast<int>(left.keypoints.size());
    result.stereo_matches = static_cast<int>(matched.size());
    if (!started) {
      started = true;
      pose = Eigen::Isometry3d::Identity();
      make_keyframe(left, matched, points);
      result.pose = pose;
      result.new_keyframe = true;
      return result;
    }

    const Eigen::Isometry3d predicted = pose * velocity;
    Eigen::Isometry3d current_from_keyframe = predicted.inverse() * keyframe.pose;
    std::vector<cv::Point3f> object;
    std::vector<cv::Point2f> image;
    track(left, current_from_keyframe,
          velocity_known ? options.search_radius_px : options.unpredicted_search_radius_px, object,
          image);
    result.tracked = static_cast<int>(object.size());
    result.inliers = estimate(object, image, current_from_keyframe);
    if (result.inliers >= options.min_inliers && !velocity_known) {
      // The wide search may have settled on a few matches only: match again, with the
      // predicted radius, around the first estimate's projections.
      Eigen::Isometry3d guided = current_from_keyframe;
      track(left, guided, options.search_radius_px, object, image);
      const int inliers = estimate(object, image, guided);
      if (inliers >= result.inliers) {
        result.tracked = static_cast<int>(object.size());
        result.inliers = inliers;
        current_from_keyframe = guided;
      }
    }

    const Eigen::Isometry3d previous = pose;
    bool replace_keyframe = false;
    if (result.inliers >= options.min_inliers) {
      pose = keyframe.pose * current_from_keyframe.inverse();
      velocity = previous.inverse() * pose;
      velocity_known = true;
      replace_keyframe = result.inliers < options.keyframe_min_inliers ||
                         result.inliers < options.keyframe_inlier_fraction *
                                              static_cast<double>(keyframe.points.size());
    } else {
      // Coast on the constant velocity and start again from this frame.
      result.inliers = 0;
      result.tracking_lost = true;
      replace_keyframe = true;
      pose = predicted;
      velocity_known = false;
    }
    // A frame with too few stereo points would make a keyframe that cannot be tracked: the old
    // one stays (it may still be tracked once the images are usable again).
    if (replace_keyframe && result.stereo_matches >= options.min_inliers) {
      make_keyframe(left, matched, points);
      result.new_keyframe = true;
    }
    result.pose = pose;
    return result;
  }
};

StereoOdometry::StereoOdometry(const StereoCalibration& calibration,
                               const StereoOdometryOptions& options) {
  validate(calibration, options);
  state_ = std::make_unique<State>(calibration, options);
}

StereoOdometry::StereoOdometry(double fx, double fy, double cx, double cy, double baseline_m,
                               const StereoOdometryOptions& options)
    : StereoOdometry(StereoCalibration{fx, fy, cx, cy, cx, baseline_m}, options) {}

StereoOdometry::~StereoOdometry() = default;
StereoOdometry::StereoOdometry(StereoOdometry&&) noexcept = default;
StereoOdometry& StereoOdometry::operator=(StereoOdometry&&) noexcept = default;

StereoOdometryResult StereoOdometry::process(const cv::Mat& left, const cv::Mat& right) {
  if (left.empty() || right.empty()) {
    throw std::invalid_argument("stereo odometry: empty image");
  }
  if (left.type() != CV_8UC1 || right.type() != CV_8UC1) {
    throw std::invalid_argument("stereo odometry: images must be CV_8UC1 (mono8)");
  }
  if (left.size() != right.size()) {
    throw std::invalid_argument("stereo odometry: left and right images differ in size");
  }
  if (left.cols < kMinImageSide || left.rows < kMinImageSide) {
    throw std::invalid_argument("stereo odometry: images must be at least 64x64");
  }
  State& s = *state_;
  if (!s.started) {
    s.image_size = left.size();
  } else if (left.size() != s.image_size) {
    throw std::invalid_argument("stereo odometry: image size differs from the first frame's");
  }
  return s.process(left, right);
}

void StereoOdometry::reset() {
  State& s = *state_;
  s.started = false;
  s.image_size = cv::Size();
  s.keyframe = {};
  s.pose = Eigen::Isometry3d::Identity();
  s.velocity = Eigen::Isometry3d::Identity();
  s.velocity_known = false;
}

const StereoOdometryOptions& StereoOdometry::options() const {
  return state_->options;
}

}  // namespace robotperf::localization
