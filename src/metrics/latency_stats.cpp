#include "robotperf/metrics/latency_stats.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace robotperf::metrics {
namespace {

// Neumaier's variant of Kahan summation: the rounding error of each addition is carried
// separately, so the sum of 10^6 values keeps nearly full double precision.
class CompensatedSum {
 public:
  void add(double value) {
    const double next = sum_ + value;
    if (std::fabs(sum_) >= std::fabs(value)) {
      compensation_ += (sum_ - next) + value;
    } else {
      compensation_ += (value - next) + sum_;
    }
    sum_ = next;
  }
  double value() const { return sum_ + compensation_; }

 private:
  double sum_ = 0.0;
  double compensation_ = 0.0;
};

nlohmann::json scaled_or_null(double value, double scale) {
  const double scaled = value * scale;
  if (std::isnan(scaled)) return nullptr;
  return scaled;
}

}  // namespace

OrderStatisticRanks percentile_interval_ranks(std::size_t n, double q, double confidence) {
  if (!(q > 0.0 && q < 1.0) || !(confidence > 0.0 && confidence < 1.0))
    throw std::invalid_argument("percentile_interval_ranks: q and confidence must be in (0, 1)");
  OrderStatisticRanks ranks;
  if (n == 0) return ranks;
  // B ~ Bin(n, q), the number of samples at or below the true quantile. [x(l), x(u)] covers it
  // when l <= B < u, so l is the largest rank with P(B <= l - 1) <= tail and u the smallest with
  // P(B <= u - 1) >= 1 - tail.
  const double tail = (1.0 - confidence) / 2.0;
  const double nd = static_cast<double>(n);
  // Beyond 12 standard deviations from the mean the binomial's mass is far below any tail used.
  const double sd = std::sqrt(nd * q * (1.0 - q));
  const double from = std::max(0.0, std::floor(nd * q - 12.0 * sd - 2.0));
  const double to = std::min(nd, std::ceil(nd * q + 12.0 * sd + 2.0));
  const double log_n_factorial = std::lgamma(nd + 1.0);
  double cdf = 0.0;  // P(B <= k)
  for (auto k = static_cast<std::size_t>(from); k <= static_cast<std::size_t>(to); ++k) {
    const double kd = static_cast<double>(k);
    cdf += std::exp(log_n_factorial - std::lgamma(kd + 1.0) - std::lgamma(nd - kd + 1.0) +
                    kd * std::log(q) + (nd - kd) * std::log1p(-q));
    // Rank j = k + 1 has P(B <= j - 1) = cdf.
    if (cdf <= tail) ranks.lower = k + 1;
    if (cdf >= 1.0 - tail && ranks.upper == 0 && k + 1 <= n) ranks.upper = k + 1;
  }
  return ranks;
}

std::size_t samples_for_upper_bound(double q, double confidence) {
  // x(n) bounds the quantile from above once P(B <= n - 1) = 1 - q^n >= 1 - tail.
  const double tail = (1.0 - confidence) / 2.0;
  return static_cast<std::size_t>(std::ceil(std::log(tail) / std::log(q)));
}

double quantile_of_sorted(std::span<const double> sorted_samples, double q) {
  if (!(q >= 0.0 && q <= 1.0)) {
    throw std::invalid_argument("quantile must be in [0, 1], got " + std::to_string(q));
  }
  if (sorted_samples.empty()) return SampleStats::kNoValue;
  const double rank = q * static_cast<double>(sorted_samples.size() - 1);
  const auto lower = static_cast<std::size_t>(std::floor(rank));
  if (lower + 1 >= sorted_samples.size()) return sorted_samples.back();
  const double fraction = rank - static_cast<double>(lower);
  const double below = sorted_samples[lower];
  const double above = sorted_samples[lower + 1];
  return below + fraction * (above - below);
}

double median(std::vector<double> samples) {
  std::ranges::sort(samples);
  return quantile_of_sorted(samples, 0.5);
}

namespace {

void require_finite(std::span<const double> samples) {
  if (!std::all_of(samples.begin(), samples.end(), [](double x) { return std::isfinite(x); })) {
    throw std::invalid_argument("compute_stats: samples must be finite (found NaN or infinity)");
  }
}

// The statistics of finite samples sorted ascending.
SampleStats stats_of_sorted(std::span<const double> sorted) {
  SampleStats stats;
  stats.count = sorted.size();
  if (sorted.empty()) return stats;

  const auto n = static_cast<double>(sorted.size());
  CompensatedSum sum;
  CompensatedSum sum_of_squares;
  for (const double x : sorted) {
    sum.add(x);
    sum_of_squares.add(x * x);
  }
  stats.min = sorted.front();
  stats.max = sorted.back();
  // Rounding can put the mean of equal samples one ulp outside [min, max]; clamping keeps the
  // ordering a reader relies on.
  stats.mean = std::clamp(sum.value() / n, stats.min, stats.max);
  stats.rms = std::sqrt(sum_of_squares.value() / n);

  // Two-pass variance: subtracting the mean first avoids the cancellation of E[x^2] - E[x]^2 when
  // the spread is small compared with the values (typical of latencies).
  if (sorted.size() > 1) {
    CompensatedSum squared_deviations;
    for (const double x : sorted) {
      const double deviation = x - stats.mean;
      squared_deviations.add(deviation * deviation);
    }
    stats.stddev = std::sqrt(squared_deviations.value() / (n - 1.0));
  }

  stats.p50 = quantile_of_sorted(sorted, 0.50);
  stats.p90 = quantile_of_sorted(sorted, 0.90);
  stats.p99 = quantile_of_sorted(sorted, 0.99);
  stats.p999 = quantile_of_sorted(sorted, 0.999);
  auto interval = [&](double q) {
    const OrderStatisticRanks ranks = percentile_interval_ranks(sorted.size(), q);
    PercentileInterval ci;
    if (ranks.lower > 0) ci.lower = sorted[ranks.lower - 1];
    if (ranks.upper > 0) ci.upper = sorted[ranks.upper - 1];
    return ci;
  };
  stats.p50_ci = interval(0.50);
  stats.p90_ci = interval(0.90);
  stats.p99_ci = interval(0.99);
  stats.p999_ci = interval(0.999);
  return stats;
}

}  // namespace

void sort_samples(std::span<double> samples, std::span<double> scratch) {
  const std::size_t n = samples.size();
  // Below this a comparison sort is as fast, and needs no second buffer.
  constexpr std::size_t kRadixFrom = 2048;
  if (n < kRadixFrom) {
    std::sort(samples.begin(), samples.end());
    return;
  }
  std::vector<double> own;
  if (scratch.size() < n) {
    own.resize(n);
    scratch = own;
  }
  // A double's bits as an unsigned key of the same order: negatives have every bit flipped (a
  // larger magnitude is a smaller value), the others only their sign bit. Keys are kept in the
  // two buffers' bits.
  auto key = [](double x) {
    const auto bits = std::bit_cast<uint64_t>(x);
    return (bits >> 63) != 0 ? ~bits : bits | (uint64_t{1} << 63);
  };
  auto value = [](uint64_t k) {
    return std::bit_cast<double>((k >> 63) != 0 ? k & ~(uint64_t{1} << 63) : ~k);
  };
  // Least significant digit first, 11 bits a pass. Latencies are whole nanoseconds well below
  // 2^53, so most low mantissa digits are the same in every sample: those passes are skipped.
  constexpr unsigned kBits = 11, kPasses = (64 + kBits - 1) / kBits;
  constexpr std::size_t kBuckets = std::size_t{1} << kBits;
  std::vector<std::array<std::size_t, kBuckets>> counts(kPasses);
  for (std::size_t i = 0; i < n; ++i) {
    const uint64_t k = key(samples[i]);
    samples[i] = std::bit_cast<double>(k);
    for (unsigned p = 0; p < kPasses; ++p) ++counts[p][(k >> (p * kBits)) & (kBuckets - 1)];
  }
  double* from = samples.data();
  double* to = scratch.data();
  for (unsigned p = 0; p < kPasses; ++p) {
    auto& count = counts[p];
    if (std::find(count.begin(), count.end(), n) != count.end()) continue;  // one digit for all
    std::size_t start = 0;
    for (auto& c : count) start += std::exchange(c, start);
    for (std::size_t i = 0; i < n; ++i) {
      const auto k = std::bit_cast<uint64_t>(from[i]);
      to[count[(k >> (p * kBits)) & (kBuckets - 1)]++] = from[i];
    }
    std::swap(from, to);
  }
  for (std::size_t i = 0; i < n; ++i) samples[i] = value(std::bit_cast<uint64_t>(from[i]));
}

SampleStats compute_stats(std::span<const double> samples) {
  // Checked before sorting: NaN breaks the sort's ordering.
  require_finite(samples);
  std::vector<double> sorted(samples.begin(), samples.end());
  sort_samples(sorted);
  return stats_of_sorted(sorted);
}

SampleStats compute_stats_of_sorted(std::span<const double> sorted) {
  require_finite(sorted);
  return stats_of_sorted(sorted);
}

nlohmann::json to_json(const SampleStats& stats, double scale, std::string_view unit) {
  nlohmann::json json = {
      {"count", stats.count},
      {"min", scaled_or_null(stats.min, scale)},
      {"mean", scaled_or_null(stats.mean, scale)},
      {"rms", scaled_or_null(stats.rms, scale)},
      {"stddev", scaled_or_null(stats.stddev, scale)},
      {"p50", scaled_or_null(stats.p50, scale)},
      {"p90", scaled_or_null(stats.p90, scale)},
      {"p99", scaled_or_null(stats.p99, scale)},
      {"p999", scaled_or_null(stats.p999, scale)},
      {"max", scaled_or_null(stats.max, scale)},
  };
  for (const auto& [name, ci] : {std::pair{"p50_ci95", stats.p50_ci},
                                 {"p90_ci95", stats.p90_ci},
                                 {"p99_ci95", stats.p99_ci},
                                 {"p999_ci95", stats.p999_ci}}) {
    json[name] = {scaled_or_null(ci.lower, scale), scaled_or_null(ci.upper, scale)};
  }
  if (!unit.empty()) json["unit"] = std::string(unit);
  return json;
}

}  // namespace robotperf::metrics
