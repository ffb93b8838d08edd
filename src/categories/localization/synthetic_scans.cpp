#include "robotperf/localization/synthetic_scans.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <limits>
#include <stdexcept>
#include <utility>

#include "robotperf/perception/camera_model.hpp"

namespace robotperf::localization {
namespace {

constexpr double kPi = 3.14159265358979323846;

// xoshiro256** (Blackman and Vigna, "Scrambled Linear Pseudorandom Number Generators", 2021),
// its state filled by splitmix64 from the seed.
class Random {
 public:
  explicit Random(uint64_t seed) {
    for (uint64_t& word : state_) {
      seed += 0x9e3779b97f4a7c15ULL;
      uint64_t z = seed;
      z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
      z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
      word = z ^ (z >> 31);
    }
  }

  uint64_t next() {
    const uint64_t result = rotl(state_[1] * 5, 7) * 9;
    const uint64_t t = state_[1] << 17;
    state_[2] ^= state_[0];
    state_[3] ^= state_[1];
    state_[1] ^= state_[2];
    state_[0] ^= state_[3];
    state_[2] ^= t;
    state_[3] = rotl(state_[3], 45);
    return result;
  }

  // In [0, 1), 53 random bits.
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }

 private:
  static uint64_t rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  uint64_t state_[4];
};

// Natural log of a positive finite x from 2 atanh((m - 1) / (m + 1)), m the mantissa in
// [sqrt(1/2), sqrt(2)), with + - * / only.
double log_of(double x) {
  int exponent = 0;
  double m = std::frexp(x, &exponent);
  if (m < 0.70710678118654752440) {
    m *= 2.0;
    --exponent;
  }
  const double s = (m - 1.0) / (m + 1.0);
  const double s2 = s * s;
  double series = 0.0;
  for (int k = 27; k >= 1; k -= 2) series = series * s2 + 1.0 / k;
  return exponent * 0.69314718055994530942 + 2.0 * s * series;
}

// Box-Muller: one standard normal from two uniforms.
double gaussian(Random& random) {
  const double u = 1.0 - random.uniform();  // (0, 1]: the log is finite
  const double cosine = perception::portable_sin_cos(2.0 * kPi * random.uniform()).cos;
  return std::sqrt(-2.0 * log_of(u)) * cosine;
}

// A rectangle, centre (x, y), half sizes (hx, hy), its x axis at (c, s).
struct Box {
  double x, y, hx, hy, c = 1.0, s = 0.0;
};
struct Disc {
  double x, y, r;
};
struct Bounds {
  double x0, y0, x1, y1;
};

Box aligned(const Bounds& b) {
  return {0.5 * (b.x0 + b.x1), 0.5 * (b.y0 + b.y1), 0.5 * (b.x1 - b.x0), 0.5 * (b.y1 - b.y0)};
}

// The distance along the unit direction (dx, dy) from (ox, oy) to the shape, infinite if it
// is missed; the origin is always outside.
double hit(const Box& b, double ox, double oy, double dx, double dy) {
  const double rx = ox - b.x, ry = oy - b.y;
  const double origin[2] = {b.c * rx + b.s * ry, -b.s * rx + b.c * ry};
  const double direction[2] = {b.c * dx + b.s * dy, -b.s * dx + b.c * dy};
  const double half[2] = {b.hx, b.hy};
  double enter = 0.0, leave = std::numeric_limits<double>::infinity();
  for (int axis = 0; axis < 2; ++axis) {
    if (direction[axis] == 0.0) {
      if (std::abs(origin[axis]) > half[axis]) return std::numeric_limits<double>::infinity();
      continue;
    }
    double near = (-half[axis] - origin[axis]) / direction[axis];
    double far = (half[axis] - origin[axis]) / direction[axis];
    if (near > far) std::swap(near, far);
    enter = std::max(enter, near);
    leave = std::min(leave, far);
  }
  return enter > 0.0 && enter <= leave ? enter : std::numeric_limits<double>::infinity();
}

double hit(const Disc& d, double ox, double oy, double dx, double dy) {
  const double rx = ox - d.x, ry = oy - d.y;
  const double b = rx * dx + ry * dy;
  const double discriminant = b * b - (rx * rx + ry * ry - d.r * d.r);
  if (discriminant < 0.0) return std::numeric_limits<double>::infinity();
  const double t = -b - std::sqrt(discriminant);
  return t > 0.0 ? t : std::numeric_limits<double>::infinity();
}

// Distance from a point to the shape, zero inside.
double distance(const Box& b, double px, double py) {
  const double rx = px - b.x, ry = py - b.y;
  const double u = std::max(std::abs(b.c * rx + b.s * ry) - b.hx, 0.0);
  const double v = std::max(std::abs(-b.s * rx + b.c * ry) - b.hy, 0.0);
  return std::sqrt(u * u + v * v);
}

double distance(const Disc& d, double px, double py) {
  const double rx = px - d.x, ry = py - d.y;
  return std::max(std::sqrt(rx * rx + ry * ry) - d.r, 0.0);
}

struct World {
  std::vector<Bounds> footprint;  // the building's outline, a union of rectangles
  std::vector<Box> boxes;
  std::vector<Disc> discs;

  bool inside(double x, double y) const {
    return std::any_of(footprint.begin(), footprint.end(), [x, y](const Bounds& b) {
      return x > b.x0 && x < b.x1 && y > b.y0 && y < b.y1;
    });
  }

  double clearance(double x, double y) const {
    double d = std::numeric_limits<double>::infinity();
    for (const Box& b : boxes) d = std::min(d, distance(b, x, y));
    for (const Disc& c : discs) d = std::min(d, distance(c, x, y));
    return d;
  }

  double cast(double ox, double oy, double dx, double dy) const {
    double t = std::numeric_limits<double>::infinity();
    for (const Box& b : boxes) t = std::min(t, hit(b, ox, oy, dx, dy));
    for (const Disc& c : discs) t = std::min(t, hit(c, ox, oy, dx, dy));
    return t;
  }
};

// Horizontal wall over x in [x0, x1], y in [y0, y1], open where `doors` (x intervals) are.
void wall_along_x(World& w, Bounds b, std::vector<std::pair<double, double>> doors) {
  double start = b.x0;
  for (const auto& [from, to] : doors) {
    w.boxes.push_back(aligned({start, b.y0, from, b.y1}));
    start = to;
  }
  w.boxes.push_back(aligned({start, b.y0, b.x1, b.y1}));
}

// Vertical wall, open where `doors` (y intervals) are.
void wall_along_y(World& w, Bounds b, std::vector<std::pair<double, double>> doors) {
  double start = b.y0;
  for (const auto& [from, to] : doors) {
    w.boxes.push_back(aligned({b.x0, start, b.x1, from}));
    start = to;
  }
  w.boxes.push_back(aligned({b.x0, start, b.x1, b.y1}));
}

// The floor plan, drawn in metres on a 20 m square: a main block [0.6, 19.4] x [0.6, 12.6]
// with an east-west corridor (y 6 .. 8) between rooms A (4.25 m wide), B (6.45 m), C (7.5 m)
// to the south and D (6.05 m), E (2.95 m), F (9.2 m, a hall with pillars) to the north, and a
// wing [0.6, 11.4] x [12.6, 19.4] of rooms G and H and a store; walls 0.15 m thick. Rotated
// furniture uses Pythagorean angles (cos, sin rational) to stay exact.
World floor_plan() {
  World w;
  w.footprint = {{0.6, 0.6, 19.4, 12.6}, {0.6, 12.6, 11.4, 19.4}};
  wall_along_x(w, {0.6, 0.6, 19.4, 0.75}, {});
  wall_along_x(w, {0.75, 5.85, 19.25, 6.0}, {{2.2, 3.1}, {9.6, 10.5}, {13.0, 14.0}, {17.4, 18.3}});
  wall_along_x(w, {0.75, 8.0, 19.25, 8.15}, {{4.6, 5.5}, {7.6, 8.5}, {11.0, 12.2}, {16.0, 17.0}});
  wall_along_x(w, {0.6, 12.45, 19.4, 12.6}, {{2.0, 2.9}});
  wall_along_x(w, {0.6, 19.25, 11.4, 19.4}, {});
  wall_along_x(w, {6.35, 16.4, 11.25, 16.55}, {{9.8, 10.6}});
  wall_along_y(w, {0.6, 0.75, 0.75, 19.25}, {});
  wall_along_y(w, {19.25, 0.75, 19.4, 12.45}, {});
  wall_along_y(w, {11.25, 12.6, 11.4, 19.25}, {});
  wall_along_y(w, {5.0, 0.75, 5.15, 5.85}, {{1.2, 2.1}});
  wall_along_y(w, {11.6, 0.75, 11.75, 5.85}, {});
  wall_along_y(w, {6.8, 8.15, 6.95, 12.45}, {});
  wall_along_y(w, {9.9, 8.15, 10.05, 12.45}, {{10.8, 11.6}});
  wall_along_y(w, {6.2, 12.6, 6.35, 19.25}, {{14.0, 14.9}});
  for (const Bounds& b :
       std::initializer_list<Bounds>{{0.75, 3.0, 1.15, 5.0},     // A: shelf
                                     {3.2, 1.5, 4.4, 2.3},       // A: table
                                     {10.6, 0.75, 11.6, 1.3},    // B: cabinet
                                     {13.0, 3.8, 13.4, 4.2},     // C: square pillar
                                     {18.7, 0.75, 19.25, 2.8},   // C: shelf
                                     {3.6, 11.75, 5.6, 12.45},   // D: sofa
                                     {6.95, 11.65, 8.2, 12.45},  // E: desk
                                     {18.0, 9.5, 18.4, 9.9},     // F: square pillar
                                     {15.0, 6.0, 16.5, 6.35},    // corridor: bench
                                     {3.8, 7.45, 4.5, 8.0},      // corridor: vending machine
                                     {0.75, 13.0, 1.2, 15.5},    // G: shelf
                                     {8.0, 13.5, 9.0, 14.3},     // H: boxes
                                     {6.35, 18.7, 10.0, 19.25},  // store: shelves
                                     {6.35, 16.55, 6.9, 18.0}})  // store: shelf
    w.boxes.push_back(aligned(b));
  w.boxes.push_back({15.5, 2.5, 0.8, 0.4, 0.8, 0.6});              // C: desk, 36.9 deg
  w.boxes.push_back({14.5, 11.6, 1.2, 0.35, 0.96, -0.28});         // F: table, -16.3 deg
  w.boxes.push_back({10.2, 15.3, 0.3, 0.3, 12.0 / 13, 5.0 / 13});  // H: crate, 22.6 deg
  w.discs = {
      {7.2, 3.0, 0.6}, {5.5, 10.0, 0.2}, {12.8, 10.1, 0.25}, {15.9, 10.4, 0.25}, {3.0, 16.0, 0.7}};
  return w;
}

// The plan scaled by `scale` about the design's origin and moved so that it starts at `origin`.
World placed(const World& design, double scale, double origin) {
  World w;
  for (const Bounds& b : design.footprint)
    w.footprint.push_back({origin + scale * b.x0, origin + scale * b.y0, origin + scale * b.x1,
                           origin + scale * b.y1});
  for (const Box& b : design.boxes)
    w.boxes.push_back(
        {origin + scale * b.x, origin + scale * b.y, scale * b.hx, scale * b.hy, b.c, b.s});
  for (const Disc& d : design.discs)
    w.discs.push_back({origin + scale * d.x, origin + scale * d.y, scale * d.r});
  return w;
}

GridMap rasterise(const World& world, uint32_t cells_a_side, double resolution, double origin) {
  GridMap map;
  map.width = map.height = cells_a_side;
  map.resolution = resolution;
  map.origin_x = map.origin_y = origin;
  const int n = static_cast<int>(cells_a_side);
  map.cells.assign(static_cast<std::size_t>(n) * n, -1);
  auto centre = [&](int i) { return origin + (i + 0.5) * resolution; };
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x)
      if (world.inside(centre(x), centre(y))) map.cells[static_cast<std::size_t>(y) * n + x] = 0;
  // Each shape marks the cells of its bounding box whose centre it covers.
  auto mark = [&](double x0, double y0, double x1, double y1, auto covers) {
    const int i0 = std::max(0, static_cast<int>(std::floor((x0 - origin) / resolution)));
    const int j0 = std::max(0, static_cast<int>(std::floor((y0 - origin) / resolution)));
    const int i1 = std::min(n - 1, static_cast<int>(std::floor((x1 - origin) / resolution)));
    const int j1 = std::min(n - 1, static_cast<int>(std::floor((y1 - origin) / resolution)));
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i)
        if (covers(centre(i), centre(j))) map.cells[static_cast<std::size_t>(j) * n + i] = 100;
  };
  for (const Box& b : world.boxes) {
    const double ex = std::abs(b.c) * b.hx + std::abs(b.s) * b.hy;
    const double ey = std::abs(b.s) * b.hx + std::abs(b.c) * b.hy;
    mark(b.x - ex, b.y - ey, b.x + ex, b.y + ey,
         [&b](double px, double py) { return distance(b, px, py) == 0.0; });
  }
  for (const Disc& d : world.discs) {
    mark(d.x - d.r, d.y - d.r, d.x + d.r, d.y + d.r,
         [&d](double px, double py) { return distance(d, px, py) == 0.0; });
  }
  return map;
}

void validate(const SyntheticScansConfig& c) {
  if (!(c.size_m >= 5.0 && c.size_m <= 200.0))
    throw std::invalid_argument("synthetic scans size_m must be in [5, 200]");
  if (!(c.resolution_m > 0.0 && c.resolution_m <= 1.0) || c.size_m / c.resolution_m > 8192.0)
    throw std::invalid_argument(
        "synthetic scans resolution_m must be in (0, 1] and give at most 8192 cells a side");
  if (!(c.angle_increment_rad > 0.0 && c.angle_increment_rad <= 2.0 * kPi))
    throw std::invalid_argument("synthetic scans angle_increment_rad must be in (0, 2 pi]");
  if (!(c.range_min_m >= 0.0 && c.range_max_m > c.range_min_m && std::isfinite(c.range_max_m)))
    throw std::invalid_argument("synthetic scans range must satisfy 0 <= min < max < inf");
  if (!(c.range_noise_sigma_m >= 0.0 && std::isfinite(c.range_noise_sigma_m)))
    throw std::invalid_argument("synthetic scans range_noise_sigma_m must be finite, >= 0");
  if (!(c.dropout_probability >= 0.0 && c.dropout_probability <= 1.0))
    throw std::invalid_argument("synthetic scans dropout_probability must be in [0, 1]");
  if (!(c.clearance_m >= 0.0 && std::isfinite(c.clearance_m)))
    throw std::invalid_argument("synthetic scans clearance_m must be finite, >= 0");
}

constexpr int kMaxAttempts = 100000;

}  // namespace

SyntheticScanDataset generate_scan_dataset(const SyntheticScansConfig& config) {
  validate(config);
  const double origin = -0.5 * config.size_m;
  const World world = placed(floor_plan(), config.size_m / 20.0, origin);
  SyntheticScanDataset dataset;
  const auto cells = static_cast<uint32_t>(std::floor(config.size_m / config.resolution_m + 0.5));
  dataset.map = rasterise(world, cells, config.resolution_m, origin);

  const Bounds extent{origin, origin, origin + config.size_m, origin + config.size_m};
  const auto beams =
      static_cast<std::size_t>(std::floor(2.0 * kPi / config.angle_increment_rad + 1e-9));
  Random random(config.seed);
  dataset.scans.resize(config.scans);
  for (SyntheticScan& sample : dataset.scans) {
    int attempts = 0;
    do {
      if (++attempts > kMaxAttempts)
        throw std::invalid_argument("synthetic scans found no pose with clearance_m");
      sample.x = random.uniform(extent.x0, extent.x1);
      sample.y = random.uniform(extent.y0, extent.y1);
    } while (!world.inside(sample.x, sample.y) ||
             world.clearance(sample.x, sample.y) < config.clearance_m);
    sample.yaw = random.uniform(-kPi, kPi);

    World scene = world;  // the mapped floor plus this scan's clutter
    for (uint32_t k = 0; k < config.clutter_objects; ++k) {
      const bool person = k % 2 == 0;
      const double size = person ? random.uniform(0.18, 0.28) : random.uniform(0.15, 0.3);
      double x = 0.0, y = 0.0;
      for (attempts = 0;; ++attempts) {
        if (attempts > kMaxAttempts)
          throw std::invalid_argument("synthetic scans found no place for clutter");
        x = random.uniform(extent.x0, extent.x1);
        y = random.uniform(extent.y0, extent.y1);
        const double to_scanner = std::hypot(x - sample.x, y - sample.y);
        if (world.inside(x, y) && world.clearance(x, y) > 1.5 * size &&
            to_scanner > 1.0 + 1.5 * size)
          break;
      }
      if (person) {
        scene.discs.push_back({x, y, size});
      } else {
        const auto [s, c] = perception::portable_sin_cos(random.uniform(0.0, kPi));
        scene.boxes.push_back({x, y, size, size, c, s});
      }
    }

    Scan& scan = sample.scan;
    scan.angle_min = static_cast<float>(-kPi);
    scan.angle_increment = static_cast<float>(config.angle_increment_rad);
    scan.range_min = static_cast<float>(config.range_min_m);
    scan.range_max = static_cast<float>(config.range_max_m);
    scan.ranges.resize(beams);
    for (std::size_t i = 0; i < beams; ++i) {
      // The beam's angle as a LaserScan reader computes it from the float fields.
      const double beam = static_cast<double>(scan.angle_min) +
                          static_cast<double>(i) * static_cast<double>(scan.angle_increment);
      const auto [s, c] = perception::portable_sin_cos(sample.yaw + beam);
      const double range = scene.cast(sample.x, sample.y, c, s);
      const bool dropped = random.uniform() < config.dropout_probability;
      const double noisy = range + config.range_noise_sigma_m * gaussian(random);
      if (dropped) {
        scan.ranges[i] = std::numeric_limits<float>::quiet_NaN();
      } else if (range > config.range_max_m) {
        scan.ranges[i] = std::numeric_limits<float>::infinity();
      } else {
        scan.ranges[i] = static_cast<float>(noisy);
      }
    }
  }
  return dataset;
}

}  // namespace robotperf::localization
