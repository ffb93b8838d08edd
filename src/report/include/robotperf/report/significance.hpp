// Is the difference between two sets of measurements larger than their spread explains?
#pragma once

#include <cstddef>
#include <span>
#include <string>

namespace robotperf::report {

struct Welch {
  double t = 0;
  double degrees_of_freedom = 0;
  double p_value = 1;  // two-sided
};

// Welch's unequal-variance t-test from summary figures (mean, sample standard deviation, count;
// each count >= 2). Two samples without spread give p = 0 when their means differ, else 1.
Welch welch_test(double mean_a, double stddev_a, std::size_t n_a, double mean_b, double stddev_b,
                 std::size_t n_b);

// The same from raw samples (each with >= 2 values).
Welch welch_test(std::span<const double> a, std::span<const double> b);

// Two-sided p-value of Student's t distribution with `dof` degrees of freedom.
double student_t_two_sided_p(double t, double dof);

// Regularized incomplete beta function I_x(a, b), for 0 <= x <= 1, a, b > 0.
double regularized_incomplete_beta(double x, double a, double b);

}  // namespace robotperf::report
