// A small ray caster for scenes of textured boxes and rectangles, from which the stereo, depth
// and visual-odometry datasets are rendered with exact ground truth. Only + - * / and floor are
// used, so the bytes are the same on every platform when the including file is built without
// fused multiply-add contraction (-ffp-contract=off).
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

namespace robotperf::perception::raycast {

struct Vec3 {
  double x = 0, y = 0, z = 0;
};
inline Vec3 operator+(Vec3 a, Vec3 b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
inline Vec3 operator-(Vec3 a, Vec3 b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
inline Vec3 operator*(double s, Vec3 a) {
  return {s * a.x, s * a.y, s * a.z};
}
inline double dot(Vec3 a, Vec3 b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
inline Vec3 cross(Vec3 a, Vec3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

inline uint32_t mix_bits(uint32_t h) {
  h ^= h >> 16;
  h *= 0x85ebca6bU;
  h ^= h >> 13;
  h *= 0xc2b2ae35U;
  h ^= h >> 16;
  return h;
}

// Smooth value noise in [-1, 1], one lattice value per unit cell.
inline double value_noise(double x, double y, uint32_t seed) {
  const double fx = std::floor(x);
  const double fy = std::floor(y);
  const auto i = static_cast<int64_t>(fx);
  const auto j = static_cast<int64_t>(fy);
  auto lattice = [seed](int64_t a, int64_t b) {
    const uint32_t h = mix_bits(static_cast<uint32_t>(a) * 73856093U ^
                                static_cast<uint32_t>(b) * 19349663U ^ seed * 83492791U);
    return static_cast<double>(h) * (2.0 / 4294967295.0) - 1.0;
  };
  const double tx = x - fx;
  const double ty = y - fy;
  const double sx = tx * tx * (3.0 - 2.0 * tx);
  const double sy = ty * ty * (3.0 - 2.0 * ty);
  const double top = lattice(i, j) + sx * (lattice(i + 1, j) - lattice(i, j));
  const double bottom = lattice(i, j + 1) + sx * (lattice(i + 1, j + 1) - lattice(i, j + 1));
  return top + sy * (bottom - top);
}

// A surface's appearance: three octaves of value noise on its own metric coordinates, tinted.
struct Texture {
  double cell_m = 0.03;  // the finest octave's cell
  uint32_t seed = 1;
  double tint[3] = {1.0, 1.0, 1.0};

  void colour(double s, double t, uint8_t rgb[3]) const {
    const double n = 0.5 * value_noise(s / cell_m, t / cell_m, seed) +
                     0.3 * value_noise(s / (2.7 * cell_m), t / (2.7 * cell_m), seed + 101) +
                     0.2 * value_noise(s / (7.3 * cell_m), t / (7.3 * cell_m), seed + 202);
    const double intensity = 128.0 + 110.0 * n;
    for (int c = 0; c < 3; ++c) {
      const double v = intensity * tint[c];
      rgb[c] = static_cast<uint8_t>(v < 0.0 ? 0.0 : (v > 255.0 ? 255.0 : v + 0.5));
    }
  }
};

// A rectangle origin + a·u + b·v, a, b in [0, 1] (u, v orthogonal), optionally with a
// rectangular hole [hole_a0, hole_a1] x [hole_b0, hole_b1] in the same parameters.
struct Rectangle {
  Vec3 origin, u, v;
  Texture texture;
  bool has_hole = false;
  double hole_a0 = 0, hole_a1 = 0, hole_b0 = 0, hole_b1 = 0;
};

// An axis-aligned box.
struct Box {
  Vec3 min, max;
  Texture texture;
};

struct Hit {
  double distance = std::numeric_limits<double>::infinity();  // along the ray's direction
  Vec3 point;
  int surface = -1;  // which primitive (rectangles first, then boxes)
  uint8_t rgb[3] = {0, 0, 0};
  bool found() const { return surface >= 0; }
};

struct Scene {
  std::vector<Rectangle> rectangles;
  std::vector<Box> boxes;
  uint8_t background[3] = {0, 0, 0};

  // The nearest surface hit by origin + s·direction, s > 0; its colour only when `shaded`.
  Hit cast(Vec3 origin, Vec3 direction, bool shaded = true) const {
    Hit best;
    int index = 0;
    for (const Rectangle& r : rectangles) {
      intersect(r, origin, direction, index++, best);
    }
    for (const Box& b : boxes) intersect(b, origin, direction, index++, best);
    if (!shaded) return best;
    if (best.found()) {
      shade(best);
    } else {
      for (int c = 0; c < 3; ++c) best.rgb[c] = background[c];
    }
    return best;
  }

 private:
  static void intersect(const Rectangle& r, Vec3 o, Vec3 d, int index, Hit& best) {
    const Vec3 normal = cross(r.u, r.v);
    const double denominator = dot(normal, d);
    if (denominator == 0.0) return;
    const double s = dot(normal, r.origin - o) / denominator;
    if (!(s > 0.0) || s >= best.distance) return;
    const Vec3 p = o + s * d;
    const Vec3 rel = p - r.origin;
    const double a = dot(rel, r.u) / dot(r.u, r.u);
    const double b = dot(rel, r.v) / dot(r.v, r.v);
    if (a < 0.0 || a > 1.0 || b < 0.0 || b > 1.0) return;
    if (r.has_hole && a > r.hole_a0 && a < r.hole_a1 && b > r.hole_b0 && b < r.hole_b1) return;
    best.distance = s;
    best.point = p;
    best.surface = index;
  }

  static void intersect(const Box& box, Vec3 o, Vec3 d, int index, Hit& best) {
    double enter = 0.0;
    double leave = best.distance;
    const double lo[3] = {box.min.x, box.min.y, box.min.z};
    const double hi[3] = {box.max.x, box.max.y, box.max.z};
    const double origin[3] = {o.x, o.y, o.z};
    const double direction[3] = {d.x, d.y, d.z};
    for (int axis = 0; axis < 3; ++axis) {
      if (direction[axis] == 0.0) {
        if (origin[axis] < lo[axis] || origin[axis] > hi[axis]) return;
        continue;
      }
      double near = (lo[axis] - origin[axis]) / direction[axis];
      double far = (hi[axis] - origin[axis]) / direction[axis];
      if (near > far) std::swap(near, far);
      if (near > enter) enter = near;
      if (far < leave) leave = far;
      if (enter > leave) return;
    }
    if (!(enter > 0.0) || enter >= best.distance) return;
    best.distance = enter;
    best.point = o + enter * d;
    best.surface = index;
  }

  void shade(Hit& hit) const {
    const auto n = static_cast<int>(rectangles.size());
    if (hit.surface < n) {
      const Rectangle& r = rectangles[static_cast<std::size_t>(hit.surface)];
      const Vec3 rel = hit.point - r.origin;
      const double lu = std::sqrt(dot(r.u, r.u));
      const double lv = std::sqrt(dot(r.v, r.v));
      r.texture.colour(dot(rel, r.u) / lu, dot(rel, r.v) / lv, hit.rgb);
      return;
    }
    const Box& b = boxes[static_cast<std::size_t>(hit.surface - n)];
    // Texture each face on the two coordinates across it, from the box's corner, so that the
    // pattern moves with the box.
    const Vec3 rel = hit.point - b.min;
    const Vec3 size = b.max - b.min;
    const double eps = 1e-9;
    if (rel.z <= eps * size.z + 1e-12 || rel.z >= size.z * (1.0 - eps)) {
      b.texture.colour(rel.x, rel.y, hit.rgb);
    } else if (rel.x <= eps * size.x + 1e-12 || rel.x >= size.x * (1.0 - eps)) {
      b.texture.colour(rel.z + 7.0, rel.y, hit.rgb);
    } else {
      b.texture.colour(rel.x, rel.z + 13.0, hit.rgb);
    }
  }
};

}  // namespace robotperf::perception::raycast
