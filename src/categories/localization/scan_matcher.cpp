#include "robotperf/localization/scan_matcher.hpp"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <thread>

namespace robotperf::localization {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr int kMaxDepth = 10;
// The default angular step moves the farthest point by one cell, so an interval of 2^L steps
// sweeps it over about 2^L cells: windows up to 2^(L+1) cells, one level above the node's.
// A second spare level covers rounding; points needing more (a coarser user-given step) are
// bounded by the map's maximum.
constexpr int kSpareLevels = 2;
constexpr int kMaxLevels = kMaxDepth + kSpareLevels + 1;
// Far enough that the squared distance transform treats it as "no obstacle" without overflow.
constexpr double kNoObstacle = 1e30;
// Limits that keep the free-cell counts and the score sums (255 per point) within 32 bits.
constexpr uint32_t kMaxCellsASide = 16384;
constexpr std::size_t kMaxPoints = 100000;
// Yaw steps a turn, at most: the search's tables grow with them (and their count must fit an
// int). The derived step, about 1 / r for the farthest point r cells away, stays under it: r is
// at most the map's width + height, 32768 cells: 205888 steps.
constexpr int kMaxAngles = 1 << 18;

double wrap_angle(double a) {
  a = std::remainder(a, 2.0 * kPi);
  return a <= -kPi ? a + 2.0 * kPi : a;
}

// The lower envelope of the parabolas (q - p)^2 + f[p], evaluated at every q: one pass of the
// exact squared Euclidean distance transform of Felzenszwalb and Huttenlocher ("Distance
// Transforms of Sampled Functions", Theory of Computing 8, 2012).
void lower_envelope(const double* f, int n, double* out, std::vector<int>& vertex,
                    std::vector<double>& boundary) {
  auto crossing = [f](int q, int p) {
    return ((f[q] + static_cast<double>(q) * q) - (f[p] + static_cast<double>(p) * p)) /
           (2.0 * (q - p));
  };
  vertex.assign(static_cast<std::size_t>(n), 0);
  boundary.assign(static_cast<std::size_t>(n) + 1, 0.0);
  int k = 0;
  boundary[0] = -std::numeric_limits<double>::infinity();
  boundary[1] = std::numeric_limits<double>::infinity();
  for (int q = 1; q < n; ++q) {
    double s = crossing(q, vertex[k]);
    while (s <= boundary[k]) {
      --k;
      s = crossing(q, vertex[k]);
    }
    ++k;
    vertex[k] = q;
    boundary[k] = s;
    boundary[k + 1] = std::numeric_limits<double>::infinity();
  }
  k = 0;
  for (int q = 0; q < n; ++q) {
    while (boundary[k + 1] < q) ++k;
    const double d = q - vertex[k];
    out[q] = d * d + f[vertex[k]];
  }
}

// Squared distance in cells from every cell centre to the nearest obstacle's centre.
std::vector<double> squared_distances(const std::vector<uint8_t>& obstacle, int width, int height) {
  std::vector<double> grid(obstacle.size());
  for (std::size_t i = 0; i < obstacle.size(); ++i) grid[i] = obstacle[i] ? 0.0 : kNoObstacle;
  std::vector<int> vertex;
  std::vector<double> boundary;
  std::vector<double> line(static_cast<std::size_t>(std::max(width, height)));
  std::vector<double> result(line.size());
  for (int x = 0; x < width; ++x) {
    for (int y = 0; y < height; ++y) line[y] = grid[static_cast<std::size_t>(y) * width + x];
    lower_envelope(line.data(), height, result.data(), vertex, boundary);
    for (int y = 0; y < height; ++y) grid[static_cast<std::size_t>(y) * width + x] = result[y];
  }
  for (int y = 0; y < height; ++y) {
    double* row = grid.data() + static_cast<std::size_t>(y) * width;
    lower_envelope(row, width, result.data(), vertex, boundary);
    std::copy(result.begin(), result.begin() + width, row);
  }
  return grid;
}

struct Point {
  double x, y;
};

// One lattice pose: angle index, and the cell the robot's origin is at.
struct Leaf {
  uint32_t score;  // sum over the points of the quantised likelihood (255 = 1)
  int32_t angle;
  int32_t cx;
  int32_t cy;
};

// Highest score first; equal scores in a fixed order, so that the answer does not depend on the
// order (or the threads) in which the tree was searched.
bool better(const Leaf& a, const Leaf& b) {
  if (a.score != b.score) return a.score > b.score;
  if (a.angle != b.angle) return a.angle < b.angle;
  if (a.cy != b.cy) return a.cy < b.cy;
  return a.cx < b.cx;
}

struct Pose {
  double x, y, yaw;
};

// The map as the search reads it, built once.
struct MatchGrids {
  GlobalLocalizerOptions options;
  int width = 0;
  int height = 0;
  double resolution = 0;
  double origin_x = 0;
  double origin_y = 0;
  // Likelihood of each cell, for the refinement's interpolation.
  std::vector<float> likelihood;
  // Level m holds, at (x, y) for x in [-2^m, width] and y in [-2^m, height], the maximum of the
  // quantised likelihood over cells [x, x + 2^m) x [y, y + 2^m) (zero outside the map), so that
  // the columns and rows just outside read zero and any lookup can be clamped onto them. All
  // levels share one row stride: a point's offset from a node's corner is the same at every
  // level.
  int top_level = 0;
  std::ptrdiff_t stride = 0;
  std::vector<uint8_t> max_grids;
  std::array<std::ptrdiff_t, kMaxLevels> level_origin{};  // index of (0, 0) in level m
  uint8_t map_max = 0;
  // Free cells: a summed-area table, and their bounding box (the search's translation window).
  std::vector<uint32_t> free_sums;
  int free_x0 = 0, free_y0 = 0, free_x1 = -1, free_y1 = -1;

  MatchGrids(const GridMap& map, const GlobalLocalizerOptions& options);

  // Whether any cell of [x, x + size) x [y, y + size) is free.
  bool any_free(int x, int y, int size) const {
    const int x0 = std::max(x, 0), y0 = std::max(y, 0);
    const int x1 = std::min(x + size, width), y1 = std::min(y + size, height);
    if (x0 >= x1 || y0 >= y1) return false;
    const std::ptrdiff_t row = width + 1;
    return free_sums[y1 * row + x1] - free_sums[y0 * row + x1] - free_sums[y1 * row + x0] +
               free_sums[y0 * row + x0] >
           0;
  }

  // Bilinear interpolation of the likelihood between cell centres at a map point, and its
  // gradient (per metre); zero outside the map.
  double sample(double wx, double wy, double& gx, double& gy) const;

  LocalizationResult localize(const Scan& scan) const;
};

// A node of the search tree (see BranchAndBound).
struct Node {
  uint32_t bound;
  int32_t angle, cx, cy, level;
};

// The open nodes are kept in this many buckets of bound values.
constexpr uint32_t kBuckets = 4096;

// The scan at one node's angles: per point, the corner of the window of cells it can hit
// relative to the node's translation corner, and the level whose max-grid window covers that
// window. Shared by every node of that level and angular interval.
struct Discretization {
  bool ready = false;
  std::vector<std::ptrdiff_t> offset;  // index of the corner in its level, less the node's
  std::vector<int32_t> dx, dy;
  std::vector<uint8_t> level;
  uint32_t saturated = 0;  // the map's maximum for each point no level covers
  int32_t min_dx = 0, max_dx = 0, min_dy = 0, max_dy = 0;
};

// Best-first branch and bound over one share of the root angle intervals. A node at level L is
// 2^L angular steps [angle, angle + 2^L) times 2^L x 2^L robot cells from (cx, cy); its bound is
// the sum over points of the maximum likelihood over every cell the point can hit within it,
// which is at least the score of every lattice pose below it. Nodes are expanded highest bound
// first, so the first leaves met are the best and the tree is opened no further than its best
// score requires (a depth-first order would open much of it before finding that score). The
// search stops below ratio * max(best, min score): every lattice pose scoring at least
// ratio * best is reached, whatever the order, threads included.
class BranchAndBound {
 public:
  BranchAndBound(const MatchGrids& map, const std::vector<Point>& cells,
                 const std::vector<double>& radii, int angles, double step, double min_sum,
                 double ratio, std::atomic<uint32_t>& shared_best)
      : map_(map),
        cells_(cells),
        radii_(radii),
        angles_(angles),
        step_(step),
        min_sum_(min_sum),
        ratio_(ratio),
        shared_best_(shared_best) {
    for (int level = 0; level <= map_.options.branch_and_bound_depth; ++level)
      discretizations_[static_cast<std::size_t>(level)].resize(
          static_cast<std::size_t>(((angles - 1) >> level) + 1));
    const uint32_t full = 255u * static_cast<uint32_t>(cells.size());
    bucket_width_ = std::max<uint32_t>(1, full / kBuckets + 1);
    buckets_.resize(full / bucket_width_ + 1);
  }

  void run(int first_root_interval, int interval_stride) {
    const int depth = map_.options.branch_and_bound_depth;
    const int size = 1 << depth;
    for (int angle = first_root_interval * size; angle < angles_; angle += interval_stride * size) {
      const Discretization& d = discretization(angle, depth);
      for (int cy = map_.free_y0; cy <= map_.free_y1; cy += size)
        for (int cx = map_.free_x0; cx <= map_.free_x1; cx += size)
          if (map_.any_free(cx, cy, size)) push({bound(d, cx, cy), angle, cx, cy, depth});
    }
    for (std::size_t b = buckets_.size(); b-- > 0;) {
      std::vector<Node>& bucket = buckets_[b];
      while (!bucket.empty()) {
        const double cut = threshold();
        if ((b + 1) * bucket_width_ <= cut) return;  // all that is left is below the cut
        const Node node = bucket.back();
        bucket.pop_back();
        if (node.bound >= cut) expand(node);
      }
    }
  }

  const Leaf& best() const { return best_; }
  bool has_best() const { return has_best_; }
  const std::vector<Leaf>& near_best() const { return near_best_; }

 private:
  double threshold() const {
    return ratio_ *
           std::max(static_cast<double>(shared_best_.load(std::memory_order_relaxed)), min_sum_);
  }

  const Discretization& discretization(int angle, int level) {
    Discretization& d =
        discretizations_[static_cast<std::size_t>(level)][static_cast<std::size_t>(angle >> level)];
    if (d.ready) return d;
    d.ready = true;
    const int steps = std::min(1 << level, angles_ - angle);
    const double half_span = 0.5 * (steps - 1) * step_;
    const double theta = angle * step_ + half_span;
    const double c = std::cos(theta), s = std::sin(theta);
    const int window = 1 << level;
    d.min_dx = d.min_dy = std::numeric_limits<int32_t>::max();
    d.max_dx = d.max_dy = std::numeric_limits<int32_t>::min();
    for (std::size_t i = 0; i < cells_.size(); ++i) {
      const double qx = c * cells_[i].x - s * cells_[i].y;
      const double qy = s * cells_[i].x + c * cells_[i].y;
      // Over the interval the point stays within a chord 2 r sin(h / 2) <= r h of its
      // mid-interval position; the margin covers rounding, and a single angle needs none.
      const double reach = steps > 1 ? radii_[i] * half_span + 1e-6 : 0.0;
      const auto x0 = static_cast<int32_t>(std::floor(0.5 + qx - reach));
      const auto x1 = static_cast<int32_t>(std::floor(0.5 + qx + reach));
      const auto y0 = static_cast<int32_t>(std::floor(0.5 + qy - reach));
      const auto y1 = static_cast<int32_t>(std::floor(0.5 + qy + reach));
      const auto extent = static_cast<uint32_t>(std::max(x1 - x0, y1 - y0) + window);
      const int needed = std::bit_width(extent - 1);
      if (needed > map_.top_level) {
        d.saturated += map_.map_max;
        continue;
      }
      d.offset.push_back(map_.level_origin[static_cast<std::size_t>(needed)] + y0 * map_.stride +
                         x0);
      d.dx.push_back(x0);
      d.dy.push_back(y0);
      d.level.push_back(static_cast<uint8_t>(needed));
      d.min_dx = std::min(d.min_dx, x0);
      d.max_dx = std::max(d.max_dx, x0);
      d.min_dy = std::min(d.min_dy, y0);
      d.max_dy = std::max(d.max_dy, y0);
    }
    return d;
  }

  uint32_t bound(const Discretization& d, int cx, int cy) const {
    const uint8_t* grids = map_.max_grids.data();
    uint32_t sum = d.saturated;
    const std::size_t n = d.offset.size();
    if (cx + d.min_dx >= -1 && cx + d.max_dx <= map_.width && cy + d.min_dy >= -1 &&
        cy + d.max_dy <= map_.height) {
      // Every window corner lies in every level's extent: no clamping.
      const std::ptrdiff_t corner = cy * map_.stride + cx;
      for (std::size_t i = 0; i < n; ++i) sum += grids[d.offset[i] + corner];
    } else {
      for (std::size_t i = 0; i < n; ++i) {
        const int lowest = -(1 << d.level[i]);
        const int x = std::clamp(cx + d.dx[i], lowest, map_.width);
        const int y = std::clamp(cy + d.dy[i], lowest, map_.height);
        sum += grids[map_.level_origin[d.level[i]] + y * map_.stride + x];
      }
    }
    return sum;
  }

  // Scores the node's children: leaves are recorded, the others queued with their bound capped
  // by the node's (which bounds them too, and may be the tighter for the power-of-two windows).
  void expand(const Node& node) {
    const int level = node.level - 1;
    const int half = 1 << level;
    const int end = std::min(node.angle + (1 << node.level), angles_);
    for (int angle = node.angle; angle < end; angle += half) {
      const Discretization& d = discretization(angle, level);
      for (int b = 0; b < 2; ++b) {
        for (int a = 0; a < 2; ++a) {
          const int x = node.cx + a * half, y = node.cy + b * half;
          if (!map_.any_free(x, y, half)) continue;
          const uint32_t child = std::min(bound(d, x, y), node.bound);
          if (child < threshold()) continue;
          if (level == 0) {
            record({child, angle, x, y});
          } else {
            push({child, angle, x, y, level});
          }
        }
      }
    }
  }

  void push(const Node& node) {
    if (node.bound >= threshold()) buckets_[node.bound / bucket_width_].push_back(node);
  }

  void record(const Leaf& leaf) {
    if (!has_best_ || better(leaf, best_)) {
      best_ = leaf;
      has_best_ = true;
      uint32_t shared = shared_best_.load(std::memory_order_relaxed);
      while (leaf.score > shared &&
             !shared_best_.compare_exchange_weak(shared, leaf.score, std::memory_order_relaxed)) {
      }
    }
    near_best_.push_back(leaf);
    // Drop what the risen best has since put out of reach, so that a long search stays small.
    if (near_best_.size() >= 2 * kept_after_compaction_ + 4096) {
      const double cut = threshold();
      std::erase_if(near_best_, [cut](const Leaf& l) { return l.score < cut; });
      kept_after_compaction_ = near_best_.size();
    }
  }

  const MatchGrids& map_;
  const std::vector<Point>& cells_;
  const std::vector<double>& radii_;
  const int angles_;
  const double step_;
  const double min_sum_;
  const double ratio_;
  std::atomic<uint32_t>& shared_best_;
  // Per level, per angular interval of that level, computed when first needed.
  std::array<std::vector<Discretization>, kMaxDepth + 1> discretizations_;
  // Open nodes by bound: bucket b holds bounds in [b, b + 1) * bucket_width_.
  std::vector<std::vector<Node>> buckets_;
  uint32_t bucket_width_ = 1;
  Leaf best_{0, 0, 0, 0};
  bool has_best_ = false;
  std::vector<Leaf> near_best_;
  std::size_t kept_after_compaction_ = 0;
};

// The scan's returns within the usable range, in the robot frame (m).
std::vector<Point> scan_points(const Scan& scan, double max_range) {
  std::vector<Point> points;
  points.reserve(scan.ranges.size());
  for (std::size_t i = 0; i < scan.ranges.size(); ++i) {
    const float r = scan.ranges[i];
    if (!std::isfinite(r) || r < scan.range_min || r > scan.range_max || r > max_range) continue;
    const double a = static_cast<double>(scan.angle_min) +
                     static_cast<double>(i) * static_cast<double>(scan.angle_increment);
    points.push_back({r * std::cos(a), r * std::sin(a)});
  }
  return points;
}

// Walks the scan in beam order keeping a point once it is `spacing` from the last one kept.
std::vector<Point> thin(const std::vector<Point>& points, double spacing) {
  std::vector<Point> kept;
  for (const Point& p : points) {
    if (!kept.empty()) {
      const double dx = p.x - kept.back().x, dy = p.y - kept.back().y;
      if (dx * dx + dy * dy < spacing * spacing) continue;
    }
    kept.push_back(p);
  }
  return kept;
}

// Evenly spread points along the scan's contour, at most max_points of them: the smallest
// spacing (by bisection) that leaves no more.
std::vector<Point> thin_to(const std::vector<Point>& points, std::size_t max_points) {
  if (points.size() <= max_points) return points;
  double fits = 0.5;
  while (thin(points, fits).size() > max_points) fits *= 2.0;
  double too_close = 0.0;
  for (int i = 0; i < 20; ++i) {
    const double mid = 0.5 * (too_close + fits);
    (thin(points, mid).size() > max_points ? too_close : fits) = mid;
  }
  return thin(points, fits);
}

// Solves the symmetric 3x3 system a x = b by Cramer's rule; false when singular.
bool solve3(const double a[3][3], const double b[3], double x[3]) {
  auto det3 = [](const double m[3][3]) {
    return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
           m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  };
  const double det = det3(a);
  if (!(std::abs(det) > 1e-300)) return false;
  for (int c = 0; c < 3; ++c) {
    double m[3][3];
    for (int r = 0; r < 3; ++r)
      for (int k = 0; k < 3; ++k) m[r][k] = k == c ? b[r] : a[r][k];
    x[c] = det3(m) / det;
  }
  return true;
}

// Sum over the points of (1 - likelihood)^2 at a pose; adds the Gauss-Newton normal equations
// of that sum (J^T J and J^T r) to `hessian` and `rhs` when they are given.
double misfit(const MatchGrids& map, const std::vector<Point>& points, const Pose& pose,
              double (*hessian)[3] = nullptr, double* rhs = nullptr) {
  const double c = std::cos(pose.yaw), s = std::sin(pose.yaw);
  double sum = 0.0;
  for (const Point& p : points) {
    const double wx = pose.x + c * p.x - s * p.y;
    const double wy = pose.y + s * p.x + c * p.y;
    double gx = 0.0, gy = 0.0;
    const double residual = 1.0 - map.sample(wx, wy, gx, gy);
    sum += residual * residual;
    if (hessian == nullptr) continue;
    const double j[3] = {gx, gy, gx * (-s * p.x - c * p.y) + gy * (c * p.x - s * p.y)};
    for (int r = 0; r < 3; ++r) {
      rhs[r] += j[r] * residual;
      for (int k = 0; k < 3; ++k) hessian[r][k] += j[r] * j[k];
    }
  }
  return sum;
}

// Levenberg-Marquardt-damped Gauss-Newton on the interpolated likelihood, from the lattice pose.
// Points on unmapped clutter sit where the likelihood is flat zero and pull on nothing. The
// result is kept only when it fits better and stays within a few lattice steps of the start.
Pose refine(const MatchGrids& map, const std::vector<Point>& points, const Pose& start,
            int iterations, double step) {
  Pose pose = start;
  double damping = 1e-3;
  double cost = misfit(map, points, pose);
  for (int i = 0; i < iterations; ++i) {
    double hessian[3][3] = {};
    double rhs[3] = {};
    misfit(map, points, pose, hessian, rhs);
    for (int r = 0; r < 3; ++r) hessian[r][r] *= 1.0 + damping;
    double delta[3];
    if (!solve3(hessian, rhs, delta)) break;
    const Pose trial{pose.x + delta[0], pose.y + delta[1], pose.yaw + delta[2]};
    const double trial_cost = misfit(map, points, trial);
    if (trial_cost < cost) {
      pose = trial;
      cost = trial_cost;
      damping *= 0.1;
      if (std::abs(delta[0]) + std::abs(delta[1]) < 1e-5 && std::abs(delta[2]) < 1e-6) break;
    } else {
      damping *= 10.0;
    }
  }
  const double reach = 3.0 * map.resolution;
  if (std::abs(pose.x - start.x) > reach || std::abs(pose.y - start.y) > reach ||
      std::abs(pose.yaw - start.yaw) > 3.0 * step)
    return start;
  return pose;
}

void validate(const GridMap& map, const GlobalLocalizerOptions& o) {
  if (map.width == 0 || map.height == 0)
    throw std::invalid_argument("localization map has zero size");
  if (map.width > kMaxCellsASide || map.height > kMaxCellsASide)
    throw std::invalid_argument("localization map is over 16384 cells a side");
  if (map.cells.size() != static_cast<std::size_t>(map.width) * map.height)
    throw std::invalid_argument("localization map has " + std::to_string(map.cells.size()) +
                                " cells for " + std::to_string(map.width) + " x " +
                                std::to_string(map.height));
  if (!(map.resolution > 0.0) || !std::isfinite(map.resolution))
    throw std::invalid_argument("localization map resolution must be positive");
  if (!std::isfinite(map.origin_x) || !std::isfinite(map.origin_y))
    throw std::invalid_argument("localization map origin must be finite");
  if (!(o.max_range_m > 0.0)) throw std::invalid_argument("localizer max_range_m must be positive");
  if (!(o.min_score >= 0.0 && o.min_score <= 1.0))
    throw std::invalid_argument("localizer min_score must be in [0, 1]");
  if (o.branch_and_bound_depth < 1 || o.branch_and_bound_depth > kMaxDepth)
    throw std::invalid_argument("localizer branch_and_bound_depth must be 1 .. 10");
  if (!(o.angular_step_rad == 0.0 ||
        (o.angular_step_rad >= 2.0 * kPi / kMaxAngles && o.angular_step_rad <= kPi)))
    throw std::invalid_argument("localizer angular_step_rad must be 0 (derived) or in [2 pi / " +
                                std::to_string(kMaxAngles) + ", pi] (at most " +
                                std::to_string(kMaxAngles) + " yaw steps a turn)");
  if (o.max_points < 1 || o.max_points > kMaxPoints)
    throw std::invalid_argument("localizer max_points must be 1 .. 100000");
  if (!(o.likelihood_sigma_m > 0.0) || !std::isfinite(o.likelihood_sigma_m))
    throw std::invalid_argument("localizer likelihood_sigma_m must be positive");
  if (o.free_threshold < 0 || o.occupied_threshold <= o.free_threshold ||
      o.occupied_threshold > 100)
    throw std::invalid_argument("localizer thresholds must satisfy 0 <= free < occupied <= 100");
  if (!(o.ambiguity_ratio > 0.0 && o.ambiguity_ratio < 1.0))
    throw std::invalid_argument("localizer ambiguity_ratio must be in (0, 1)");
  if (o.refinement_iterations < 0)
    throw std::invalid_argument("localizer refinement_iterations must not be negative");
  if (o.threads < 1) throw std::invalid_argument("localizer threads must be at least 1");
}

MatchGrids::MatchGrids(const GridMap& map, const GlobalLocalizerOptions& opts)
    : options(opts),
      width(static_cast<int>(map.width)),
      height(static_cast<int>(map.height)),
      resolution(map.resolution),
      origin_x(map.origin_x),
      origin_y(map.origin_y) {
  const std::size_t cells = map.cells.size();
  std::vector<uint8_t> obstacle(cells);
  for (std::size_t i = 0; i < cells; ++i) obstacle[i] = map.cells[i] >= options.occupied_threshold;

  // Likelihood from the distance to the nearest obstacle cell, less half a cell so that a hit
  // on the obstacle's face (its cell's edge) is as likely as one on its centre.
  const std::vector<double> squared = squared_distances(obstacle, width, height);
  const double sigma_cells = options.likelihood_sigma_m / resolution;
  likelihood.resize(cells);
  std::vector<uint8_t> quantised(cells);
  for (std::size_t i = 0; i < cells; ++i) {
    const double d =
        squared[i] >= kNoObstacle ? kNoObstacle : std::max(0.0, std::sqrt(squared[i]) - 0.5);
    const double l = std::exp(-d * d / (2.0 * sigma_cells * sigma_cells));
    likelihood[i] = static_cast<float>(l);
    quantised[i] = static_cast<uint8_t>(std::lround(255.0 * l));
    map_max = std::max(map_max, quantised[i]);
  }

  // Levels up to the depth's spare ones, and no coarser than one window covering the map.
  const int cover = std::bit_width(static_cast<unsigned>(std::max(width, height) - 1)) + 1;
  top_level = std::min(options.branch_and_bound_depth + kSpareLevels, cover);
  stride = width + (std::ptrdiff_t{1} << top_level) + 1;
  std::ptrdiff_t total = 0;
  for (int m = 0; m <= top_level; ++m) {
    const std::ptrdiff_t pad = std::ptrdiff_t{1} << m;
    level_origin[static_cast<std::size_t>(m)] = total + pad * stride + pad;
    total += (height + pad + 1) * stride;
  }
  max_grids.assign(static_cast<std::size_t>(total), 0);
  auto at = [this](int m, int x, int y) -> uint8_t& {
    return max_grids[static_cast<std::size_t>(level_origin[static_cast<std::size_t>(m)] +
                                              y * stride + x)];
  };
  auto read = [&](int m, int x, int y) -> uint8_t {
    const int pad = 1 << m;
    return x < -pad || x > width || y < -pad || y > height ? 0 : at(m, x, y);
  };
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      at(0, x, y) = quantised[static_cast<std::size_t>(y) * width + x];
  for (int m = 1; m <= top_level; ++m) {
    const int half = 1 << (m - 1);
    for (int y = -(1 << m); y <= height; ++y) {
      for (int x = -(1 << m); x <= width; ++x) {
        at(m, x, y) = std::max({read(m - 1, x, y), read(m - 1, x + half, y),
                                read(m - 1, x, y + half), read(m - 1, x + half, y + half)});
      }
    }
  }

  const std::ptrdiff_t row = width + 1;
  free_sums.assign(static_cast<std::size_t>(row * (height + 1)), 0);
  free_x0 = width;
  free_y0 = height;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const int8_t v = map.cells[static_cast<std::size_t>(y) * width + x];
      const bool free = v >= 0 && v <= options.free_threshold;
      free_sums[(y + 1) * row + x + 1] = free_sums[y * row + x + 1] + free_sums[(y + 1) * row + x] -
                                         free_sums[y * row + x] + (free ? 1 : 0);
      if (free) {
        free_x0 = std::min(free_x0, x);
        free_y0 = std::min(free_y0, y);
        free_x1 = std::max(free_x1, x);
        free_y1 = std::max(free_y1, y);
      }
    }
  }
}

double MatchGrids::sample(double wx, double wy, double& gx, double& gy) const {
  gx = gy = 0.0;
  const double u = (wx - origin_x) / resolution - 0.5;
  const double v = (wy - origin_y) / resolution - 0.5;
  if (!(u > -1.0 && u < width && v > -1.0 && v < height)) return 0.0;
  const double fu = std::floor(u), fv = std::floor(v);
  const int x = static_cast<int>(fu), y = static_cast<int>(fv);
  auto cell = [this](int cx, int cy) -> double {
    if (cx < 0 || cy < 0 || cx >= width || cy >= height) return 0.0;
    return likelihood[static_cast<std::size_t>(cy) * width + cx];
  };
  const double v00 = cell(x, y), v10 = cell(x + 1, y);
  const double v01 = cell(x, y + 1), v11 = cell(x + 1, y + 1);
  const double a = u - fu, b = v - fv;
  gx = ((1.0 - b) * (v10 - v00) + b * (v11 - v01)) / resolution;
  gy = ((1.0 - a) * (v01 - v00) + a * (v11 - v10)) / resolution;
  return (1.0 - b) * ((1.0 - a) * v00 + a * v10) + b * ((1.0 - a) * v01 + a * v11);
}

LocalizationResult MatchGrids::localize(const Scan& scan) const {
  if (scan.ranges.empty()) throw std::invalid_argument("localization scan has no ranges");
  if (!(scan.angle_increment != 0.0f) || !std::isfinite(scan.angle_increment) ||
      !std::isfinite(scan.angle_min))
    throw std::invalid_argument("localization scan angle_increment must be finite and non-zero");

  LocalizationResult result;
  // Uninformative until found: uniform over the free cells' bounding box (the map when none is
  // free) and every yaw.
  const bool any_free_cell = free_x1 >= free_x0;
  const double span_x = (any_free_cell ? free_x1 - free_x0 + 1 : width) * resolution;
  const double span_y = (any_free_cell ? free_y1 - free_y0 + 1 : height) * resolution;
  result.covariance = {span_x * span_x / 12.0, 0.0, 0.0, 0.0, span_y * span_y / 12.0, 0.0, 0.0, 0.0,
                       kPi * kPi / 3.0};

  // Returns beyond the map's diagonal cannot land in it from any free cell.
  const double reach = std::min(options.max_range_m, (width + height) * resolution);
  const std::vector<Point> points = scan_points(scan, reach);
  if (points.empty() || !any_free_cell) return result;
  const std::vector<Point> used = thin_to(points, options.max_points);

  // The search works in cells.
  std::vector<Point> cells(used.size());
  std::vector<double> radii(used.size());
  double farthest = 0.0;
  for (std::size_t i = 0; i < used.size(); ++i) {
    cells[i] = {used[i].x / resolution, used[i].y / resolution};
    radii[i] = std::hypot(cells[i].x, cells[i].y);
    farthest = std::max(farthest, radii[i]);
  }
  double step = options.angular_step_rad;
  if (step == 0.0) {
    const double r = std::max(farthest, 1.0);
    step = std::acos(1.0 - 1.0 / (2.0 * r * r));
  }
  const int angles = static_cast<int>(std::ceil(2.0 * kPi / step - 1e-9));
  step = 2.0 * kPi / angles;

  const double full = 255.0 * static_cast<double>(used.size());
  const double min_sum = options.min_score * full;
  const double ratio = options.ambiguity_ratio;
  const int root_size = 1 << options.branch_and_bound_depth;
  const int root_intervals = (angles + root_size - 1) / root_size;
  const int threads = static_cast<int>(std::min<unsigned>(options.threads, root_intervals));
  std::atomic<uint32_t> shared_best{0};
  std::vector<BranchAndBound> searches;
  searches.reserve(static_cast<std::size_t>(threads));
  for (int t = 0; t < threads; ++t)
    searches.emplace_back(*this, cells, radii, angles, step, min_sum, ratio, shared_best);
  {
    std::vector<std::jthread> pool;  // joined on leaving the block, exception or not
    for (int t = 1; t < threads; ++t)
      pool.emplace_back([&searches, t, threads] { searches[t].run(t, threads); });
    searches[0].run(0, threads);
  }

  const BranchAndBound* winner = nullptr;
  for (const BranchAndBound& s : searches)
    if (s.has_best() && (winner == nullptr || better(s.best(), winner->best()))) winner = &s;
  if (winner == nullptr) return result;
  const Leaf best = winner->best();
  const Pose lattice{origin_x + (best.cx + 0.5) * resolution,
                     origin_y + (best.cy + 0.5) * resolution, wrap_angle(best.angle * step)};
  result.x = lattice.x;
  result.y = lattice.y;
  result.yaw = lattice.yaw;
  result.score = best.score / full;
  if (best.score < min_sum) return result;
  result.found = true;

  // Score-weighted spread of the near-best lattice poses about the best (see the header),
  // summed in a fixed order so that the bits do not depend on the threads.
  const double cut = ratio * best.score;
  const double top = best.score - cut;  // zero only when every score is zero
  std::vector<Leaf> near;
  for (const BranchAndBound& s : searches)
    for (const Leaf& leaf : s.near_best())
      if (leaf.score >= cut) near.push_back(leaf);
  std::sort(near.begin(), near.end(), better);
  double weights = 0.0;
  double spread[3][3] = {};
  for (const Leaf& leaf : near) {
    const double w = top > 0.0 ? (leaf.score - cut) / top : 1.0;
    const double d[3] = {(leaf.cx - best.cx) * resolution, (leaf.cy - best.cy) * resolution,
                         wrap_angle((leaf.angle - best.angle) * step)};
    weights += w;
    for (int r = 0; r < 3; ++r)
      for (int c = r; c < 3; ++c) spread[r][c] += w * d[r] * d[c];
  }
  const double quantisation[3] = {resolution * resolution / 12.0, resolution * resolution / 12.0,
                                  step * step / 12.0};
  for (int r = 0; r < 3; ++r) {
    for (int c = r; c < 3; ++c) {
      const double v = spread[r][c] / weights + (r == c ? quantisation[r] : 0.0);
      result.covariance[3 * r + c] = result.covariance[3 * c + r] = v;
    }
  }

  if (options.refinement_iterations > 0) {
    const Pose refined = refine(*this, points, lattice, options.refinement_iterations, step);
    result.x = refined.x;
    result.y = refined.y;
    result.yaw = wrap_angle(refined.yaw);
  }
  return result;
}

}  // namespace

struct GlobalLocalizer::Impl {
  MatchGrids grids;
};

GlobalLocalizer::GlobalLocalizer(const GridMap& map, GlobalLocalizerOptions options) {
  validate(map, options);
  impl_ = std::make_unique<const Impl>(Impl{MatchGrids(map, options)});
}

GlobalLocalizer::~GlobalLocalizer() = default;
GlobalLocalizer::GlobalLocalizer(GlobalLocalizer&&) noexcept = default;
GlobalLocalizer& GlobalLocalizer::operator=(GlobalLocalizer&&) noexcept = default;

LocalizationResult GlobalLocalizer::localize(const Scan& scan) const {
  return impl_->grids.localize(scan);
}

}  // namespace robotperf::localization
