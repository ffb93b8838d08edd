// Joint-space motion planning (OMPL RRTConnect with a CollisionChecker as state validity), path
// simplification, time parameterisation within velocity and acceleration limits, and a simulated
// position-controlled arm that executes the trajectory.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "robotperf/manipulation/collision.hpp"
#include "robotperf/manipulation/robot_model.hpp"

namespace robotperf::manipulation {

using JointPath = std::vector<std::vector<double>>;

struct PlanOptions {
  double planning_time_s = 1.0;  // RRTConnect's budget (simplification gets what is left, >= 0.1 s)
  // Motion validation step as a fraction of the joint space's extent (MoveIt's
  // longest_valid_segment_fraction).
  double longest_valid_segment_fraction = 0.005;
  bool simplify = true;
  // OMPL's random numbers come from one generator per process whose seed can be set only before
  // OMPL makes its first random number generator: the first Planner of a process with a seed
  // other than 0 sets it (0: OMPL seeds from the clock). A later Planner asking for another seed
  // cannot change it (a warning says so). With the seed set, a process that plans the same
  // queries in the same order gets the same plans, as long as RRTConnect and simplification
  // finish within their time budgets.
  uint32_t seed = 0;
};

struct PlanResult {
  bool success = false;
  JointPath path;                 // start ... goal (simplified when asked)
  std::size_t raw_waypoints = 0;  // before simplification
  double planning_time_s = 0;     // RRTConnect
  double simplify_time_s = 0;
};

// Not thread-safe (one planner over one checker).
class Planner {
 public:
  Planner(const RobotModel& model, std::unique_ptr<CollisionChecker> checker,
          const PlanOptions& options);
  ~Planner();
  // Throws std::invalid_argument when start or goal has the wrong size.
  PlanResult plan(const std::vector<double>& start, const std::vector<double>& goal);
  CollisionChecker& checker();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Sum over segments of the Euclidean joint-space distance (rad).
double path_length(const JointPath& path);

// Every state on the path, interpolated linearly at most `step` rad apart (max-norm), is within
// the limits and collision-free by `checker`. `first_invalid` (when given) gets the bad state.
bool path_valid(const RobotModel& model, CollisionChecker& checker, const JointPath& path,
                double step, std::vector<double>* first_invalid = nullptr);

struct TrajectorySample {
  double time_s = 0;
  std::vector<double> position, velocity, acceleration;
};

// Time parameterisation: on each segment between waypoints all joints follow one trapezoidal
// velocity profile (at rest at every waypoint), as fast as the most limited joint allows:
// |velocity| <= scaling * max_velocity and |acceleration| <= scaling * max_acceleration of every
// joint. Sampled every `sample_period_s`, plus each waypoint exactly.
std::vector<TrajectorySample> time_parameterize(const JointPath& path,
                                                const std::vector<JointLimits>& limits,
                                                double sample_period_s,
                                                double velocity_scaling = 1.0,
                                                double acceleration_scaling = 1.0);

// The trajectory's position and velocity at time t (cubic Hermite between samples; held at the
// ends).
void interpolate(const std::vector<TrajectorySample>& trajectory, double t, double* position,
                 double* velocity);

// A simulated position-controlled arm: each control step the joints move towards the commanded
// position as a first-order lag with time constant `lag_s`.
struct ExecutionOptions {
  double control_rate_hz = 100;
  double lag_s = 0.01;
  double settle_s = 0.1;  // control steps after the trajectory's end
};

struct ExecutionStep {
  double time_s;
  std::vector<double> position, velocity;  // actual
};

struct ExecutionResult {
  std::size_t steps = 0;
  double max_tracking_error = 0;  // rad, max over steps and joints of |desired - actual|
  double final_error = 0;         // rad, at the end, against the last trajectory point
};

// Runs the simulation in simulated time (no sleeping) and calls `on_step` for every control step.
template <class OnStep>
ExecutionResult execute(const std::vector<TrajectorySample>& trajectory,
                        const ExecutionOptions& options, OnStep&& on_step);

}  // namespace robotperf::manipulation

#include "robotperf/manipulation/execution_impl.hpp"
