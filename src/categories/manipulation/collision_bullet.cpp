// The Bullet collision backend: a btCollisionWorld over a btDbvtBroadphase (dynamic AABB tree),
// the allowed-collision matrix as the broad phase's pair filter, zero collision margins so that
// shapes are their exact size.
#include <btBulletCollisionCommon.h>

#include "robotperf/manipulation/collision.hpp"

namespace robotperf::manipulation {
namespace {

std::unique_ptr<btCollisionShape> bullet_shape(const Shape& s) {
  std::unique_ptr<btConvexShape> shape;
  switch (s.type) {
    case Shape::Type::kBox:
      shape = std::make_unique<btBoxShape>(btVector3(static_cast<btScalar>(s.box_size.x() / 2),
                                                     static_cast<btScalar>(s.box_size.y() / 2),
                                                     static_cast<btScalar>(s.box_size.z() / 2)));
      shape->setMargin(0);
      break;
    case Shape::Type::kCylinder:
      shape = std::make_unique<btCylinderShapeZ>(btVector3(static_cast<btScalar>(s.radius),
                                                           static_cast<btScalar>(s.radius),
                                                           static_cast<btScalar>(s.length / 2)));
      shape->setMargin(0);
      break;
    case Shape::Type::kSphere:  // a point with the radius as margin: already exact
      shape = std::make_unique<btSphereShape>(static_cast<btScalar>(s.radius));
      break;
  }
  return shape;
}

btTransform bullet_transform(const Eigen::Isometry3d& t) {
  const Eigen::Matrix3d& r = t.linear();
  const btMatrix3x3 basis(static_cast<btScalar>(r(0, 0)), static_cast<btScalar>(r(0, 1)),
                          static_cast<btScalar>(r(0, 2)), static_cast<btScalar>(r(1, 0)),
                          static_cast<btScalar>(r(1, 1)), static_cast<btScalar>(r(1, 2)),
                          static_cast<btScalar>(r(2, 0)), static_cast<btScalar>(r(2, 1)),
                          static_cast<btScalar>(r(2, 2)));
  return btTransform(basis, btVector3(static_cast<btScalar>(t.translation().x()),
                                      static_cast<btScalar>(t.translation().y()),
                                      static_cast<btScalar>(t.translation().z())));
}

constexpr int kSceneObject = -1;

// Pairs the broad phase hands on: robot vs scene, and links the matrix does not exempt.
class AllowedCollisionFilter final : public btOverlapFilterCallback {
 public:
  explicit AllowedCollisionFilter(const RobotModel& model) : model_(model) {}
  bool needBroadphaseCollision(btBroadphaseProxy* p0, btBroadphaseProxy* p1) const override {
    const int a = static_cast<btCollisionObject*>(p0->m_clientObject)->getUserIndex();
    const int b = static_cast<btCollisionObject*>(p1->m_clientObject)->getUserIndex();
    if (a == kSceneObject || b == kSceneObject) return a != b;
    return !model_.collision_allowed(static_cast<std::size_t>(a), static_cast<std::size_t>(b));
  }

 private:
  const RobotModel& model_;
};

class BulletChecker final : public CollisionChecker {
 public:
  BulletChecker(const RobotModel& model, const Scene& scene)
      : model_(model),
        dispatcher_(&configuration_),
        world_(&dispatcher_, &broadphase_, &configuration_),
        filter_(model) {
    broadphase_.getOverlappingPairCache()->setOverlapFilterCallback(&filter_);
    for (std::size_t i = 0; i < model.links().size(); ++i) {
      for (const auto& s : model.links()[i].shapes) {
        auto& body = add(bullet_shape(s), static_cast<int>(i), model.links()[i].name);
        link_shapes_.push_back({i, s.origin, &body});
      }
    }
    for (const auto& o : scene.objects) {
      auto& body = add(bullet_shape(o.shape), kSceneObject, o.name);
      body.setWorldTransform(bullet_transform(o.shape.origin));
    }
  }

  ~BulletChecker() override {
    for (auto& b : bodies_) world_.removeCollisionObject(b.object.get());
  }

  const char* backend() const override { return "bullet"; }

  CollisionAnswer check(const double* q) override {
    model_.link_poses(q, poses_);
    return check_at(poses_);
  }

  CollisionAnswer check_at(const std::vector<Eigen::Isometry3d>& poses) override {
    for (auto& ls : link_shapes_)
      ls.body->setWorldTransform(bullet_transform(poses[ls.link] * ls.origin));
    // Contact points persist between queries in Bullet's manifolds; a boolean query must not see
    // those of the previous state.
    for (int i = 0; i < dispatcher_.getNumManifolds(); ++i)
      dispatcher_.getManifoldByIndexInternal(i)->clearManifold();
    world_.performDiscreteCollisionDetection();
    CollisionAnswer self;
    for (int i = 0; i < dispatcher_.getNumManifolds(); ++i) {
      const btPersistentManifold* m = dispatcher_.getManifoldByIndexInternal(i);
      bool touching = false;
      for (int c = 0; c < m->getNumContacts() && !touching; ++c)
        touching = m->getContactPoint(c).getDistance() <= 0;
      if (!touching) continue;
      const auto* a = static_cast<const btCollisionObject*>(m->getBody0());
      const auto* b = static_cast<const btCollisionObject*>(m->getBody1());
      const bool with_scene =
          a->getUserIndex() == kSceneObject || b->getUserIndex() == kSceneObject;
      const CollisionAnswer found{true, with_scene, name_of(a), name_of(b)};
      if (with_scene) return found;  // robot vs scene is reported first, as FCL does
      if (!self.in_collision) self = found;
    }
    return self;
  }

 private:
  struct OwnedBody {
    std::unique_ptr<btCollisionShape> shape;
    std::unique_ptr<btCollisionObject> object;
    std::string name;
  };
  struct LinkShape {
    std::size_t link;
    Eigen::Isometry3d origin;
    btCollisionObject* body;
  };

  btCollisionObject& add(std::unique_ptr<btCollisionShape> shape, int user_index,
                         const std::string& name) {
    auto object = std::make_unique<btCollisionObject>();
    object->setCollisionShape(shape.get());
    object->setUserIndex(user_index);
    object->setUserIndex2(static_cast<int>(bodies_.size()));
    world_.addCollisionObject(object.get());
    bodies_.push_back({std::move(shape), std::move(object), name});
    return *bodies_.back().object;
  }

  const std::string& name_of(const btCollisionObject* o) const {
    return bodies_[static_cast<std::size_t>(o->getUserIndex2())].name;
  }

  const RobotModel& model_;
  btDefaultCollisionConfiguration configuration_;
  btCollisionDispatcher dispatcher_;
  btDbvtBroadphase broadphase_;
  btCollisionWorld world_;
  AllowedCollisionFilter filter_;
  std::vector<OwnedBody> bodies_;
  std::vector<LinkShape> link_shapes_;
  std::vector<Eigen::Isometry3d> poses_;
};

}  // namespace

std::unique_ptr<CollisionChecker> make_bullet_checker(const RobotModel& model, const Scene& scene) {
  return std::make_unique<BulletChecker>(model, scene);
}

}  // namespace robotperf::manipulation
