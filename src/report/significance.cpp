#include "robotperf/report/significance.hpp"

#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>

namespace robotperf::report {
namespace {

// Continued fraction of the incomplete beta function (modified Lentz's method), valid for
// x < (a + 1) / (a + b + 2).
double beta_continued_fraction(double x, double a, double b) {
  constexpr double kTiny = 1e-300;
  constexpr double kEpsilon = 1e-15;
  double c = 1.0;
  double d = 1.0 - (a + b) * x / (a + 1.0);
  if (std::fabs(d) < kTiny) d = kTiny;
  d = 1.0 / d;
  double h = d;
  for (int m = 1; m <= 1000; ++m) {
    const double m2 = 2.0 * m;
    // Even step.
    double coefficient = m * (b - m) * x / ((a + m2 - 1.0) * (a + m2));
    d = 1.0 + coefficient * d;
    c = 1.0 + coefficient / c;
    if (std::fabs(d) < kTiny) d = kTiny;
    if (std::fabs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    h *= d * c;
    // Odd step.
    coefficient = -(a + m) * (a + b + m) * x / ((a + m2) * (a + m2 + 1.0));
    d = 1.0 + coefficient * d;
    c = 1.0 + coefficient / c;
    if (std::fabs(d) < kTiny) d = kTiny;
    if (std::fabs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    const double delta = d * c;
    h *= delta;
    if (std::fabs(delta - 1.0) < kEpsilon) break;
  }
  return h;
}

}  // namespace

double regularized_incomplete_beta(double x, double a, double b) {
  if (!(a > 0) || !(b > 0) || x < 0 || x > 1)
    throw std::invalid_argument("incomplete beta: needs 0 <= x <= 1 and a, b > 0");
  if (x == 0 || x == 1) return x;
  const double log_front =
      std::lgamma(a + b) - std::lgamma(a) - std::lgamma(b) + a * std::log(x) + b * std::log1p(-x);
  const double front = std::exp(log_front);
  // Use the symmetry I_x(a, b) = 1 - I_{1-x}(b, a) where the fraction converges faster.
  if (x < (a + 1.0) / (a + b + 2.0)) return front * beta_continued_fraction(x, a, b) / a;
  return 1.0 - front * beta_continued_fraction(1.0 - x, b, a) / b;
}

double student_t_two_sided_p(double t, double dof) {
  if (std::isnan(t) || !(dof > 0)) return std::numeric_limits<double>::quiet_NaN();
  if (std::isinf(t)) return 0.0;
  return regularized_incomplete_beta(dof / (dof + t * t), dof / 2.0, 0.5);
}

Welch welch_test(double mean_a, double stddev_a, std::size_t n_a, double mean_b, double stddev_b,
                 std::size_t n_b) {
  if (n_a < 2 || n_b < 2) throw std::invalid_argument("Welch test: needs >= 2 values per side");
  const double va = stddev_a * stddev_a / static_cast<double>(n_a);
  const double vb = stddev_b * stddev_b / static_cast<double>(n_b);
  Welch w;
  if (va + vb == 0) {
    w.t = mean_a == mean_b ? 0 : std::numeric_limits<double>::infinity();
    w.degrees_of_freedom = static_cast<double>(n_a + n_b - 2);
    w.p_value = mean_a == mean_b ? 1.0 : 0.0;
    return w;
  }
  w.t = (mean_a - mean_b) / std::sqrt(va + vb);
  w.degrees_of_freedom =
      (va + vb) * (va + vb) /
      (va * va / static_cast<double>(n_a - 1) + vb * vb / static_cast<double>(n_b - 1));
  w.p_value = student_t_two_sided_p(w.t, w.degrees_of_freedom);
  return w;
}

Welch welch_test(std::span<const double> a, std::span<const double> b) {
  auto mean_sd = [](std::span<const double> x) {
    const double n = static_cast<double>(x.size());
    const double mean = std::accumulate(x.begin(), x.end(), 0.0) / n;
    double ss = 0;
    for (double v : x) ss += (v - mean) * (v - mean);
    return std::pair{mean, std::sqrt(ss / (n - 1))};
  };
  if (a.size() < 2 || b.size() < 2)
    throw std::invalid_argument("Welch test: needs >= 2 values per side");
  const auto [ma, sa] = mean_sd(a);
  const auto [mb, sb] = mean_sd(b);
  return welch_test(ma, sa, a.size(), mb, sb, b.size());
}

}  // namespace robotperf::report
