// The FCL collision backend (FCL 0.7): shapes as fcl primitives in dynamic AABB tree managers.
#include <fcl/broadphase/broadphase_dynamic_AABB_tree.h>
#include <fcl/narrowphase/collision.h>

#include <cmath>
#include <stdexcept>

#include "robotperf/manipulation/collision.hpp"

namespace robotperf::manipulation {
namespace {

// The shape grown by `padding` on every side (a box, cylinder or sphere that contains the shape's
// Minkowski sum with a ball of that radius).
std::shared_ptr<fcl::CollisionGeometryd> fcl_geometry(const Shape& s, double padding = 0) {
  switch (s.type) {
    case Shape::Type::kBox: {
      const Eigen::Vector3d size = s.box_size.array() + 2 * padding;
      return std::make_shared<fcl::Boxd>(size.x(), size.y(), size.z());
    }
    case Shape::Type::kCylinder:
      return std::make_shared<fcl::Cylinderd>(s.radius + padding, s.length + 2 * padding);
    case Shape::Type::kSphere:
      return std::make_shared<fcl::Sphered>(s.radius + padding);
  }
  return nullptr;
}

struct Body {
  int link;          // index into RobotModel::links(), -1 for scene objects
  std::string name;  // a copy: the scene may be a temporary
};

class FclChecker final : public CollisionChecker {
 public:
  FclChecker(const RobotModel& model, const Scene& scene, double padding) : model_(model) {
    for (std::size_t i = 0; i < model.links().size(); ++i) {
      bodies_.push_back({static_cast<int>(i), model.links()[i].name});
    }
    for (const auto& o : scene.objects) scene_bodies_.push_back({-1, o.name});
    for (std::size_t i = 0; i < model.links().size(); ++i) {
      for (const auto& s : model.links()[i].shapes) {
        auto obj = std::make_unique<fcl::CollisionObjectd>(fcl_geometry(s, padding));
        obj->setUserData(&bodies_[i]);
        link_shapes_.push_back({static_cast<int>(i), s.origin, obj.get()});
        robot_.registerObject(obj.get());
        objects_.push_back(std::move(obj));
      }
    }
    for (std::size_t i = 0; i < scene.objects.size(); ++i) {
      const auto& o = scene.objects[i];
      auto obj = std::make_unique<fcl::CollisionObjectd>(fcl_geometry(o.shape), o.shape.origin);
      obj->computeAABB();
      obj->setUserData(&scene_bodies_[i]);
      world_.registerObject(obj.get());
      objects_.push_back(std::move(obj));
    }
    robot_.setup();
    world_.setup();
  }

  const char* backend() const override { return "fcl"; }

  CollisionAnswer check(const double* q) override {
    model_.link_poses(q, poses_);
    return check_at(poses_);
  }

  CollisionAnswer check_at(const std::vector<Eigen::Isometry3d>& poses) override {
    for (auto& ls : link_shapes_) {
      ls.object->setTransform(poses[static_cast<std::size_t>(ls.link)] * ls.origin);
      ls.object->computeAABB();
    }
    robot_.update();
    Query query{this, {}};
    robot_.collide(&world_, &query, &Query::callback);
    if (!query.answer.in_collision) robot_.collide(&query, &Query::callback);
    return query.answer;
  }

 private:
  struct LinkShape {
    int link;
    Eigen::Isometry3d origin;
    fcl::CollisionObjectd* object;
  };
  struct Query {
    FclChecker* self;
    CollisionAnswer answer;
    // FCL's broad-phase callback: true stops the traversal.
    static bool callback(fcl::CollisionObjectd* a, fcl::CollisionObjectd* b, void* data) {
      auto& q = *static_cast<Query*>(data);
      if (q.answer.in_collision) return true;
      const auto& ba = *static_cast<const Body*>(a->getUserData());
      const auto& bb = *static_cast<const Body*>(b->getUserData());
      const bool with_scene = ba.link < 0 || bb.link < 0;
      if (!with_scene && q.self->model_.collision_allowed(static_cast<std::size_t>(ba.link),
                                                          static_cast<std::size_t>(bb.link)))
        return false;
      fcl::CollisionRequestd request;  // one contact, no penetration depth: a boolean query
      fcl::CollisionResultd result;
      if (fcl::collide(a, b, request, result) == 0) return false;
      q.answer = {true, with_scene, ba.name, bb.name};
      return true;
    }
  };

  const RobotModel& model_;
  std::vector<Body> bodies_;
  std::vector<Body> scene_bodies_;
  std::vector<std::unique_ptr<fcl::CollisionObjectd>> objects_;
  std::vector<LinkShape> link_shapes_;
  fcl::DynamicAABBTreeCollisionManagerd robot_;
  fcl::DynamicAABBTreeCollisionManagerd world_;
  std::vector<Eigen::Isometry3d> poses_;
};

}  // namespace

std::unique_ptr<CollisionChecker> make_fcl_checker(const RobotModel& model, const Scene& scene,
                                                   double padding) {
  if (!(padding >= 0) || !std::isfinite(padding))
    throw std::invalid_argument("collision padding must be a finite length >= 0");
  return std::make_unique<FclChecker>(model, scene, padding);
}

}  // namespace robotperf::manipulation
