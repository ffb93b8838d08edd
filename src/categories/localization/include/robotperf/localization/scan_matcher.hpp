#pragma once

// Global 2D localization of one laser scan in an occupancy grid, with no initial guess, as Isaac
// ROS's occupancy grid localizer finds a robot's first pose: a correlative search over
// (x, y, yaw) covering the whole map, made fast by the multi-resolution branch and bound of
// Cartographer's fast correlative scan matcher (Hess et al., "Real-Time Loop Closure in 2D LIDAR
// SLAM", ICRA 2016), here branching over angle as well as translation, then a sub-cell
// Gauss-Newton refinement on the bilinearly interpolated likelihood field.

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

namespace robotperf::localization {

// nav_msgs/OccupancyGrid's data: row-major, cell (0, 0) has its corner at the origin (the
// origin's yaw is 0), cell (i, j) covers x in origin_x + [i, i + 1) * resolution and likewise y.
// Values: -1 unknown, 0 free .. 100 occupied.
struct GridMap {
  uint32_t width = 0;
  uint32_t height = 0;
  double resolution = 0.05;  // m per cell
  double origin_x = 0;
  double origin_y = 0;
  std::vector<int8_t> cells;
};

// sensor_msgs/LaserScan's geometry and ranges: beam i points at angle_min + i * angle_increment
// in the robot frame (the scanner sits at the robot's origin). A range outside
// [range_min, range_max], NaN or infinite is no return (REP 117) and is ignored.
struct Scan {
  float angle_min = 0;
  float angle_increment = 0;
  float range_min = 0;
  float range_max = 0;
  std::vector<float> ranges;
};

struct GlobalLocalizerOptions {
  // Returns farther than this, or than the map's diagonal, are not used (m).
  double max_range_m = 30.0;
  // A pose is found when its score (LocalizationResult::score) reaches this.
  double min_score = 0.5;
  // Levels of the search tree below its roots: a root spans 2^depth cells a side and 2^depth
  // angular steps, and every level halves both. 1 .. 10.
  int branch_and_bound_depth = 7;
  // Angular lattice step (rad), 2 pi / 262144 .. pi (at most 262144 steps a turn). 0: derived
  // from the farthest point used, at r, as the rotation that moves it by one cell,
  // acos(1 - resolution^2 / (2 r^2)), as Cartographer does.
  double angular_step_rad = 0.0;
  // The search scores the scan thinned evenly along its contour (a point is kept once it is a
  // spacing away from the last one kept, the spacing chosen for) to at most this many points;
  // the refinement uses every return. 1 .. 100000.
  std::size_t max_points = 150;
  // The likelihood of a cell is exp(-d^2 / (2 sigma^2)), d its distance to the nearest occupied
  // cell's centre less half a cell (so that a return on an obstacle's face scores 1): the score
  // tolerates range noise and the lattice's steps.
  double likelihood_sigma_m = 0.07;
  // Cells at or above this value are obstacles (map_server's occupied_thresh 0.65).
  int occupied_threshold = 65;
  // Cells in [0, this] are free (map_server's free_thresh 0.25); the robot is searched for only
  // in free cells.
  int free_threshold = 25;
  // Every lattice pose scoring at least this fraction of the best one is enumerated (the search
  // prunes below it); their spread around the best is the covariance. In (0, 1).
  double ambiguity_ratio = 0.95;
  // Gauss-Newton iterations of the sub-cell refinement; 0 leaves the lattice pose.
  int refinement_iterations = 10;
  // Threads (std::thread) the search's root angle intervals are dealt out to, sharing the best
  // score for pruning; 1 runs on the calling thread. The answer is the same for any number.
  unsigned threads = 1;
};

struct LocalizationResult {
  // Whether the best pose's score reached min_score. When not, the pose and score are those of
  // the best lattice pose the search scored (zero when none) and the covariance is that of a
  // pose uniform over the bounding box of the map's free cells and all yaws.
  bool found = false;
  double x = 0;    // m, map frame
  double y = 0;    // m
  double yaw = 0;  // rad, in (-pi, pi]
  // Mean over the scan points used of the likelihood of the cell each hits at the best lattice
  // pose, in [0, 1].
  double score = 0;
  // Row-major 3x3 covariance of (x, y, yaw) in m^2, m rad, rad^2: the score-weighted spread of
  // the lattice poses scoring at least ambiguity_ratio * best around the best one, each weighted
  // by (score - ratio * best) / (best - ratio * best) so that it fades to zero at the cut, plus
  // the lattice's own quantisation variance (step^2 / 12 per axis), which keeps it positive
  // definite. A sharp, unique peak gives about a cell's and a step's variance; a corridor, a
  // symmetric room or a second place that fits as well widens it along the ambiguity.
  std::array<double, 9> covariance{};
};

// The likelihood field and its multi-resolution max grids are built once per map in the
// constructor; localize() is const and safe to call from several threads at once.
class GlobalLocalizer {
 public:
  // Throws std::invalid_argument for a zero-size map or one over 16384 cells a side,
  // cells.size() != width * height, a resolution that is not positive and finite, or options
  // out of range.
  explicit GlobalLocalizer(const GridMap& map, GlobalLocalizerOptions options = {});
  ~GlobalLocalizer();
  GlobalLocalizer(GlobalLocalizer&&) noexcept;
  GlobalLocalizer& operator=(GlobalLocalizer&&) noexcept;

  // Throws std::invalid_argument for an empty scan or an angle_increment that is zero or not
  // finite.
  LocalizationResult localize(const Scan& scan) const;

 private:
  struct Impl;
  std::unique_ptr<const Impl> impl_;
};

}  // namespace robotperf::localization
