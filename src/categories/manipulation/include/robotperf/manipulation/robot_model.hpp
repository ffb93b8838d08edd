// A serial arm for the manipulation kernels: its kinematic chain (for KDL), joint limits,
// collision geometry per link (primitives) and the allowed-collision matrix, read from URDF.
// Kept free of FCL, Bullet and OMPL headers: those stay inside the kernels' .cpp files.
#pragma once

#include <Eigen/Geometry>
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

namespace KDL {
class Chain;
}

namespace robotperf::manipulation {

// A collision primitive in its link's frame. Cylinders are along their local z axis.
struct Shape {
  enum class Type { kBox, kCylinder, kSphere };
  Type type = Type::kBox;
  Eigen::Vector3d box_size = Eigen::Vector3d::Zero();  // full edge lengths (kBox)
  double radius = 0;                                   // kCylinder, kSphere
  double length = 0;                                   // kCylinder
  Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();
};

struct Link {
  std::string name;
  // Which joint moves it: -1 for the base (fixed in the world), i for the link after joint i.
  int joint = -1;
  std::vector<Shape> shapes;
};

struct JointLimits {
  double lower = 0;
  double upper = 0;
  double max_velocity = 0;      // rad/s
  double max_acceleration = 0;  // rad/s^2 (URDF has none: given to the loader)
};

// An obstacle of the planning scene.
struct SceneObject {
  std::string name;
  Shape shape;  // shape.origin is its pose in the robot base frame
};

struct Scene {
  std::vector<SceneObject> objects;
};

class RobotModel {
 public:
  // Reads the chain from `base_link` to `tip_link` of a URDF document: revolute and continuous
  // joints move, fixed joints fold into their parent. Links on the chain and their collision
  // primitives (box, cylinder, sphere) are kept; the allowed-collision matrix allows each pair of
  // links joined by a joint. Throws std::invalid_argument naming what is wrong.
  static RobotModel from_urdf(const std::string& urdf_xml, const std::string& base_link,
                              const std::string& tip_link, double max_acceleration);

  // The built-in xArm6-class arm (link_base -> link6, acceleration limit 10 rad/s^2).
  static const RobotModel& xarm6();

  RobotModel(const RobotModel&);
  RobotModel(RobotModel&&) noexcept;
  RobotModel& operator=(const RobotModel&) = delete;
  ~RobotModel();

  const std::string& name() const { return name_; }
  std::size_t dof() const { return joint_names_.size(); }
  const std::vector<std::string>& joint_names() const { return joint_names_; }
  const std::vector<JointLimits>& limits() const { return limits_; }
  const std::vector<Link>& links() const { return links_; }
  const std::string& base_link() const { return links_.front().name; }
  const std::string& tip_link() const { return tip_link_; }
  // KDL's joints cache their last pose (not thread-safe): a solver works on a copy of its own.
  const KDL::Chain& chain() const { return *chain_; }

  bool collision_allowed(std::size_t link_a, std::size_t link_b) const {
    return allowed_[link_a * links_.size() + link_b];
  }
  // True when every q[i] is within [lower - tolerance, upper + tolerance].
  bool within_limits(const double* q, double tolerance = 0) const;

  // The pose of every link of links() in the base frame, computed with Eigen from the URDF
  // joint origins (independently of KDL, so it can check KDL's answers).
  void link_poses(const double* q, std::vector<Eigen::Isometry3d>& poses) const;
  // The tip link's pose in the base frame, the same way.
  Eigen::Isometry3d tip_pose(const double* q) const;

 private:
  RobotModel();
  struct JointFrame {
    Eigen::Isometry3d origin;  // parent link -> joint frame at q = 0
    Eigen::Vector3d axis;      // in the joint frame
  };
  std::string name_;
  std::string tip_link_;
  std::vector<std::string> joint_names_;
  std::vector<JointLimits> limits_;
  std::vector<JointFrame> joints_;
  Eigen::Isometry3d tip_offset_ = Eigen::Isometry3d::Identity();  // fixed joints after the last
  std::vector<Link> links_;
  std::vector<bool> allowed_;
  std::unique_ptr<KDL::Chain> chain_;
};

// Signed distance from a point (in the shape's frame) to a primitive: negative inside.
double signed_distance(const Shape& shape, const Eigen::Vector3d& p);

// One field of a JointState or JointTrajectoryPoint (`what`: "positions", "velocities", ...) in
// the model's joint order: by name when `names` is not empty (joints the model does not have are
// ignored, as a JointState may carry a gripper's), else positionally. Throws
// std::invalid_argument naming what does not fit: a size, a missing joint, a value not finite.
std::vector<double> in_model_order(const RobotModel& model, const std::vector<std::string>& names,
                                   const std::vector<double>& values, const char* what);

}  // namespace robotperf::manipulation
