// Sampled ground truth for collision queries, and the benchmarks' scene.
#include <algorithm>
#include <cmath>
#include <limits>

#include "robotperf/manipulation/collision.hpp"

namespace robotperf::manipulation {
namespace {

// Points on a shape's surface (in the shape's frame), no two neighbours more than `spacing` apart.
std::vector<Eigen::Vector3d> surface_samples(const Shape& s, double spacing) {
  std::vector<Eigen::Vector3d> out;
  auto steps = [&](double extent) {
    return std::max(1, static_cast<int>(std::ceil(extent / spacing)));
  };
  switch (s.type) {
    case Shape::Type::kBox: {
      const Eigen::Vector3d h = s.box_size / 2;
      for (int axis = 0; axis < 3; ++axis) {
        const int u = (axis + 1) % 3, v = (axis + 2) % 3;
        const int nu = steps(s.box_size[u]), nv = steps(s.box_size[v]);
        for (int side = -1; side <= 1; side += 2) {
          for (int i = 0; i <= nu; ++i) {
            for (int j = 0; j <= nv; ++j) {
              Eigen::Vector3d p;
              p[axis] = side * h[axis];
              p[u] = -h[u] + s.box_size[u] * i / nu;
              p[v] = -h[v] + s.box_size[v] * j / nv;
              out.push_back(p);
            }
          }
        }
      }
      break;
    }
    case Shape::Type::kCylinder: {
      const double h = s.length / 2;
      const int around = steps(2 * M_PI * s.radius);
      const int along = steps(s.length);
      for (int k = 0; k < around; ++k) {
        const double a = 2 * M_PI * k / around;
        for (int i = 0; i <= along; ++i)
          out.emplace_back(s.radius * std::cos(a), s.radius * std::sin(a),
                           -h + s.length * i / along);
      }
      const int rings = steps(s.radius);
      for (int r = 0; r <= rings; ++r) {
        const double rad = s.radius * r / rings;
        const int n = std::max(1, steps(2 * M_PI * rad));
        for (int k = 0; k < n; ++k) {
          const double a = 2 * M_PI * k / n;
          out.emplace_back(rad * std::cos(a), rad * std::sin(a), -h);
          out.emplace_back(rad * std::cos(a), rad * std::sin(a), h);
        }
      }
      break;
    }
    case Shape::Type::kSphere: {
      const int lat = steps(M_PI * s.radius);
      for (int i = 0; i <= lat; ++i) {
        const double polar = M_PI * i / lat;
        const int n = std::max(1, steps(2 * M_PI * s.radius * std::sin(polar)));
        for (int k = 0; k < n; ++k) {
          const double a = 2 * M_PI * k / n;
          out.emplace_back(s.radius * std::sin(polar) * std::cos(a),
                           s.radius * std::sin(polar) * std::sin(a), s.radius * std::cos(polar));
        }
      }
      break;
    }
  }
  return out;
}

struct PosedShape {
  const Shape* shape;
  Eigen::Isometry3d pose;  // in the base frame
  std::vector<Eigen::Vector3d> samples;
};

// Smallest signed distance of a's surface samples to b, and of b's to a; stops early below `stop`.
double min_distance(const PosedShape& a, const PosedShape& b, double stop) {
  double m = std::numeric_limits<double>::infinity();
  for (const auto* pair : {&a, &b}) {
    const PosedShape& from = *pair;
    const PosedShape& to = pair == &a ? b : a;
    const Eigen::Isometry3d rel = to.pose.inverse() * from.pose;
    for (const auto& p : from.samples) {
      m = std::min(m, signed_distance(*to.shape, rel * p));
      if (m <= stop) return m;
    }
  }
  return m;
}

}  // namespace

GroundTruthAnswer sampled_ground_truth(const RobotModel& model, const Scene& scene, const double* q,
                                       double spacing, double margin) {
  std::vector<Eigen::Isometry3d> link_poses;
  model.link_poses(q, link_poses);
  std::vector<std::vector<PosedShape>> links(model.links().size());
  for (std::size_t i = 0; i < links.size(); ++i) {
    for (const auto& s : model.links()[i].shapes)
      links[i].push_back({&s, link_poses[i] * s.origin, surface_samples(s, spacing)});
  }
  std::vector<PosedShape> objects;
  for (const auto& o : scene.objects)
    objects.push_back({&o.shape, o.shape.origin, surface_samples(o.shape, spacing)});

  double m = std::numeric_limits<double>::infinity();
  const double stop = -margin;
  auto visit = [&](const PosedShape& a, const PosedShape& b) {
    m = std::min(m, min_distance(a, b, stop));
    return m <= stop;
  };
  bool done = false;
  for (std::size_t i = 0; i < links.size() && !done; ++i) {
    for (const auto& a : links[i]) {
      for (const auto& b : objects) done = done || visit(a, b);
    }
  }
  for (std::size_t i = 0; i < links.size() && !done; ++i) {
    for (std::size_t j = i + 1; j < links.size() && !done; ++j) {
      if (model.collision_allowed(i, j)) continue;
      for (const auto& a : links[i]) {
        for (const auto& b : links[j]) done = done || visit(a, b);
      }
    }
  }
  GroundTruthAnswer answer;
  answer.min_sampled_distance = m;
  answer.truth = m <= -margin           ? GroundTruth::kColliding
                 : m > spacing + margin ? GroundTruth::kFree
                                        : GroundTruth::kUncertain;
  return answer;
}

Scene box_scene(const Eigen::Vector3d& size, const Eigen::Vector3d& centre) {
  SceneObject box;
  box.name = "box";
  box.shape.type = Shape::Type::kBox;
  box.shape.box_size = size;
  box.shape.origin = Eigen::Isometry3d::Identity();
  box.shape.origin.translation() = centre;
  return Scene{{box}};
}

Scene default_scene() {
  // A 0.2 x 0.2 x 0.4 m pillar standing 0.45 m in front of the base, inside the arm's reach.
  return box_scene(Eigen::Vector3d(0.2, 0.2, 0.4), Eigen::Vector3d(0.45, 0.0, 0.2));
}

std::unique_ptr<CollisionChecker> make_collision_checker(CollisionBackend backend,
                                                         const RobotModel& model,
                                                         const Scene& scene) {
  return backend == CollisionBackend::kFcl ? make_fcl_checker(model, scene)
                                           : make_bullet_checker(model, scene);
}

}  // namespace robotperf::manipulation
