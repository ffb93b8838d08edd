#include "robotperf/metrics/latency_stats.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <stdexcept>
#include <vector>

namespace robotperf::metrics {
namespace {

std::vector<double> one_to(int n) {
  std::vector<double> values(n);
  std::iota(values.begin(), values.end(), 1.0);
  return values;
}

TEST(ComputeStats, OneToTenMatchesHandComputedValues) {
  const SampleStats stats = compute_stats(one_to(10));
  EXPECT_EQ(stats.count, 10u);
  EXPECT_DOUBLE_EQ(stats.min, 1.0);
  EXPECT_DOUBLE_EQ(stats.max, 10.0);
  EXPECT_DOUBLE_EQ(stats.mean, 5.5);
  // sum of squares 385 → rms sqrt(38.5); squared deviations 82.5 → sample stddev sqrt(82.5 / 9).
  EXPECT_DOUBLE_EQ(stats.rms, std::sqrt(38.5));
  EXPECT_DOUBLE_EQ(stats.stddev, std::sqrt(82.5 / 9.0));
  // Type 7: h = 9 q.
  EXPECT_DOUBLE_EQ(stats.p50, 5.5);
  EXPECT_DOUBLE_EQ(stats.p90, 9.1);
  EXPECT_DOUBLE_EQ(stats.p99, 9.91);
  EXPECT_DOUBLE_EQ(stats.p999, 9.991);
}

TEST(ComputeStats, OrderOfInputDoesNotMatter) {
  const std::vector<double> shuffled = {7, 3, 10, 1, 9, 2, 8, 5, 6, 4};
  const SampleStats stats = compute_stats(shuffled);
  EXPECT_DOUBLE_EQ(stats.p90, 9.1);
  EXPECT_DOUBLE_EQ(stats.min, 1.0);
  EXPECT_DOUBLE_EQ(stats.max, 10.0);
}

TEST(ComputeStats, InterpolatesBetweenUnequalNeighbours) {
  // n = 4, h = 3 q: p50 → h 1.5 between 20 and 40 → 30; p90 → h 2.7 between 40 and 100 → 82.
  const std::vector<double> samples = {100, 10, 40, 20};
  const SampleStats stats = compute_stats(samples);
  EXPECT_DOUBLE_EQ(stats.p50, 30.0);
  EXPECT_DOUBLE_EQ(stats.p90, 82.0);
  EXPECT_DOUBLE_EQ(stats.mean, 42.5);
}

TEST(ComputeStats, SingleSampleHasEveryStatisticButStddev) {
  const std::vector<double> samples = {4.25};
  const SampleStats stats = compute_stats(samples);
  EXPECT_EQ(stats.count, 1u);
  for (const double value :
       {stats.min, stats.mean, stats.rms, stats.p50, stats.p90, stats.p99, stats.p999, stats.max}) {
    EXPECT_DOUBLE_EQ(value, 4.25);
  }
  EXPECT_TRUE(std::isnan(stats.stddev));
}

TEST(ComputeStats, EmptyInputGivesCountZeroAndNaN) {
  const SampleStats stats = compute_stats(std::vector<double>{});
  EXPECT_EQ(stats.count, 0u);
  for (const double value : {stats.min, stats.mean, stats.rms, stats.stddev, stats.p50, stats.p90,
                             stats.p99, stats.p999, stats.max}) {
    EXPECT_TRUE(std::isnan(value));
  }
}

TEST(ComputeStats, RejectsNonFiniteSamples) {
  const std::vector<double> with_nan = {1.0, std::numeric_limits<double>::quiet_NaN()};
  const std::vector<double> with_inf = {1.0, std::numeric_limits<double>::infinity()};
  EXPECT_THROW(compute_stats(with_nan), std::invalid_argument);
  EXPECT_THROW(compute_stats(with_inf), std::invalid_argument);
}

TEST(ComputeStats, SmallSpreadOnLargeOffsetKeepsPrecision) {
  // Latencies in ns since an epoch-like offset: a naive E[x^2] - E[x]^2 loses all digits here.
  std::vector<double> samples;
  for (int i = 0; i < 1000; ++i) samples.push_back(1e12 + (i % 2 == 0 ? -1.0 : 1.0));
  const SampleStats stats = compute_stats(samples);
  EXPECT_DOUBLE_EQ(stats.mean, 1e12);
  EXPECT_NEAR(stats.stddev, std::sqrt(1000.0 / 999.0), 1e-9);
}

TEST(ComputeStats, MeanOfEqualSamplesStaysWithinMinAndMax) {
  const std::vector<double> samples(12345, 0.1);
  const SampleStats stats = compute_stats(samples);
  EXPECT_GE(stats.mean, stats.min);
  EXPECT_LE(stats.mean, stats.max);
  EXPECT_NEAR(stats.stddev, 0.0, 1e-15);
}

TEST(ComputeStats, MillionUniformSamplesAreFastAndSane) {
  std::mt19937_64 generator(42);
  std::uniform_real_distribution<double> uniform(0.0, 1000.0);
  std::vector<double> samples(1'000'000);
  for (double& sample : samples) sample = uniform(generator);

  const auto start = std::chrono::steady_clock::now();
  const SampleStats stats = compute_stats(samples);
  const auto elapsed = std::chrono::steady_clock::now() - start;

  EXPECT_EQ(stats.count, 1'000'000u);
  EXPECT_NEAR(stats.p50, 500.0, 3.0);
  EXPECT_NEAR(stats.p99, 990.0, 1.0);
  EXPECT_NEAR(stats.p999, 999.0, 0.3);
  EXPECT_NEAR(stats.mean, 500.0, 2.0);
  EXPECT_NEAR(stats.stddev, 1000.0 / std::sqrt(12.0), 1.0);
  EXPECT_NEAR(stats.rms, 1000.0 / std::sqrt(3.0), 1.0);
  EXPECT_LE(stats.p50, stats.p90);
  EXPECT_LE(stats.p90, stats.p99);
  EXPECT_LE(stats.p99, stats.p999);
  EXPECT_LE(stats.p999, stats.max);
  // Generous bound (sanitizer builds are slow); a quadratic algorithm would take minutes.
  EXPECT_LT(std::chrono::duration<double>(elapsed).count(), 5.0);
}

TEST(Median, OfSamplesInAnyOrder) {
  EXPECT_DOUBLE_EQ(median({8.0, 2.0, 4.0}), 4.0);
  EXPECT_DOUBLE_EQ(median({8.0, 2.0, 4.0, 3.0}), 3.5);
  EXPECT_TRUE(std::isnan(median({})));
}

TEST(QuantileOfSorted, EndpointsAndInvalidQuantile) {
  const std::vector<double> sorted = {2.0, 4.0, 8.0};
  EXPECT_DOUBLE_EQ(quantile_of_sorted(sorted, 0.0), 2.0);
  EXPECT_DOUBLE_EQ(quantile_of_sorted(sorted, 1.0), 8.0);
  EXPECT_DOUBLE_EQ(quantile_of_sorted(sorted, 0.75), 6.0);
  EXPECT_TRUE(std::isnan(quantile_of_sorted(std::vector<double>{}, 0.5)));
  EXPECT_THROW(quantile_of_sorted(sorted, 1.5), std::invalid_argument);
  EXPECT_THROW(quantile_of_sorted(sorted, -0.1), std::invalid_argument);
  EXPECT_THROW(quantile_of_sorted(sorted, std::numeric_limits<double>::quiet_NaN()),
               std::invalid_argument);
}

TEST(StatsToJson, ScalesValuesAndAddsUnit) {
  const std::vector<double> nanoseconds = {1'000'000.0, 3'000'000.0};
  const nlohmann::json json = to_json(compute_stats(nanoseconds), 1e-6, "ms");
  EXPECT_EQ(json.at("count").get<std::size_t>(), 2u);
  EXPECT_DOUBLE_EQ(json.at("min").get<double>(), 1.0);
  EXPECT_DOUBLE_EQ(json.at("mean").get<double>(), 2.0);
  EXPECT_DOUBLE_EQ(json.at("max").get<double>(), 3.0);
  EXPECT_DOUBLE_EQ(json.at("p50").get<double>(), 2.0);
  EXPECT_EQ(json.at("unit").get<std::string>(), "ms");
  for (const char* key : {"rms", "stddev", "p90", "p99", "p999"}) {
    EXPECT_TRUE(json.at(key).is_number()) << key;
  }
}

TEST(StatsToJson, NoUnitKeyWhenUnitIsEmpty) {
  const nlohmann::json json = to_json(compute_stats(one_to(3)));
  EXPECT_FALSE(json.contains("unit"));
  EXPECT_DOUBLE_EQ(json.at("max").get<double>(), 3.0);
}

TEST(StatsToJson, NaNBecomesNull) {
  const nlohmann::json empty = to_json(compute_stats(std::vector<double>{}), 1e-3, "us");
  EXPECT_EQ(empty.at("count").get<std::size_t>(), 0u);
  for (const char* key : {"min", "mean", "rms", "stddev", "p50", "p90", "p99", "p999", "max"}) {
    EXPECT_TRUE(empty.at(key).is_null()) << key;
  }
  EXPECT_EQ(empty.dump().find("NaN"), std::string::npos);

  const nlohmann::json single = to_json(compute_stats(std::vector<double>{5.0}));
  EXPECT_TRUE(single.at("stddev").is_null());
  EXPECT_TRUE(single.at("max").is_number());
}

// The textbook interval of a median of 100 samples: x(40) to x(61).
TEST(PercentileInterval, MedianOfAHundredIsTheTextbookInterval) {
  const OrderStatisticRanks r = percentile_interval_ranks(100, 0.5);
  EXPECT_EQ(r.lower, 40u);
  EXPECT_EQ(r.upper, 61u);
  const SampleStats s = compute_stats(one_to(100));
  EXPECT_DOUBLE_EQ(s.p50_ci.lower, 40.0);
  EXPECT_DOUBLE_EQ(s.p50_ci.upper, 61.0);
  EXPECT_LE(s.p50_ci.lower, s.p50);
  EXPECT_GE(s.p50_ci.upper, s.p50);
}

TEST(PercentileInterval, TooFewSamplesLeaveTheUpperEndOpen) {
  EXPECT_EQ(samples_for_upper_bound(0.99), 368u);
  EXPECT_EQ(samples_for_upper_bound(0.999), 3688u);
  const SampleStats few = compute_stats(one_to(367));
  EXPECT_TRUE(std::isnan(few.p99_ci.upper));
  EXPECT_FALSE(std::isnan(few.p99_ci.lower));
  const SampleStats enough = compute_stats(one_to(368));
  EXPECT_DOUBLE_EQ(enough.p99_ci.upper, 368.0);
  // One sample bounds nothing.
  const SampleStats one = compute_stats(std::vector<double>{5.0});
  EXPECT_TRUE(std::isnan(one.p50_ci.lower));
  EXPECT_TRUE(std::isnan(one.p50_ci.upper));
  EXPECT_THROW(percentile_interval_ranks(10, 1.0), std::invalid_argument);
}

// The intervals hold what they claim: over many sample sets from a known distribution, about 95 %
// of them contain the true percentile (at least 95 % by construction, a little more since ranks
// are whole numbers).
TEST(PercentileInterval, CoversTheTruePercentileAtTheStatedRate) {
  std::mt19937_64 generator(3);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const int trials = 2000;
  int covered_p90 = 0, covered_p50 = 0;
  std::vector<double> samples(300);
  for (int t = 0; t < trials; ++t) {
    for (double& x : samples) x = uniform(generator);
    const SampleStats s = compute_stats(samples);
    covered_p90 += s.p90_ci.lower <= 0.9 && 0.9 <= s.p90_ci.upper;
    covered_p50 += s.p50_ci.lower <= 0.5 && 0.5 <= s.p50_ci.upper;
  }
  for (int covered : {covered_p90, covered_p50}) {
    const double rate = static_cast<double>(covered) / trials;
    EXPECT_GT(rate, 0.935);
    EXPECT_LT(rate, 0.985);
  }
}

TEST(PercentileInterval, LargeSampleCountsStayFastAndNarrow) {
  const auto start = std::chrono::steady_clock::now();
  const OrderStatisticRanks r = percentile_interval_ranks(10'000'000, 0.999);
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(2));
  // 10^7 samples: the p99.9 rank 9'990'000 give or take two standard deviations (100 each).
  EXPECT_GT(r.lower, 9'989'700u);
  EXPECT_LT(r.lower, 9'990'000u);
  EXPECT_GT(r.upper, 9'990'000u);
  EXPECT_LT(r.upper, 9'990'300u);
}

TEST(StatsToJson, IntervalsArePairsWithNullForAnOpenEnd) {
  const nlohmann::json json = to_json(compute_stats(one_to(100)), 2.0);
  EXPECT_DOUBLE_EQ(json.at("p50_ci95").at(0).get<double>(), 80.0);
  EXPECT_DOUBLE_EQ(json.at("p50_ci95").at(1).get<double>(), 122.0);
  EXPECT_TRUE(json.at("p99_ci95").at(1).is_null());
  EXPECT_TRUE(json.at("p999_ci95").at(1).is_null());
}

}  // namespace
}  // namespace robotperf::metrics

// The radix sort must give std::sort's order on every kind of double: negatives (whose bits
// sort backwards), zeros of both signs, subnormals, infinities, repeats and whole nanoseconds.
TEST(SortSamples, GivesStdSortsOrder) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> wide(-1e12, 1e12);
  std::uniform_int_distribution<int64_t> nanoseconds(0, 50'000'000);
  const double specials[] = {0.0,
                             -0.0,
                             std::numeric_limits<double>::denorm_min(),
                             -std::numeric_limits<double>::denorm_min(),
                             std::numeric_limits<double>::infinity(),
                             -std::numeric_limits<double>::infinity(),
                             std::numeric_limits<double>::max(),
                             std::numeric_limits<double>::lowest(),
                             1.0,
                             -1.0};
  for (const std::size_t n : {0, 1, 100, 2047, 2048, 5000, 300'000}) {
    std::vector<double> samples(n);
    for (std::size_t i = 0; i < n; ++i) {
      switch (i % 4) {
        case 0:
          samples[i] = wide(rng);
          break;
        case 1:
          samples[i] = static_cast<double>(nanoseconds(rng));
          break;
        case 2:
          samples[i] = specials[rng() % std::size(specials)];
          break;
        default:
          samples[i] = -static_cast<double>(nanoseconds(rng)) / 7.0;
      }
    }
    std::vector<double> expected = samples;
    std::sort(expected.begin(), expected.end());
    // Half of the sizes with a scratch buffer of the caller's, half with the sort's own.
    std::vector<double> scratch(n % 2 == 0 ? n + 3 : 0, -1.0);
    robotperf::metrics::sort_samples(samples, scratch);
    ASSERT_EQ(samples.size(), expected.size());
    for (std::size_t i = 0; i < n; ++i)
      ASSERT_EQ(samples[i], expected[i]) << "n " << n << " at " << i;
  }
}

TEST(SortSamples, EqualSamplesAndOneDigitOfDifference) {
  std::vector<double> same(10'000, 123456.0);
  robotperf::metrics::sort_samples(same);
  EXPECT_TRUE(std::all_of(same.begin(), same.end(), [](double x) { return x == 123456.0; }));
  // Values that differ in one 11-bit digit only: every other pass is skipped.
  std::vector<double> one_digit;
  for (int i = 4999; i >= 0; --i) one_digit.push_back(static_cast<double>(i % 2000) * 1024.0);
  std::vector<double> expected = one_digit;
  std::sort(expected.begin(), expected.end());
  robotperf::metrics::sort_samples(one_digit);
  EXPECT_EQ(one_digit, expected);
}
