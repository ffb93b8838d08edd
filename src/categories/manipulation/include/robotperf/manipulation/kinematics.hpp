// Forward and inverse kinematics of a RobotModel's chain on orocos-kdl, as MoveIt's KDL and LMA
// kinematics plugins compute them.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <random>
#include <vector>

#include "robotperf/manipulation/robot_model.hpp"

namespace robotperf::manipulation {

// The tip pose by KDL::ChainFkSolverPos_recursive. Not thread-safe (keeps its buffers); solvers
// of one model may run in different threads (each has its own copy of the chain).
class ForwardKinematics {
 public:
  explicit ForwardKinematics(const RobotModel& model);
  ~ForwardKinematics();
  // Throws std::invalid_argument when KDL reports an error.
  Eigen::Isometry3d tip_pose(const double* q);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

enum class IkSolver {
  // Newton-Raphson with joint limits over KDL::ChainIkSolverVel_pinv, as ChainIkSolverPos_NR_JL
  // and MoveIt's KDL plugin iterate, with step halving and whole-turn wrapping into the limits.
  kNewtonRaphsonJL,
  kLevenbergMarquardt,  // KDL::ChainIkSolverPos_LMA (MoveIt's LMA plugin)
};

struct IkOptions {
  IkSolver solver = IkSolver::kNewtonRaphsonJL;
  unsigned max_iterations = 500;  // per attempt
  double eps = 1e-5;              // the solver's convergence tolerance
  double timeout_s = 0.005;       // all attempts together
  uint64_t seed = 0;              // random restarts
};

struct IkResult {
  bool success = false;
  std::vector<double> q;         // the solution (empty without success)
  unsigned attempts = 0;         // the first from the seed state, then random restarts
  double position_error = 0;     // m, of the solution's tip pose (when success)
  double orientation_error = 0;  // rad
};

// Position and orientation difference between two poses (m, rad).
void pose_error(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, double& position_m,
                double& orientation_rad);

// Solves for a joint state whose tip pose is the target: one attempt from the seed state, then
// attempts from uniformly random states within the joint limits until one converges within the
// limits or the timeout passes, as MoveIt's KDL plugin does. Not thread-safe; solvers of one
// model may run in different threads, as ForwardKinematics.
class InverseKinematics {
 public:
  InverseKinematics(const RobotModel& model, const IkOptions& options);
  ~InverseKinematics();
  IkResult solve(const Eigen::Isometry3d& target, const std::vector<double>& seed_state);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace robotperf::manipulation
