// Functional evaluators of the manipulation benchmarks (d1-d6). Answers are checked with
// computations independent of the kernel under test: FK and IK against the URDF's own transform
// chain (Eigen, not KDL), collision answers against the sampled ground truth and against both
// FCL and Bullet, plans by re-checking every interpolated state with FCL and Bullet without the
// planner's link padding and their timing by finite differences of their positions.
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

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

// The positions of a JointState in the model's order (in_model_order), or empty with `why` set
// when they do not fit.
std::vector<double> positions(const RobotModel& m, const msgs::JointState& s, std::string& why) {
  try {
    return in_model_order(m, s.name, s.position, "positions");
  } catch (const std::invalid_argument& e) {
    why = e.what();
    return {};
  }
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
    std::string why;
    const auto q = positions(m, out, why);
    if (q.empty()) {
      problem("a solution is not a state of the arm: " + why);
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
    std::string why;
    const auto q = positions(RobotModel::xarm6(), state, why);
    if (q.empty()) {
      problem("a dataset state is not a state of the arm: " + why);
      return;
    }
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

// A trajectory is judged by what its positions and times say, not by the figures reported with
// it: its joints' speeds between points (finite differences) against the velocity limits, its
// reported velocities against those speeds, and its path length summed from its positions. The
// tracking error is the executor's own figure (the evaluator does not see the arm's states).
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
    // The trajectory and the query in the model's joint order.
    const auto& names = out.trajectory.joint_names;
    manipulation::JointPath path, velocities, accelerations;
    std::vector<double> times;
    std::vector<double> start, goal;
    try {
      for (const auto& p : out.trajectory.points) {
        path.push_back(in_model_order(m, names, p.positions, "positions"));
        velocities.push_back(p.velocities.empty()
                                 ? std::vector<double>{}
                                 : in_model_order(m, names, p.velocities, "velocities"));
        accelerations.push_back(p.accelerations.empty()
                                    ? std::vector<double>{}
                                    : in_model_order(m, names, p.accelerations, "accelerations"));
        times.push_back(p.time_from_start.sec + p.time_from_start.nanosec * 1e-9);
      }
    } catch (const std::invalid_argument& e) {
      problem(std::string("a trajectory point is not a state of the arm: ") + e.what());
      return;
    }
    try {
      if (query.points.empty()) throw std::invalid_argument("it has no points");
      start = in_model_order(m, query.joint_names, query.points.front().positions, "positions");
      goal = in_model_order(m, query.joint_names, query.points.back().positions, "positions");
    } catch (const std::invalid_argument& e) {
      problem(std::string("a query is not a pair of states of the arm: ") + e.what());
      return;
    }
    auto close = [](const std::vector<double>& a, const std::vector<double>& b) {
      for (std::size_t j = 0; j < a.size(); ++j)
        if (std::abs(a[j] - b[j]) > 1e-6) return false;
      return true;
    };
    const bool ends = close(path.front(), start) && close(path.back(), goal);
    if (!ends) problem("a trajectory does not start at the query's start or end at its goal");
    const bool timing_ok = std::adjacent_find(times.begin(), times.end(), [](double a, double b) {
                             return !(b > a);
                           }) == times.end();
    if (!timing_ok) problem("a trajectory's times do not increase");
    bool limits_ok = true, velocities_ok = true;
    for (std::size_t k = 0; k < path.size(); ++k) {
      for (std::size_t j = 0; j < m.dof(); ++j) {
        const JointLimits& lim = m.limits()[j];
        if (!velocities[k].empty())
          limits_ok &= std::abs(velocities[k][j]) <= lim.max_velocity * (1 + 1e-9);
        if (!accelerations[k].empty())
          limits_ok &= std::abs(accelerations[k][j]) <= lim.max_acceleration * (1 + 1e-9);
        if (k == 0 || !timing_ok) continue;
        // Times have a resolution of 1 ns: an interval may be up to 1 ns longer than it reads.
        const double dt = times[k] - times[k - 1], dq = path[k][j] - path[k - 1][j];
        limits_ok &= std::abs(dq) <= lim.max_velocity * (1 + 1e-6) * (dt + 1e-9);
        if (velocities[k].empty() || velocities[k - 1].empty()) continue;
        const double v0 = velocities[k - 1][j], v1 = velocities[k][j];
        limits_ok &= std::abs(v1 - v0) <= lim.max_acceleration * (1 + 1e-6) * (dt + 1e-9);
        // With |acceleration| <= a, the mean velocity over an interval (dq / dt) is within a dt / 4
        // of the mean of its end velocities (the trapezoidal rule's error bound), whatever the
        // profile.
        velocities_ok &= std::abs(dq / dt - (v0 + v1) / 2) <=
                         lim.max_acceleration * dt / 4 + lim.max_velocity * (1e-6 + 1e-9 / dt);
      }
    }
    if (!limits_ok) problem("a trajectory exceeds the velocity or acceleration limits");
    if (!velocities_ok) problem("a trajectory's velocities do not match its positions and times");
    // Both backends without padding, finer than the planner's own motion checks.
    valid_ += ends && timing_ok && limits_ok && velocities_ok &&
              manipulation::path_valid(m, *fcl_, path, kRecheckStep) &&
              manipulation::path_valid(m, *bullet_, path, kRecheckStep);
    length_sum_ += manipulation::path_length(path);
    if (!(out.max_tracking_error >= 0) || !std::isfinite(out.max_tracking_error))
      problem("an execution result's tracking error is not a finite figure >= 0");
    else
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
       .description = "plans re-checked with FCL and Bullet at 0.005 rad steps, joint speeds "
                      "between points against the limits, reported velocities against them, "
                      "ends, and execution tracking",
       .output_type = "robotperf_msgs/msg/PlanExecutionResult",
       .truth_roles = {"query"},
       .metrics = {{"success_rate", "fraction", "queries planned and executed"},
                   {"valid_fraction", "fraction",
                    "plans from start to goal, within the limits (reported and between points), "
                    "velocities matching the positions, and collision-free (FCL and Bullet, no "
                    "padding) at every 0.005 rad"},
                   {"path_length_mean_rad", "rad",
                    "mean joint-space length of the trajectories' positions"},
                   {"tracking_error_max_rad", "rad",
                    "largest |desired - actual| while executing, as the executor reports it"}}},
      [](const plugin::TruthStreams& t, const plugin::Parameters&) {
        return std::make_unique<PlanExecutionEvaluator>(t["query"]);
      });
}

}  // namespace robotperf::manipulation
