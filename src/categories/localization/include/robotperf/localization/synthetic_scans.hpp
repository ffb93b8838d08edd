#pragma once

// A deterministic map-localization dataset standing in for RobotPerf's b2 input: the occupancy
// grid of an L-shaped office floor (rooms of distinct sizes off a long corridor, doorways,
// furniture and pillars, deliberately without symmetry, unknown outside the building) and 2D
// lidar scans ray-cast against the true floor from known poses, with range noise, dropouts and
// unmapped clutter (people and boxes that are in the world but not in the map).

#include <cstdint>
#include <numbers>
#include <vector>

#include "robotperf/localization/scan_matcher.hpp"

namespace robotperf::localization {

struct SyntheticScansConfig {
  uint64_t seed = 1;
  // The map is size_m x size_m at resolution_m, its origin at (-size_m / 2, -size_m / 2); the
  // floor plan, drawn for 20 m, is scaled to it.
  double size_m = 20.0;
  double resolution_m = 0.05;
  uint32_t scans = 100;
  // A 360 degree indoor lidar: 0.5 degree steps (720 beams, as RPLIDAR-class scanners give)
  // and a 20 m range (a Hokuyo UST-20LX's), which sees across the 20 m floor. Beam i is at
  // -pi + i * increment.
  double angle_increment_rad = std::numbers::pi / 360.0;
  double range_min_m = 0.1;
  double range_max_m = 20.0;
  double range_noise_sigma_m = 0.02;  // Gaussian, added to every return
  double dropout_probability = 0.02;  // a beam reads NaN (REP 117: no measurement)
  // People (discs of 0.18 .. 0.28 m radius) and boxes (0.3 .. 0.6 m a side, any yaw) placed
  // afresh for each scan in free space, at least 1 m from the scanner; not in the map.
  uint32_t clutter_objects = 6;
  // A pose is at least this far from every mapped obstacle.
  double clearance_m = 0.3;
};

// One scan and the pose it was taken from (map frame). Beams that hit nothing within
// range_max read +inf (REP 117).
struct SyntheticScan {
  Scan scan;
  double x = 0;
  double y = 0;
  double yaw = 0;  // rad, in [-pi, pi)
};

struct SyntheticScanDataset {
  GridMap map;  // cells whose centre lies in an obstacle are 100, other cells in the building 0
  std::vector<SyntheticScan> scans;
};

// Poses uniform over the building's free space (with clearance), yaws uniform. The same bytes
// on every machine: its own random generator (xoshiro256**), its own sin, cos and log from + - *
// / only, built without fused multiply-add contraction (-ffp-contract=off). Throws
// std::invalid_argument for a size outside [5, 200] m, a resolution outside (0, 1] m or one that
// gives more than 8192 cells a side, a bad range, increment or probability, or a clearance no
// pose can have.
SyntheticScanDataset generate_scan_dataset(const SyntheticScansConfig& config = {});

}  // namespace robotperf::localization
