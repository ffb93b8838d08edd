// Functional evaluators of the manipulation benchmarks (d1-d6). Answers are checked with
// computations independent of the kernel under test: FK and IK against the URDF's own transform
// chain (Eigen, not KDL), collision answers against the sampled ground truth and against both
// FCL and Bullet, plans by re-checking every interpolated state with FCL and Bullet without the
// planner's link padding.
#include <algorithm>
#include <cmath>

#include "category.hpp"
#include "robotperf/manipulation/collision.hpp"
#include "robotperf/manipulation/kinematics.hpp"
#include "robotperf/manipulation/planning.hpp"
#include "robotperf/msgs/eigen_geometry.hpp"
#include "robotperf/msgs/robotperf_msgs.hpp"
#include "robotperf/msgs/sensor_msgs.hpp"

namespace robotperf::manipulation {
namespace {

using plugin::DatasetStream;
using plugin::FunctionalEvaluator;

const double kNaN = std::nan("");

// The positions of a JointState in the model's order, or empty when they do not fit.
std::vector<double> positions(const RobotModel& m, const msgs::JointState& s) {
  if (s.position.size() != m.dof()) return {};
  if (s.name.empty()) return s.position;
  std::vector<double> q(m.dof());
  for (std::size_t j = 0; j < m.dof(); ++j) {
    auto it = std::find(s.name.begin(), s.name.end(), m.joint_names()[j]);
    if (it == s.name.end()) return {};
    q[j] = s.position[static_cast<std::size_t>(it - s.name.begin())];
  }
  return q;
}

class ForwardKinematicsEvaluator final : public FunctionalEvaluator {
 public:
  explicit ForwardKinematicsEvaluator(const DatasetStream& truth) : truth_(truth) {
    plugin::require_type<msgs::PoseStamped>(truth, "forward_kinematics");
  }
  void add(const void* output, std::size_t frame) override {
    const auto& out = *static_cast<const msgs::PoseStamped*>(output);
    const auto& truth = *static_cast<const msgs::PoseStamped*>(truth_.messages[frame].get());
    if (out.header.frame_id != truth.header.frame_id)
      problem("pose frame is '" + out.header.frame_id + "', expected '" + truth.header.frame_id +
              "'");
    double dp, dr;
    manipulation::pose_error(msgs::isometry_of(out.pose), msgs::isometry_of(truth.pose), dp, dr);
    position_ = std::max(position_, dp);
    orientation_ = std::max(orientation_, dr);
    ++n_;
  }
  std::map<std::string, double> metrics() const override {
    return {{"position_error_max_m", n_ ? position_ : kNaN},
            {"orientation_error_max_rad", n_ ? orientation_ : kNaN}};
  }

 private:
  const DatasetStream& truth_;
  double position_ = 0, orientation_ = 0;
  std::size_t n_ = 0;
};

class InverseKinematicsEvaluator final : public FunctionalEvaluator {
 public:
  explicit InverseKinematicsEvaluator(const DatasetStream& target) : target_(target) {
    plugin::require_type<msgs::PoseStamped>(target, "inverse_kinematics");
  }
  void add(const void* output, std::size_t frame) override {
    const RobotModel& m = RobotModel::xarm6();
    const auto& out = *static_cast<const msgs::JointState*>(output);
    const auto& target = *static_cast<const msgs::PoseStamped*>(target_.messages[frame].get());
    ++n_;
    if (out.position.empty()) return;  // no solution found
    const auto q = positions(m, out);
    if (q.empty()) {
      problem("solution is not a joint state of the arm's " + std::to_string(m.dof()) + " joints");
      return;
    }
    if (!m.within_limits(q.data(), 1e-9)) problem("a solution is outside the joint limits");
    double dp, dr;
    manipulation::pose_error(m.tip_pose(q.data()), msgs::isometry_of(target.pose), dp, dr);
    ++solved_;
    position_ = std::max(position_, dp);
    orientation_ = std::max(orientation_, dr);
    position_sum_ += dp;
  }
  std::map<std::string, double> metrics() const override {
    return {
        {"success_rate", n_ ? static_cast<double>(solved_) / static_cast<double>(n_) : kNaN},
        {"position_error_mean_m", solved_ ? position_sum_ / static_cast<double>(solved_) : kNaN},
        {"position_error_max_m", solved_ ? position_ : kNaN},
        {"orientation_error_max_rad", solved_ ? orientation_ : kNaN}};
  }

 private:
  const DatasetStream& target_;
  std::size_t n_ = 0, solved_ = 0;
  double position_ = 0, orientation_ = 0, position_sum_ = 0;
};

class CollisionEvaluator final : public FunctionalEvaluator {
 public:
  CollisionEvaluator(const DatasetStream& truth, const DatasetStream& states)
      : truth_(truth),
        states_(states),
        fcl_(manipulation::make_fcl_checker(RobotModel::xarm6(), manipulation::default_scene())),
        bullet_(
            manipulation::make_bullet_checker(RobotModel::xarm6(), manipulation::default_scene())) {
    plugin::require_type<msgs::CollisionResult>(truth, "collision");
    plugin::require_type<msgs::JointState>(states, "collision");
  }
  void add(const void* output, std::size_t frame) override {
    const auto& out = *static_cast<const msgs::CollisionResult*>(output);
    const auto& truth = *static_cast<const msgs::CollisionResult*>(truth_.messages[frame].get());
    const auto& state = *static_cast<const msgs::JointState*>(states_.messages[frame].get());
    const auto q = positions(RobotModel::xarm6(), state);
    ++n_;
    agree_truth_ += out.in_collision == truth.in_collision;
    const auto a = fcl_->check(q.data());
    const auto b = bullet_->check(q.data());
    agree_backends_ += a.in_collision == b.in_collision;
    agree_kernel_ += out.in_collision == a.in_collision && out.in_collision == b.in_collision;
    colliding_ += truth.in_collision;
  }
  std::map<std::string, double> metrics() const override {
    auto share = [&](std::size_t k) {
      return n_ ? static_cast<double>(k) / static_cast<double>(n_) : kNaN;
    };
    return {{"truth_agreement", share(agree_truth_)},
            {"fcl_bullet_agreement", share(agree_backends_)},
            {"kernel_backends_agreement", share(agree_kernel_)},
            {"colliding_fraction", share(colliding_)}};
  }

 private:
  const DatasetStream& truth_;
  const DatasetStream& states_;
  std::unique_ptr<manipulation::CollisionChecker> fcl_, bullet_;
  std::size_t n_ = 0, agree_truth_ = 0, agree_backends_ = 0, agree_kernel_ = 0, colliding_ = 0;
};

class PlanExecutionEvaluator final : public FunctionalEvaluator {
 public:
  explicit PlanExecutionEvaluator(const DatasetStream& queries)
      : queries_(queries),
        fcl_(manipulation::make_fcl_checker(RobotModel::xarm6(), manipulation::default_scene())),
        bullet_(
            manipulation::make_bullet_checker(RobotModel::xarm6(), manipulation::default_scene())) {
    plugin::require_type<msgs::JointTrajectory>(queries, "plan_execution");
  }
  void add(const void* output, std::size_t frame) override {
    const RobotModel& m = RobotModel::xarm6();
    const auto& out = *static_cast<const msgs::PlanExecutionResult*>(output);
    const auto& query = *static_cast<const msgs::JointTrajectory*>(queries_.messages[frame].get());
    ++n_;
    if (!out.success || out.trajectory.points.empty()) return;
    ++succeeded_;
    manipulation::JointPath path;
    for (const auto& p : out.trajectory.points) path.push_back(p.positions);
    auto close = [](const std::vector<double>& a, const std::vector<double>& b) {
      if (a.size() != b.size()) return false;
      for (std::size_t j = 0; j < a.size(); ++j)
        if (std::abs(a[j] - b[j]) > 1e-6) return false;
      return true;
    };
    const bool ends = close(path.front(), query.points.front().positions) &&
                      close(path.back(), query.points.back().positions);
    if (!ends) problem("a trajectory does not start at the query's start or end at its goal");
    bool limits_ok = true;
    for (const auto& p : out.trajectory.points) {
      for (std::size_t j = 0; j < m.dof() && j < p.velocities.size(); ++j) {
        limits_ok &= std::abs(p.velocities[j]) <= m.limits()[j].max_velocity * (1 + 1e-9);
        if (j < p.accelerations.size())
          limits_ok &= std::abs(p.accelerations[j]) <= m.limits()[j].max_acceleration * (1 + 1e-9);
      }
    }
    if (!limits_ok) problem("a trajectory exceeds the velocity or acceleration limits");
    // Both backends without padding, finer than the planner's own motion checks.
    valid_ += ends && limits_ok && manipulation::path_valid(m, *fcl_, path, kRecheckStep) &&
              manipulation::path_valid(m, *bullet_, path, kRecheckStep);
    length_sum_ += out.path_length;
    tracking_ = std::max(tracking_, out.max_tracking_error);
  }
  std::map<std::string, double> metrics() const override {
    const double n = static_cast<double>(n_), s = static_cast<double>(succeeded_);
    return {{"success_rate", n_ ? s / n : kNaN},
            {"valid_fraction", succeeded_ ? static_cast<double>(valid_) / s : kNaN},
            {"path_length_mean_rad", succeeded_ ? length_sum_ / s : kNaN},
            {"tracking_error_max_rad", succeeded_ ? tracking_ : kNaN}};
  }

 private:
  static constexpr double kRecheckStep = 0.005;  // rad
  const DatasetStream& queries_;
  std::unique_ptr<manipulation::CollisionChecker> fcl_, bullet_;
  std::size_t n_ = 0, succeeded_ = 0, valid_ = 0;
  double length_sum_ = 0, tracking_ = 0;
};

}  // namespace

void register_evaluators(plugin::Registrar& registrar) {
  registrar.add_evaluator(
      {.name = "forward_kinematics",
       .description = "flange pose against the URDF transform chain computed without KDL",
       .output_type = "geometry_msgs/msg/PoseStamped",
       .truth_roles = {"pose"},
       .metrics = {{"position_error_max_m", "m", "largest position difference"},
                   {"orientation_error_max_rad", "rad",
                    "largest rotation angle between the poses"}}},
      [](const plugin::TruthStreams& t, const plugin::Parameters&) {
        return std::make_unique<ForwardKinematicsEvaluator>(t["pose"]);
      });
  registrar.add_evaluator(
      {.name = "inverse_kinematics",
       .description = "solutions' flange poses (URDF transform chain, not KDL) against the targets",
       .output_type = "sensor_msgs/msg/JointState",
       .truth_roles = {"target"},
       .metrics = {{"success_rate", "fraction", "targets answered with a solution"},
                   {"position_error_mean_m", "m", "mean position error of the solutions"},
                   {"position_error_max_m", "m", "largest position error of a solution"},
                   {"orientation_error_max_rad", "rad",
                    "largest orientation error of a solution"}}},
      [](const plugin::TruthStreams& t, const plugin::Parameters&) {
        return std::make_unique<InverseKinematicsEvaluator>(t["target"]);
      });
  registrar.add_evaluator(
      {.name = "collision",
       .description = "answers against the sampled ground truth, and FCL against Bullet on the "
                      "same states",
       .output_type = "robotperf_msgs/msg/CollisionResult",
       .truth_roles = {"truth", "state"},
       .metrics = {{"truth_agreement", "fraction", "answers equal to the sampled ground truth"},
                   {"fcl_bullet_agreement", "fraction", "states where FCL and Bullet agree"},
                   {"kernel_backends_agreement", "fraction",
                    "answers equal to both FCL and Bullet"},
                   {"colliding_fraction", "fraction", "states in collision (ground truth)"}}},
      [](const plugin::TruthStreams& t, const plugin::Parameters&) {
        return std::make_unique<CollisionEvaluator>(t["truth"], t["state"]);
      });
  registrar.add_evaluator(
      {.name = "plan_execution",
       .description = "plans re-checked with FCL and Bullet at 0.005 rad steps, limits, ends, "
                      "and execution tracking",
       .output_type = "robotperf_msgs/msg/PlanExecutionResult",
       .truth_roles = {"query"},
       .metrics = {{"success_rate", "fraction", "queries planned and executed"},
                   {"valid_fraction", "fraction",
                    "plans from start to goal, within the limits and collision-free (FCL and "
                    "Bullet, no padding) at every 0.005 rad"},
                   {"path_length_mean_rad", "rad", "mean joint-space path length"},
                   {"tracking_error_max_rad", "rad",
                    "largest |desired - actual| while executing"}}},
      [](const plugin::TruthStreams& t, const plugin::Parameters&) {
        return std::make_unique<PlanExecutionEvaluator>(t["query"]);
      });
}

}  // namespace robotperf::manipulation
