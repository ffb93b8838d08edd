// Summary statistics of a set of samples (latencies, periods, ...), computed from all samples as
// docs/design.md §3.6 requires.
#pragma once

#include <cstddef>
#include <limits>
#include <nlohmann/json.hpp>
#include <span>
#include <string_view>
#include <vector>

namespace robotperf::metrics {

// Statistics of a sample set, in the unit of the samples.
//
// Definitions (n = count, x(1) <= ... <= x(n) the sorted samples):
//   mean    arithmetic mean, summed with compensated (Neumaier) summation.
//   rms     sqrt(mean of x^2).
//   stddev  SAMPLE standard deviation, sqrt(sum((x - mean)^2) / (n - 1)); NaN when n == 1.
//   pXX     quantile q = XX/100 by linear interpolation between closest ranks ("type 7" of Hyndman
//           & Fan, the default of R, NumPy and Excel's PERCENTILE.INC):
//           h = (n - 1) q, value = x(floor(h)+1) + (h - floor(h)) (x(floor(h)+2) - x(floor(h)+1)).
//           Example: samples 1..10 give p50 = 5.5, p90 = 9.1, p99 = 9.91.
//   p999    the 99.9th percentile.
//   pXX_ci  a distribution-free 95 % confidence interval of the percentile, from the order
//           statistics: [x(l), x(u)] with l and u the binomial quantiles of Bin(n, q) that leave
//           at most 2.5 % below and above. Its upper end is NaN when the samples are too few to
//           bound it (u would be beyond x(n): p99 needs 368 samples, p99.9 3688), its lower end
//           likewise below x(1).
// With no samples, count is 0 and every other field is NaN (there is no such value, and 0 would
// read as a measurement).
struct PercentileInterval {
  double lower = std::numeric_limits<double>::quiet_NaN();
  double upper = std::numeric_limits<double>::quiet_NaN();
};

struct SampleStats {
  static constexpr double kNoValue = std::numeric_limits<double>::quiet_NaN();

  std::size_t count = 0;
  double min = kNoValue;
  double mean = kNoValue;
  double rms = kNoValue;
  double stddev = kNoValue;
  double p50 = kNoValue;
  double p90 = kNoValue;
  double p99 = kNoValue;
  double p999 = kNoValue;
  double max = kNoValue;
  PercentileInterval p50_ci, p90_ci, p99_ci, p999_ci;
};

// The confidence of every PercentileInterval.
inline constexpr double kPercentileConfidence = 0.95;

// The 1-based ranks l and u of the order statistics that bound quantile q of n samples with the
// given two-sided confidence; 0 where no sample can (l below x(1), u beyond x(n)).
struct OrderStatisticRanks {
  std::size_t lower = 0;
  std::size_t upper = 0;
};
OrderStatisticRanks percentile_interval_ranks(std::size_t n, double q,
                                              double confidence = kPercentileConfidence);

// The fewest samples whose largest bounds quantile q from above with the given confidence.
std::size_t samples_for_upper_bound(double q, double confidence = kPercentileConfidence);

// Sorts samples ascending, as std::sort does, in linear time for large spans (a radix sort on the
// values' bits; a trace's analysis sorts tens of millions). -0 comes before +0; NaNs, which
// compute_stats refuses, end up first or last by their sign bit. `scratch`, when at least as
// long as `samples`, is used as the second buffer (its contents are overwritten); otherwise one
// is allocated.
void sort_samples(std::span<double> samples, std::span<double> scratch = {});

// Computes all statistics with one sort of a copy of `samples`: O(n) (sort_samples), about 10 ms
// for 10^6 samples. Throws std::invalid_argument if a sample is NaN or infinite.
SampleStats compute_stats(std::span<const double> samples);
// The same of samples already sorted ascending (a caller with millions of samples sorts its own
// buffer in place instead of having them copied). Throws std::invalid_argument if a sample is NaN
// or infinite.
SampleStats compute_stats_of_sorted(std::span<const double> sorted);

// Type-7 quantile (see SampleStats) of samples already sorted ascending; q in [0, 1].
// Returns NaN for an empty span. Throws std::invalid_argument if q is outside [0, 1].
double quantile_of_sorted(std::span<const double> sorted_samples, double q);
// The type-7 median (for an even count, the mean of the middle two) of samples in any order;
// NaN for none. NaN samples have no order: the caller removes them first.
double median(std::vector<double> samples);

// JSON object {"count", "min", "mean", "rms", "stddev", "p50", "p90", "p99", "p999", "max",
// "p50_ci95", ..., "p999_ci95"} (the intervals as [lower, upper]) with every value except count
// multiplied by `scale` (e.g. 1e-6 to report nanosecond samples in milliseconds), plus "unit":
// `unit` when `unit` is not empty. A NaN value becomes JSON null.
nlohmann::json to_json(const SampleStats& stats, double scale = 1.0, std::string_view unit = {});

}  // namespace robotperf::metrics
