#include "robotperf/manipulation/planning.hpp"

#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/geometric/SimpleSetup.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>
#include <ompl/util/Console.h>
#include <ompl/util/RandomNumbers.h>

#include <chrono>
#include <cmath>
#include <iostream>
#include <mutex>
#include <optional>
#include <stdexcept>

namespace robotperf::manipulation {

namespace ob = ompl::base;
namespace og = ompl::geometric;

namespace {

// Before the SimpleSetup below makes OMPL's first generators; see PlanOptions::seed.
void seed_ompl(uint32_t seed) {
  static std::mutex mutex;
  static std::optional<uint32_t> process_seed;
  if (seed == 0) return;
  const std::lock_guard lock(mutex);
  if (!process_seed) {
    ompl::RNG::setSeed(seed);
    process_seed = seed;
  } else if (*process_seed != seed) {
    std::cerr << "warning: OMPL's random seed is per process and already " << *process_seed
              << ": the planner asking for " << seed << " plans with that\n";
  }
}

}  // namespace

struct Planner::Impl {
  Impl(const RobotModel& m, std::unique_ptr<CollisionChecker> c, const PlanOptions& o)
      : model(m), checker(std::move(c)), options(o) {
    // OMPL logs every planning request at INFO; keep warnings and errors only.
    static std::once_flag quiet;
    std::call_once(quiet, [] { ompl::msg::setLogLevel(ompl::msg::LOG_WARN); });
    seed_ompl(o.seed);
    const unsigned n = static_cast<unsigned>(m.dof());
    auto space = std::make_shared<ob::RealVectorStateSpace>(n);
    ob::RealVectorBounds bounds(n);
    for (unsigned i = 0; i < n; ++i) {
      bounds.setLow(i, m.limits()[i].lower);
      bounds.setHigh(i, m.limits()[i].upper);
    }
    space->setBounds(bounds);
    space->setLongestValidSegmentFraction(o.longest_valid_segment_fraction);
    setup = std::make_unique<og::SimpleSetup>(space);
    setup->setStateValidityChecker([this](const ob::State* s) {
      const double* q = s->as<ob::RealVectorStateSpace::StateType>()->values;
      return model.within_limits(q) && !checker->check(q).in_collision;
    });
    setup->setPlanner(std::make_shared<og::RRTConnect>(setup->getSpaceInformation()));
    setup->setup();
  }

  const RobotModel& model;
  std::unique_ptr<CollisionChecker> checker;
  PlanOptions options;
  std::unique_ptr<og::SimpleSetup> setup;
};

Planner::Planner(const RobotModel& model, std::unique_ptr<CollisionChecker> checker,
                 const PlanOptions& options)
    : impl_(std::make_unique<Impl>(model, std::move(checker), options)) {
  if (!(options.planning_time_s > 0) || !(options.longest_valid_segment_fraction > 0))
    throw std::invalid_argument("planning needs planning_time > 0 and a segment fraction > 0");
}
Planner::~Planner() = default;
CollisionChecker& Planner::checker() {
  return *impl_->checker;
}

PlanResult Planner::plan(const std::vector<double>& start, const std::vector<double>& goal) {
  Impl& s = *impl_;
  const std::size_t n = s.model.dof();
  if (start.size() != n || goal.size() != n)
    throw std::invalid_argument("a planning query needs " + std::to_string(n) + " joint positions");
  auto space = s.setup->getStateSpace();
  ob::ScopedState<> from(space), to(space);
  for (std::size_t i = 0; i < n; ++i) {
    from[i] = start[i];
    to[i] = goal[i];
  }
  s.setup->clear();  // a fresh tree per query, as MoveIt plans each request anew
  s.setup->setStartAndGoalStates(from, to);
  PlanResult r;
  const auto t0 = std::chrono::steady_clock::now();
  const ob::PlannerStatus status = s.setup->solve(s.options.planning_time_s);
  const auto t1 = std::chrono::steady_clock::now();
  r.planning_time_s = std::chrono::duration<double>(t1 - t0).count();
  if (status != ob::PlannerStatus::EXACT_SOLUTION) return r;
  r.raw_waypoints = s.setup->getSolutionPath().getStateCount();
  if (s.options.simplify) {
    s.setup->simplifySolution(std::max(0.1, s.options.planning_time_s - r.planning_time_s));
    r.simplify_time_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
  }
  const og::PathGeometric& path = s.setup->getSolutionPath();
  for (std::size_t k = 0; k < path.getStateCount(); ++k) {
    const double* q =
        path.getState(static_cast<unsigned>(k))->as<ob::RealVectorStateSpace::StateType>()->values;
    r.path.emplace_back(q, q + n);
  }
  r.success = true;
  return r;
}

double path_length(const JointPath& path) {
  double length = 0;
  for (std::size_t k = 1; k < path.size(); ++k) {
    double sq = 0;
    for (std::size_t j = 0; j < path[k].size(); ++j)
      sq += (path[k][j] - path[k - 1][j]) * (path[k][j] - path[k - 1][j]);
    length += std::sqrt(sq);
  }
  return length;
}

bool path_valid(const RobotModel& model, CollisionChecker& checker, const JointPath& path,
                double step, std::vector<double>* first_invalid) {
  std::vector<double> q;
  auto valid = [&](const std::vector<double>& state) {
    if (state.size() == model.dof() && model.within_limits(state.data(), 1e-9) &&
        !checker.check(state.data()).in_collision)
      return true;
    if (first_invalid) *first_invalid = state;
    return false;
  };
  if (path.empty()) return false;
  if (!valid(path.front())) return false;
  for (std::size_t k = 1; k < path.size(); ++k) {
    if (path[k].size() != model.dof()) return valid(path[k]);
    double span = 0;
    for (std::size_t j = 0; j < path[k].size(); ++j)
      span = std::max(span, std::abs(path[k][j] - path[k - 1][j]));
    const int steps = std::max(1, static_cast<int>(std::ceil(span / step)));
    q.resize(path[k].size());
    for (int i = 1; i <= steps; ++i) {
      const double f = static_cast<double>(i) / steps;
      for (std::size_t j = 0; j < q.size(); ++j)
        q[j] = path[k - 1][j] + f * (path[k][j] - path[k - 1][j]);
      if (!valid(q)) return false;
    }
  }
  return true;
}

std::vector<TrajectorySample> time_parameterize(const JointPath& path,
                                                const std::vector<JointLimits>& limits,
                                                double sample_period_s, double velocity_scaling,
                                                double acceleration_scaling) {
  if (!(sample_period_s > 0) || !(velocity_scaling > 0) || !(acceleration_scaling > 0))
    throw std::invalid_argument("time parameterisation needs a positive period and scalings");
  std::vector<TrajectorySample> out;
  if (path.empty()) return out;
  const std::size_t n = path.front().size();
  if (limits.size() != n) throw std::invalid_argument("joint limits do not match the path");
  out.push_back({0.0, path.front(), std::vector<double>(n, 0.0), std::vector<double>(n, 0.0)});
  double t0 = 0;
  for (std::size_t k = 1; k < path.size(); ++k) {
    // The profile s(t) goes 0 -> 1; joint j moves delta_j * s(t). Its normalised limits are the
    // tightest over the joints that move.
    std::vector<double> delta(n);
    double v = INFINITY, a = INFINITY;
    for (std::size_t j = 0; j < n; ++j) {
      delta[j] = path[k][j] - path[k - 1][j];
      if (std::abs(delta[j]) < 1e-12) continue;
      v = std::min(v, velocity_scaling * limits[j].max_velocity / std::abs(delta[j]));
      a = std::min(a, acceleration_scaling * limits[j].max_acceleration / std::abs(delta[j]));
    }
    if (!std::isfinite(v)) continue;  // a repeated waypoint
    // Trapezoid over distance 1, or a triangle when the peak velocity is never reached.
    double ramp = v / a;
    double cruise = 1.0 / v - ramp;
    if (cruise < 0) {
      ramp = std::sqrt(1.0 / a);
      cruise = 0;
      v = a * ramp;
    }
    const double duration = 2 * ramp + cruise;
    auto profile = [&](double t, double& s, double& sd, double& sdd) {
      if (t < ramp) {
        s = 0.5 * a * t * t, sd = a * t, sdd = a;
      } else if (t < ramp + cruise) {
        s = 0.5 * a * ramp * ramp + v * (t - ramp), sd = v, sdd = 0;
      } else {
        const double r = std::max(0.0, duration - t);
        s = 1.0 - 0.5 * a * r * r, sd = a * r, sdd = r > 0 ? -a : 0;
      }
    };
    const int samples = std::max(1, static_cast<int>(std::ceil(duration / sample_period_s)));
    for (int i = 1; i <= samples; ++i) {
      const double t = i == samples ? duration : i * sample_period_s;
      double s, sd, sdd;
      profile(t, s, sd, sdd);
      TrajectorySample p{t0 + t, std::vector<double>(n), std::vector<double>(n),
                         std::vector<double>(n)};
      for (std::size_t j = 0; j < n; ++j) {
        p.position[j] = i == samples ? path[k][j] : path[k - 1][j] + delta[j] * s;
        p.velocity[j] = delta[j] * sd;
        p.acceleration[j] = delta[j] * sdd;
      }
      out.push_back(std::move(p));
    }
    t0 += duration;
  }
  return out;
}

void interpolate(const std::vector<TrajectorySample>& trajectory, double t, double* position,
                 double* velocity) {
  const std::size_t n = trajectory.front().position.size();
  if (t <= trajectory.front().time_s || trajectory.size() == 1) {
    for (std::size_t j = 0; j < n; ++j)
      position[j] = trajectory.front().position[j], velocity[j] = 0;
    return;
  }
  if (t >= trajectory.back().time_s) {
    for (std::size_t j = 0; j < n; ++j)
      position[j] = trajectory.back().position[j], velocity[j] = 0;
    return;
  }
  const auto after =
      std::upper_bound(trajectory.begin(), trajectory.end(), t,
                       [](double time, const TrajectorySample& s) { return time < s.time_s; });
  const TrajectorySample& p1 = *after;
  const TrajectorySample& p0 = *(after - 1);
  const double h = p1.time_s - p0.time_s;
  const double u = h > 0 ? (t - p0.time_s) / h : 1.0;
  const double h00 = 2 * u * u * u - 3 * u * u + 1, h10 = u * u * u - 2 * u * u + u;
  const double h01 = -2 * u * u * u + 3 * u * u, h11 = u * u * u - u * u;
  const double d00 = 6 * u * u - 6 * u, d10 = 3 * u * u - 4 * u + 1;
  const double d01 = -6 * u * u + 6 * u, d11 = 3 * u * u - 2 * u;
  for (std::size_t j = 0; j < n; ++j) {
    position[j] = h00 * p0.position[j] + h10 * h * p0.velocity[j] + h01 * p1.position[j] +
                  h11 * h * p1.velocity[j];
    velocity[j] = h > 0 ? (d00 * p0.position[j] + d01 * p1.position[j]) / h + d10 * p0.velocity[j] +
                              d11 * p1.velocity[j]
                        : 0;
  }
}

}  // namespace robotperf::manipulation
