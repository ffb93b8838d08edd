// b2 map localization without the graph: the global scan matcher on hand-built maps and on the
// synthetic dataset, and the dataset's determinism.
#include "robotperf/localization/scan_matcher.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

#include "robotperf/localization/synthetic_scans.hpp"

namespace robotperf::localization {
namespace {

constexpr double kPi = std::numbers::pi;

struct Rect {
  double x0, y0, x1, y1;
};

// A map of axis-aligned obstacles: cells whose centre is in one are 100, the rest free.
GridMap map_of(const std::vector<Rect>& obstacles, uint32_t width, uint32_t height, double origin_x,
               double origin_y) {
  GridMap map;
  map.width = width;
  map.height = height;
  map.resolution = 0.05;
  map.origin_x = origin_x;
  map.origin_y = origin_y;
  map.cells.assign(std::size_t{width} * height, 0);
  for (uint32_t j = 0; j < height; ++j) {
    for (uint32_t i = 0; i < width; ++i) {
      const double x = origin_x + (i + 0.5) * map.resolution;
      const double y = origin_y + (j + 0.5) * map.resolution;
      for (const Rect& r : obstacles)
        if (x > r.x0 && x < r.x1 && y > r.y0 && y < r.y1) map.cells[j * width + i] = 100;
    }
  }
  return map;
}

// An exact, noise-free scan of the obstacles from (x, y, yaw): 720 beams over 360 degrees.
Scan scan_of(const std::vector<Rect>& obstacles, double x, double y, double yaw, double range_max) {
  Scan scan;
  scan.angle_min = static_cast<float>(-kPi);
  scan.angle_increment = static_cast<float>(2.0 * kPi / 720.0);
  scan.range_min = 0.1f;
  scan.range_max = static_cast<float>(range_max);
  for (int i = 0; i < 720; ++i) {
    const double a = yaw + scan.angle_min + i * static_cast<double>(scan.angle_increment);
    const double dx = std::cos(a), dy = std::sin(a);
    double nearest = std::numeric_limits<double>::infinity();
    for (const Rect& r : obstacles) {
      // Slab test.
      double enter = 0.0, leave = nearest;
      const double o[2] = {x, y}, d[2] = {dx, dy}, lo[2] = {r.x0, r.y0}, hi[2] = {r.x1, r.y1};
      bool missed = false;
      for (int k = 0; k < 2 && !missed; ++k) {
        if (std::abs(d[k]) < 1e-12) {
          missed = o[k] < lo[k] || o[k] > hi[k];
          continue;
        }
        const double t0 = (lo[k] - o[k]) / d[k], t1 = (hi[k] - o[k]) / d[k];
        enter = std::max(enter, std::min(t0, t1));
        leave = std::min(leave, std::max(t0, t1));
        missed = enter > leave;
      }
      if (!missed && enter > 0.0) nearest = enter;
    }
    scan.ranges.push_back(nearest <= range_max ? static_cast<float>(nearest)
                                               : std::numeric_limits<float>::infinity());
  }
  return scan;
}

// A 6 m x 5 m room (origin (-1, 2)) with an inner wall, a cabinet and a pillar placed
// without symmetry.
std::vector<Rect> room() {
  return {{-1.0, 2.0, 5.0, 2.1}, {-1.0, 6.9, 5.0, 7.0}, {-1.0, 2.0, -0.9, 7.0},
          {4.9, 2.0, 5.0, 7.0},  {1.5, 5.2, 1.62, 6.9}, {1.62, 5.2, 2.6, 5.32},
          {3.7, 2.1, 4.9, 2.55}, {0.2, 3.0, 0.45, 3.25}};
}

double yaw_error(double a, double b) {
  return std::abs(std::remainder(a - b, 2.0 * kPi));
}

bool positive_definite(const std::array<double, 9>& c) {
  const double m1 = c[0];
  const double m2 = c[0] * c[4] - c[1] * c[3];
  const double m3 = c[0] * (c[4] * c[8] - c[5] * c[7]) - c[1] * (c[3] * c[8] - c[5] * c[6]) +
                    c[2] * (c[3] * c[7] - c[4] * c[6]);
  const bool symmetric = c[1] == c[3] && c[2] == c[6] && c[5] == c[7];
  return symmetric && m1 > 0.0 && m2 > 0.0 && m3 > 0.0;
}

TEST(GlobalLocalizer, FindsAKnownPoseInAHandBuiltRoom) {
  const GlobalLocalizer localizer(map_of(room(), 120, 100, -1.0, 2.0));
  struct Truth {
    double x, y, yaw;
  };
  for (const Truth& t : {Truth{0.9, 3.7, 0.6}, Truth{3.3, 4.4, -2.4}, Truth{0.4, 6.1, 3.0}}) {
    const LocalizationResult r = localizer.localize(scan_of(room(), t.x, t.y, t.yaw, 20.0));
    ASSERT_TRUE(r.found) << "score " << r.score;
    EXPECT_LT(std::hypot(r.x - t.x, r.y - t.y), 0.05) << r.x << ", " << r.y;
    EXPECT_LT(yaw_error(r.yaw, t.yaw), kPi / 180.0) << r.yaw;
    EXPECT_GT(r.score, 0.9);
    EXPECT_TRUE(positive_definite(r.covariance));
  }
}

TEST(GlobalLocalizer, LocalizesTheSyntheticDataset) {
  const SyntheticScanDataset data = generate_scan_dataset();
  ASSERT_EQ(data.scans.size(), 100u);
  const GlobalLocalizer localizer(data.map);
  int within = 0;
  for (const SyntheticScan& s : data.scans) {
    const LocalizationResult r = localizer.localize(s.scan);
    EXPECT_TRUE(positive_definite(r.covariance));
    within += r.found && std::hypot(r.x - s.x, r.y - s.y) <= 0.1 &&
              yaw_error(r.yaw, s.yaw) <= 2.0 * kPi / 180.0;
  }
  EXPECT_GE(within, 98);
}

TEST(GlobalLocalizer, ThreadsGiveTheSameAnswer) {
  const SyntheticScanDataset data = generate_scan_dataset({.seed = 7, .scans = 5});
  const GlobalLocalizer one(data.map);
  const GlobalLocalizer three(data.map, {.threads = 3});
  for (const SyntheticScan& s : data.scans) {
    const LocalizationResult a = one.localize(s.scan);
    const LocalizationResult b = three.localize(s.scan);
    EXPECT_EQ(a.found, b.found);
    EXPECT_EQ(a.x, b.x);
    EXPECT_EQ(a.y, b.y);
    EXPECT_EQ(a.yaw, b.yaw);
    EXPECT_EQ(a.score, b.score);
    EXPECT_EQ(a.covariance, b.covariance);
  }
}

TEST(GlobalLocalizer, CovarianceGrowsAlongAFeaturelessCorridor) {
  // 30 m of straight corridor, 2 m wide, seen by a 6 m scanner: every position along it away
  // from the ends, and both headings, fit equally.
  const std::vector<Rect> corridor = {
      {0.0, 0.0, 30.0, 0.1}, {0.0, 2.1, 30.0, 2.2}, {0.0, 0.0, 0.1, 2.2}, {29.9, 0.0, 30.0, 2.2}};
  const GlobalLocalizer in_corridor(map_of(corridor, 600, 44, 0.0, 0.0));
  const LocalizationResult ambiguous = in_corridor.localize(scan_of(corridor, 14.0, 1.1, 0.3, 6.0));
  const GlobalLocalizer in_room(map_of(room(), 120, 100, -1.0, 2.0));
  const LocalizationResult distinct = in_room.localize(scan_of(room(), 0.9, 3.7, 0.6, 6.0));
  ASSERT_TRUE(ambiguous.found);
  ASSERT_TRUE(distinct.found);
  EXPECT_TRUE(positive_definite(ambiguous.covariance));
  EXPECT_TRUE(positive_definite(distinct.covariance));
  // Along the corridor (x) and in yaw (it fits turned round too), not across it.
  EXPECT_GT(ambiguous.covariance[0], 1.0);
  EXPECT_GT(ambiguous.covariance[8], 1.0);
  EXPECT_LT(ambiguous.covariance[4], 0.01);
  EXPECT_LT(distinct.covariance[0], 0.01);
  EXPECT_LT(distinct.covariance[4], 0.01);
  EXPECT_LT(distinct.covariance[8], 0.01);
  EXPECT_GT(ambiguous.covariance[0], 100.0 * distinct.covariance[0]);
}

TEST(GlobalLocalizer, AMiscalibratedScannerScoresWorse) {
  // Ranges 20 % long, as from a scanner with a wrong time-of-flight scale: no pose fits them
  // as well as the true scans fit.
  const SyntheticScanDataset data = generate_scan_dataset({.scans = 10});
  const GlobalLocalizer localizer(data.map);
  int misplaced = 0;
  for (const SyntheticScan& s : data.scans) {
    Scan stretched = s.scan;
    for (float& r : stretched.ranges) r *= 1.2f;
    stretched.range_max *= 1.2f;
    const LocalizationResult good = localizer.localize(s.scan);
    const LocalizationResult bad = localizer.localize(stretched);
    ASSERT_TRUE(good.found);
    EXPECT_LT(bad.score, good.score - 0.1) << "true scan " << good.score;
    misplaced += std::hypot(bad.x - s.x, bad.y - s.y) > 0.5 || yaw_error(bad.yaw, s.yaw) > 0.1;
  }
  EXPECT_GE(misplaced, 5);
}

TEST(GlobalLocalizer, NoReturnsIsNotFound) {
  const GlobalLocalizer localizer(map_of(room(), 120, 100, -1.0, 2.0));
  Scan empty = scan_of(room(), 0.9, 3.7, 0.6, 20.0);
  std::fill(empty.ranges.begin(), empty.ranges.end(), std::numeric_limits<float>::infinity());
  const LocalizationResult r = localizer.localize(empty);
  EXPECT_FALSE(r.found);
  EXPECT_EQ(r.score, 0.0);
  EXPECT_TRUE(positive_definite(r.covariance));
  EXPECT_GT(r.covariance[8], 3.0);  // every yaw: pi^2 / 3
}

void expect_invalid(const auto& call, const std::string& message) {
  try {
    call();
    ADD_FAILURE() << "no exception; expected: " << message;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
  }
}

TEST(GlobalLocalizer, BadInputIsOneClearError) {
  const GridMap good = map_of(room(), 120, 100, -1.0, 2.0);
  GridMap empty = good;
  empty.width = 0;
  empty.cells.clear();
  expect_invalid([&] { GlobalLocalizer{empty}; }, "zero size");
  GridMap short_cells = good;
  short_cells.cells.pop_back();
  expect_invalid([&] { GlobalLocalizer{short_cells}; }, "11999 cells for 120 x 100");
  GridMap flat = good;
  flat.resolution = 0.0;
  expect_invalid([&] { GlobalLocalizer{flat}; }, "resolution must be positive");
  expect_invalid([&] { GlobalLocalizer(good, {.ambiguity_ratio = 1.0}); }, "ambiguity_ratio");

  const GlobalLocalizer localizer(good);
  Scan scan = scan_of(room(), 0.9, 3.7, 0.6, 20.0);
  Scan no_ranges = scan;
  no_ranges.ranges.clear();
  expect_invalid([&] { localizer.localize(no_ranges); }, "no ranges");
  Scan no_increment = scan;
  no_increment.angle_increment = 0.0f;
  expect_invalid([&] { localizer.localize(no_increment); }, "angle_increment");
}

// The search's tables grow with the yaw steps of a turn: a step so fine that they could not be
// held (or their count would overflow an int) is refused when the localizer is built, while the
// finest allowed one builds.
TEST(GlobalLocalizer, AnAngularStepTooFineIsOneClearError) {
  const GridMap good = map_of(room(), 120, 100, -1.0, 2.0);
  for (const double step : {1e-9, 1e-12, 2.0 * kPi / 300000.0}) {
    expect_invalid([&] { GlobalLocalizer(good, {.angular_step_rad = step}); },
                   "angular_step_rad must be 0 (derived) or in [2 pi / 262144, pi]");
  }
  EXPECT_NO_THROW(GlobalLocalizer(good, {.angular_step_rad = 2.0 * kPi / 262144.0}));
  EXPECT_NO_THROW(GlobalLocalizer(good, {.angular_step_rad = kPi}));
}

TEST(SyntheticScans, SameConfigSameBytes) {
  const SyntheticScanDataset a = generate_scan_dataset({.scans = 20});
  const SyntheticScanDataset b = generate_scan_dataset({.scans = 20});
  const SyntheticScanDataset other = generate_scan_dataset({.seed = 2, .scans = 20});
  EXPECT_EQ(a.map.cells, b.map.cells);
  ASSERT_EQ(a.scans.size(), b.scans.size());
  bool differs_from_other_seed = false;
  for (std::size_t i = 0; i < a.scans.size(); ++i) {
    const std::vector<float>& ra = a.scans[i].scan.ranges;
    const std::vector<float>& rb = b.scans[i].scan.ranges;
    ASSERT_EQ(ra.size(), rb.size());
    EXPECT_EQ(std::memcmp(ra.data(), rb.data(), ra.size() * sizeof(float)), 0);  // NaN too
    EXPECT_EQ(a.scans[i].x, b.scans[i].x);
    EXPECT_EQ(a.scans[i].y, b.scans[i].y);
    EXPECT_EQ(a.scans[i].yaw, b.scans[i].yaw);
    differs_from_other_seed |= a.scans[i].x != other.scans[i].x;
  }
  EXPECT_TRUE(differs_from_other_seed);
}

// FNV-1a over the map and the scans: the same on every machine (the generator uses only
// IEEE-754 basic operations and its own random numbers).
TEST(SyntheticScans, KnownDigest) {
  const SyntheticScanDataset data = generate_scan_dataset({.scans = 10});
  uint64_t hash = 0xcbf29ce484222325ULL;
  auto mix = [&hash](const void* bytes, std::size_t size) {
    for (std::size_t i = 0; i < size; ++i) {
      hash ^= static_cast<const unsigned char*>(bytes)[i];
      hash *= 0x100000001b3ULL;
    }
  };
  mix(data.map.cells.data(), data.map.cells.size());
  for (const SyntheticScan& s : data.scans) {
    mix(s.scan.ranges.data(), s.scan.ranges.size() * sizeof(float));
    const double pose[3] = {s.x, s.y, s.yaw};
    mix(pose, sizeof pose);
  }
  EXPECT_EQ(hash, 0xd4f6859917027a7fULL);
}

TEST(SyntheticScans, MatchesItsDescription) {
  const SyntheticScansConfig config;
  const SyntheticScanDataset data = generate_scan_dataset(config);
  const GridMap& map = data.map;
  EXPECT_EQ(map.width, 400u);
  EXPECT_EQ(map.height, 400u);
  EXPECT_DOUBLE_EQ(map.origin_x, -10.0);
  const auto count = [&map](int8_t value) {
    return std::count(map.cells.begin(), map.cells.end(), value);
  };
  EXPECT_GT(count(-1), 20000);   // outside the L-shaped building
  EXPECT_GT(count(100), 10000);  // walls and furniture
  EXPECT_GT(count(0), 100000);
  EXPECT_EQ(count(-1) + count(0) + count(100), 160000);

  std::size_t beams = 0, dropped = 0;
  for (const SyntheticScan& s : data.scans) {
    ASSERT_EQ(s.scan.ranges.size(), 720u);
    EXPECT_FLOAT_EQ(s.scan.range_max, 20.0f);
    // The pose is in a free cell with clearance: no occupied cell within 0.25 m.
    const int ci = static_cast<int>(std::floor((s.x - map.origin_x) / map.resolution));
    const int cj = static_cast<int>(std::floor((s.y - map.origin_y) / map.resolution));
    for (int dj = -5; dj <= 5; ++dj)
      for (int di = -5; di <= 5; ++di)
        if (di * di + dj * dj <= 25) {
          EXPECT_EQ(map.cells[(cj + dj) * 400 + ci + di], 0);
        }
    EXPECT_GE(s.yaw, -kPi);
    EXPECT_LT(s.yaw, kPi);
    for (const float r : s.scan.ranges) {
      ++beams;
      dropped += std::isnan(r);
      // No measurement, nothing within range, or a return from the closed floor.
      EXPECT_TRUE(std::isnan(r) || r == std::numeric_limits<float>::infinity() ||
                  (r > 0.0f && r < 20.5f))
          << r;
    }
  }
  EXPECT_NEAR(static_cast<double>(dropped) / beams, config.dropout_probability, 0.005);
}

TEST(SyntheticScans, BadConfigIsOneClearError) {
  expect_invalid([] { generate_scan_dataset({.size_m = 1.0}); }, "size_m");
  expect_invalid([] { generate_scan_dataset({.resolution_m = 0.0}); }, "resolution_m");
  expect_invalid([] { generate_scan_dataset({.range_min_m = 5.0, .range_max_m = 1.0}); }, "range");
  expect_invalid([] { generate_scan_dataset({.clearance_m = 50.0}); }, "clearance_m");
}

}  // namespace
}  // namespace robotperf::localization
