// Collision checking of a RobotModel against a Scene and itself: a boolean query as MoveIt's
// collision backends answer it. The FCL and Bullet backends keep their headers in their .cpp.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "robotperf/manipulation/robot_model.hpp"

namespace robotperf::manipulation {

struct CollisionAnswer {
  bool in_collision = false;
  bool with_scene = false;  // the contact found is robot vs scene (else robot vs itself)
  std::string first;        // the two bodies in contact (link or scene object names)
  std::string second;
};

// Not thread-safe: each checker keeps its own collision objects posed at the last query.
class CollisionChecker {
 public:
  virtual ~CollisionChecker() = default;
  virtual const char* backend() const = 0;
  // Robot vs the scene first, then self-collision of the links the allowed-collision matrix does
  // not exempt; stops at the first contact (touching counts as collision).
  virtual CollisionAnswer check(const double* q) = 0;
  // The same query with the links posed by the caller: each link's pose in the base frame, in
  // RobotModel::links() order (as a planning scene poses them from tf).
  virtual CollisionAnswer check_at(const std::vector<Eigen::Isometry3d>& link_poses) = 0;
};

enum class CollisionBackend { kFcl, kBullet };

// FCL: one DynamicAABBTree broad phase for the links and one for the scene. `padding` (m) grows
// every link shape on every side, as MoveIt's link padding does: "free" then means at least that
// clearance to the scene (twice that between links). Throws std::invalid_argument for a negative
// padding.
std::unique_ptr<CollisionChecker> make_fcl_checker(const RobotModel& model, const Scene& scene,
                                                   double padding = 0);
// Bullet: a btCollisionWorld with a dynamic AABB tree (btDbvtBroadphase), margins zero.
std::unique_ptr<CollisionChecker> make_bullet_checker(const RobotModel& model, const Scene& scene);
std::unique_ptr<CollisionChecker> make_collision_checker(CollisionBackend backend,
                                                         const RobotModel& model,
                                                         const Scene& scene);

// Independent ground truth by sampling: the surfaces of every pair of shapes that may not touch
// are sampled at `spacing` and each sample's signed distance to the other shape is computed
// analytically. Two closed solids intersect exactly when a surface point of one lies in the other,
// and signed distance is 1-Lipschitz, so the smallest sampled distance m decides: m <= -margin is
// certainly in collision, m > spacing + margin certainly free, anything between is uncertain.
enum class GroundTruth { kFree, kColliding, kUncertain };
struct GroundTruthAnswer {
  GroundTruth truth = GroundTruth::kUncertain;
  double min_sampled_distance = 0;  // m
};
GroundTruthAnswer sampled_ground_truth(const RobotModel& model, const Scene& scene, const double* q,
                                       double spacing = 0.004, double margin = 0.001);

// The benchmarks' scene: one box in front of the arm (size and centre in metres, base frame).
Scene box_scene(const Eigen::Vector3d& size, const Eigen::Vector3d& centre);
Scene default_scene();

}  // namespace robotperf::manipulation
