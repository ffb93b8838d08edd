#include "robotperf/manipulation/robot_model.hpp"

#include <urdf_model/model.h>
#include <urdf_parser/urdf_parser.h>

#include <algorithm>
#include <cmath>
#include <kdl/chain.hpp>
#include <stdexcept>
#include <string>

#include "kdl_frame.hpp"

namespace robotperf::manipulation {

extern const char* const kXarm6Urdf;  // xarm6_urdf.cpp, generated from robots/xarm6.urdf

namespace {

Eigen::Isometry3d to_eigen(const urdf::Pose& p) {
  double x, y, z, w;
  p.rotation.getQuaternion(x, y, z, w);
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::Quaterniond(w, x, y, z).normalized().toRotationMatrix();
  t.translation() = Eigen::Vector3d(p.position.x, p.position.y, p.position.z);
  return t;
}

Shape to_shape(const urdf::Collision& c, const std::string& link) {
  Shape s;
  s.origin = to_eigen(c.origin);
  if (!c.geometry) throw std::invalid_argument("link '" + link + "': collision without geometry");
  switch (c.geometry->type) {
    case urdf::Geometry::BOX: {
      const auto& b = static_cast<const urdf::Box&>(*c.geometry);
      s.type = Shape::Type::kBox;
      s.box_size = Eigen::Vector3d(b.dim.x, b.dim.y, b.dim.z);
      break;
    }
    case urdf::Geometry::CYLINDER: {
      const auto& cy = static_cast<const urdf::Cylinder&>(*c.geometry);
      s.type = Shape::Type::kCylinder;
      s.radius = cy.radius;
      s.length = cy.length;
      break;
    }
    case urdf::Geometry::SPHERE:
      s.type = Shape::Type::kSphere;
      s.radius = static_cast<const urdf::Sphere&>(*c.geometry).radius;
      break;
    default:
      throw std::invalid_argument(
          "link '" + link + "': only box, cylinder and sphere collision geometry is supported");
  }
  return s;
}

}  // namespace

RobotModel::RobotModel() : chain_(std::make_unique<KDL::Chain>()) {}
RobotModel::RobotModel(const RobotModel& o)
    : name_(o.name_),
      tip_link_(o.tip_link_),
      joint_names_(o.joint_names_),
      limits_(o.limits_),
      joints_(o.joints_),
      tip_offset_(o.tip_offset_),
      links_(o.links_),
      allowed_(o.allowed_),
      chain_(std::make_unique<KDL::Chain>(*o.chain_)) {}
RobotModel::RobotModel(RobotModel&&) noexcept = default;
RobotModel::~RobotModel() = default;

RobotModel RobotModel::from_urdf(const std::string& urdf_xml, const std::string& base_link,
                                 const std::string& tip_link, double max_acceleration) {
  const urdf::ModelInterfaceSharedPtr urdf = urdf::parseURDF(urdf_xml);
  if (!urdf) throw std::invalid_argument("the robot description is not valid URDF");
  if (!urdf->getLink(base_link))
    throw std::invalid_argument("URDF has no base link '" + base_link + "'");
  if (!urdf->getLink(tip_link))
    throw std::invalid_argument("URDF has no tip link '" + tip_link + "'");
  if (!(max_acceleration > 0)) throw std::invalid_argument("max_acceleration must be > 0");

  // The path from the tip up to the base, then walked base -> tip.
  std::vector<urdf::LinkConstSharedPtr> path;
  for (urdf::LinkConstSharedPtr l = urdf->getLink(tip_link); l; l = l->getParent()) {
    path.push_back(l);
    if (l->name == base_link) break;
  }
  if (path.back()->name != base_link) {
    throw std::invalid_argument("link '" + tip_link + "' is not below '" + base_link +
                                "' in the URDF tree");
  }
  std::reverse(path.begin(), path.end());

  RobotModel m;
  m.name_ = urdf->getName();
  m.tip_link_ = tip_link;
  // In the Eigen transform chain fixed joints fold into the next moving joint's origin (after the
  // last one, into tip_offset_); the KDL chain gets a segment for every joint, as kdl_parser
  // builds it.
  Eigen::Isometry3d fixed = Eigen::Isometry3d::Identity();
  for (std::size_t i = 0; i < path.size(); ++i) {
    const auto& link = path[i];
    if (i > 0) {
      const urdf::Joint& j = *link->parent_joint;
      const Eigen::Isometry3d origin = to_eigen(j.parent_to_joint_origin_transform);
      if (j.type == urdf::Joint::REVOLUTE || j.type == urdf::Joint::CONTINUOUS) {
        Eigen::Vector3d axis(j.axis.x, j.axis.y, j.axis.z);
        if (axis.norm() < 1e-9) throw std::invalid_argument("joint '" + j.name + "' has no axis");
        axis.normalize();
        JointLimits lim;
        if (j.type == urdf::Joint::REVOLUTE) {
          if (!j.limits) throw std::invalid_argument("joint '" + j.name + "' has no <limit>");
          lim.lower = j.limits->lower;
          lim.upper = j.limits->upper;
        } else {
          lim.lower = -M_PI;
          lim.upper = M_PI;
        }
        lim.max_velocity = j.limits && j.limits->velocity > 0 ? j.limits->velocity : 1.0;
        lim.max_acceleration = max_acceleration;
        if (!(lim.lower < lim.upper))
          throw std::invalid_argument("joint '" + j.name + "': lower limit is not below upper");
        m.joints_.push_back({fixed * origin, axis});
        m.joint_names_.push_back(j.name);
        m.limits_.push_back(lim);
        // Relative to the KDL segments of the fixed joints before it, not folding them in again.
        const KDL::Frame f = to_kdl(origin);
        m.chain_->addSegment(
            KDL::Segment(link->name,
                         KDL::Joint(j.name, f.p, f.M * KDL::Vector(axis.x(), axis.y(), axis.z()),
                                    KDL::Joint::RotAxis),
                         f));
        fixed = Eigen::Isometry3d::Identity();
      } else if (j.type == urdf::Joint::FIXED) {
        fixed = fixed * origin;
        m.chain_->addSegment(
            KDL::Segment(link->name, KDL::Joint(j.name, KDL::Joint::None), to_kdl(origin)));
      } else {
        throw std::invalid_argument("joint '" + j.name +
                                    "': only revolute, continuous and fixed joints are supported");
      }
    }
    Link l;
    l.name = link->name;
    l.joint = static_cast<int>(m.joints_.size()) - 1;
    for (const auto& c : link->collision_array) {
      Shape s = to_shape(*c, link->name);
      s.origin = fixed * s.origin;
      l.shapes.push_back(s);
    }
    m.links_.push_back(std::move(l));
  }
  m.tip_offset_ = fixed;
  if (m.joints_.empty())
    throw std::invalid_argument("no moving joint between " + base_link + " and " + tip_link);

  // Adjacent links (joined by one joint, fixed joints included) may touch.
  const std::size_t n = m.links_.size();
  m.allowed_.assign(n * n, false);
  for (std::size_t i = 0; i < n; ++i) {
    m.allowed_[i * n + i] = true;
    if (i + 1 < n) m.allowed_[i * n + i + 1] = m.allowed_[(i + 1) * n + i] = true;
  }
  return m;
}

const RobotModel& RobotModel::xarm6() {
  // Velocity limits are in the URDF; the acceleration limit is the published 10 rad/s^2.
  static const RobotModel model = from_urdf(kXarm6Urdf, "link_base", "link6", 10.0);
  return model;
}

bool RobotModel::within_limits(const double* q, double tolerance) const {
  for (std::size_t i = 0; i < limits_.size(); ++i) {
    if (!(q[i] >= limits_[i].lower - tolerance && q[i] <= limits_[i].upper + tolerance))
      return false;
  }
  return true;
}

void RobotModel::link_poses(const double* q, std::vector<Eigen::Isometry3d>& poses) const {
  std::vector<Eigen::Isometry3d> joint_frames(joints_.size());
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  for (std::size_t i = 0; i < joints_.size(); ++i) {
    t = t * joints_[i].origin * Eigen::AngleAxisd(q[i], joints_[i].axis);
    joint_frames[i] = t;
  }
  poses.resize(links_.size());
  for (std::size_t i = 0; i < links_.size(); ++i) {
    poses[i] = links_[i].joint < 0 ? Eigen::Isometry3d::Identity()
                                   : joint_frames[static_cast<std::size_t>(links_[i].joint)];
  }
}

Eigen::Isometry3d RobotModel::tip_pose(const double* q) const {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  for (std::size_t i = 0; i < joints_.size(); ++i)
    t = t * joints_[i].origin * Eigen::AngleAxisd(q[i], joints_[i].axis);
  return t * tip_offset_;
}

std::vector<double> in_model_order(const RobotModel& model, const std::vector<std::string>& names,
                                   const std::vector<double>& values, const char* what) {
  std::vector<double> q;
  if (names.empty()) {
    if (values.size() != model.dof()) {
      throw std::invalid_argument("joint state has " + std::to_string(values.size()) + " " + what +
                                  ", the arm " + std::to_string(model.dof()) + " joints");
    }
    q = values;
  } else {
    if (names.size() != values.size()) {
      throw std::invalid_argument("joint state has " + std::to_string(names.size()) +
                                  " names but " + std::to_string(values.size()) + " " + what);
    }
    q.resize(model.dof());
    for (std::size_t j = 0; j < model.dof(); ++j) {
      const auto it = std::find(names.begin(), names.end(), model.joint_names()[j]);
      if (it == names.end())
        throw std::invalid_argument("joint state has no joint '" + model.joint_names()[j] + "'");
      q[j] = values[static_cast<std::size_t>(it - names.begin())];
    }
  }
  for (std::size_t j = 0; j < q.size(); ++j) {
    if (!std::isfinite(q[j])) {
      throw std::invalid_argument("joint state's " + std::string(what) + " hold a value for '" +
                                  model.joint_names()[j] + "' that is not finite");
    }
  }
  return q;
}

double signed_distance(const Shape& shape, const Eigen::Vector3d& p) {
  switch (shape.type) {
    case Shape::Type::kSphere:
      return p.norm() - shape.radius;
    case Shape::Type::kCylinder: {
      const Eigen::Vector2d d(p.head<2>().norm() - shape.radius,
                              std::abs(p.z()) - shape.length / 2);
      return std::min(std::max(d.x(), d.y()), 0.0) + d.cwiseMax(0.0).norm();
    }
    case Shape::Type::kBox: {
      const Eigen::Vector3d d = p.cwiseAbs() - shape.box_size / 2;
      return std::min(d.maxCoeff(), 0.0) + d.cwiseMax(0.0).norm();
    }
  }
  return 0;
}

}  // namespace robotperf::manipulation
