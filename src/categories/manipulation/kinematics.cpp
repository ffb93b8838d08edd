#include "robotperf/manipulation/kinematics.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <kdl/chain.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainiksolverpos_lma.hpp>
#include <kdl/chainiksolvervel_pinv.hpp>
#include <kdl/jntarray.hpp>
#include <limits>
#include <stdexcept>

#include "kdl_frame.hpp"

namespace robotperf::manipulation {
namespace {}  // namespace

void pose_error(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, double& position_m,
                double& orientation_rad) {
  position_m = (a.translation() - b.translation()).norm();
  orientation_rad = Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle();
}

// Each solver owns a copy of the model's chain: KDL::Joint::pose caches its last angle and
// rotation in the joint (orocos_kinematics_dynamics issue #373), so solvers on one chain in two
// threads (two nodes of one process) read each other's rotations.
struct ForwardKinematics::Impl {
  explicit Impl(const RobotModel& m) : chain(m.chain()), solver(chain), q(chain.getNrOfJoints()) {}
  KDL::Chain chain;
  KDL::ChainFkSolverPos_recursive solver;
  KDL::JntArray q;
  KDL::Frame out;
};

ForwardKinematics::ForwardKinematics(const RobotModel& model)
    : impl_(std::make_unique<Impl>(model)) {}
ForwardKinematics::~ForwardKinematics() = default;

Eigen::Isometry3d ForwardKinematics::tip_pose(const double* q) {
  for (unsigned i = 0; i < impl_->q.rows(); ++i) impl_->q(i) = q[i];
  if (const int rc = impl_->solver.JntToCart(impl_->q, impl_->out); rc < 0) {
    throw std::invalid_argument(std::string("KDL forward kinematics failed: ") +
                                impl_->solver.strError(rc));
  }
  return to_eigen(impl_->out);
}

struct InverseKinematics::Impl {
  Impl(const RobotModel& m, const IkOptions& o)
      : model(m),
        options(o),
        chain(m.chain()),
        n(chain.getNrOfJoints()),
        q_min(n),
        q_max(n),
        fk(chain),
        vel(chain),
        rng(o.seed) {
    for (unsigned i = 0; i < n; ++i) {
      q_min(i) = m.limits()[i].lower;
      q_max(i) = m.limits()[i].upper;
    }
    if (o.solver == IkSolver::kLevenbergMarquardt) {
      lma = std::make_unique<KDL::ChainIkSolverPos_LMA>(chain, o.eps,
                                                        static_cast<int>(o.max_iterations));
    }
  }

  // Newton-Raphson with joint limits as KDL's ChainIkSolverPos_NR_JL iterates (FK, twist error,
  // pseudo-inverse step, keep within the limits), with two changes that decide whether it
  // converges within the budget (35 % of reachable targets without them, 99+ % with):
  // - a joint that steps past a limit is first brought back by a whole turn when that lands
  //   within the limits (the xArm's +-3.11 rad joints are nearly continuous: clamping parks the
  //   joint at the limit while the target angle is just across +-pi, and the attempt stalls);
  // - when a full step does not reduce the error, it is retried at half the length from the
  //   previous state (undamped steps far from the solution oscillate for all 500 iterations,
  //   about 1.5 ms, while a restart usually converges in 20). Once the step is down to 1/1000
  //   the attempt is stuck (singular or pushing against a limit) and a restart is the better use
  //   of the time, as in MoveIt's KDL plugin.
  // The deadline is checked every iteration so that no attempt overruns the timeout. Returns true
  // when the twist error is within eps on every component.
  bool newton_raphson_jl(const KDL::Frame& goal, KDL::JntArray& q,
                         std::chrono::steady_clock::time_point deadline) {
    double accepted_error = std::numeric_limits<double>::infinity();
    double step_scale = 1;
    for (unsigned it = 0; it < options.max_iterations; ++it) {
      fk.JntToCart(q, reached);
      const KDL::Twist error = KDL::diff(reached, goal);
      if (KDL::Equal(error, KDL::Twist::Zero(), options.eps)) return true;
      if (std::chrono::steady_clock::now() >= deadline) return false;
      const double error_norm = std::max(error.vel.Norm(), error.rot.Norm());
      if (error_norm < accepted_error) {
        accepted_error = error_norm;
        accepted = q;
        step_scale = 1;
        if (vel.CartToJnt(q, error, step) < 0) return false;
      } else {
        step_scale *= 0.5;
        if (step_scale < 1e-3) return false;
      }
      for (unsigned i = 0; i < n; ++i) q(i) = into_limits(i, accepted(i) + step_scale * step(i));
    }
    return false;
  }

  // The same angle by whole turns within [q_min, q_max] when there is one, else the nearer limit.
  double into_limits(unsigned i, double v) const {
    if (v >= q_min(i) && v <= q_max(i)) return v;
    double turned = std::fmod(v - q_min(i), 2 * M_PI);
    if (turned < 0) turned += 2 * M_PI;
    if (q_min(i) + turned <= q_max(i)) return q_min(i) + turned;
    return std::clamp(v, q_min(i), q_max(i));
  }

  // LMA ignores joint limits: bring revolute angles into range by whole turns where possible.
  bool fold_into_limits(KDL::JntArray& q) const {
    for (unsigned i = 0; i < n; ++i) {
      double v = q(i);
      while (v > q_max(i)) v -= 2 * M_PI;
      while (v < q_min(i)) v += 2 * M_PI;
      if (v > q_max(i)) return false;
      q(i) = v;
    }
    return true;
  }

  const RobotModel& model;
  IkOptions options;
  KDL::Chain chain;  // its own, as ForwardKinematics's
  unsigned n;
  KDL::JntArray q_min, q_max;
  KDL::ChainFkSolverPos_recursive fk;
  KDL::ChainIkSolverVel_pinv vel;
  KDL::Frame reached;
  KDL::JntArray step{n};
  KDL::JntArray accepted{n};  // the state with the lowest error so far in an attempt
  std::unique_ptr<KDL::ChainIkSolverPos_LMA> lma;
  std::mt19937_64 rng;
};

InverseKinematics::InverseKinematics(const RobotModel& model, const IkOptions& options)
    : impl_(std::make_unique<Impl>(model, options)) {
  if (options.max_iterations == 0 || !(options.eps > 0) || !(options.timeout_s > 0))
    throw std::invalid_argument("IK needs max_iterations > 0, eps > 0 and timeout > 0");
}
InverseKinematics::~InverseKinematics() = default;

IkResult InverseKinematics::solve(const Eigen::Isometry3d& target,
                                  const std::vector<double>& seed_state) {
  Impl& s = *impl_;
  if (seed_state.size() != s.n)
    throw std::invalid_argument("IK seed state has " + std::to_string(seed_state.size()) +
                                " joints, the chain " + std::to_string(s.n));
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                            std::chrono::duration<double>(s.options.timeout_s));
  const KDL::Frame goal = to_kdl(target);
  KDL::JntArray start(s.n), solution(s.n);
  for (unsigned i = 0; i < s.n; ++i) start(i) = seed_state[i];
  IkResult result;
  do {
    ++result.attempts;
    bool converged;
    if (s.lma) {
      converged = s.lma->CartToJnt(start, goal, solution) >= 0 && s.fold_into_limits(solution);
    } else {
      solution = start;
      converged = s.newton_raphson_jl(goal, solution, deadline);
    }
    if (converged) {
      KDL::Frame reached;
      s.fk.JntToCart(solution, reached);
      result.success = true;
      result.q.assign(solution.data.data(), solution.data.data() + s.n);
      pose_error(to_eigen(reached), target, result.position_error, result.orientation_error);
      return result;
    }
    for (unsigned i = 0; i < s.n; ++i)
      start(i) = std::uniform_real_distribution<double>(s.q_min(i), s.q_max(i))(s.rng);
  } while (std::chrono::steady_clock::now() < deadline);
  return result;
}

}  // namespace robotperf::manipulation
