// The template part of planning.hpp.
#pragma once

#include <algorithm>
#include <cmath>

namespace robotperf::manipulation {

template <class OnStep>
ExecutionResult execute(const std::vector<TrajectorySample>& trajectory,
                        const ExecutionOptions& options, OnStep&& on_step) {
  ExecutionResult r;
  if (trajectory.empty()) return r;
  const std::size_t n = trajectory.front().position.size();
  const double dt = 1.0 / options.control_rate_hz;
  const double gain = 1.0 - std::exp(-dt / options.lag_s);
  const double end = trajectory.back().time_s + options.settle_s;
  ExecutionStep step{0, trajectory.front().position, std::vector<double>(n, 0.0)};
  std::vector<double> desired(n), desired_velocity(n);
  for (std::size_t k = 0;; ++k) {
    step.time_s = static_cast<double>(k) * dt;
    if (step.time_s > end + 1e-12) break;
    interpolate(trajectory, step.time_s, desired.data(), desired_velocity.data());
    for (std::size_t j = 0; j < n; ++j)
      r.max_tracking_error =
          std::max(r.max_tracking_error, std::abs(desired[j] - step.position[j]));
    on_step(static_cast<const ExecutionStep&>(step));
    ++r.steps;
    for (std::size_t j = 0; j < n; ++j) {
      const double move = gain * (desired[j] - step.position[j]);
      step.position[j] += move;
      step.velocity[j] = move / dt;
    }
  }
  for (std::size_t j = 0; j < n; ++j)
    r.final_error =
        std::max(r.final_error, std::abs(trajectory.back().position[j] - step.position[j]));
  return r;
}

}  // namespace robotperf::manipulation
