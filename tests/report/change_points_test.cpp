// Change points on synthetic series whose steps are known: found where planted, and on noise
// alone reported at about the stated rate (docs/design.md §8).
#include "robotperf/report/change_points.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <stdexcept>
#include <vector>

namespace robotperf::report {
namespace {

// Latency-like noise: a level with normal noise of 2 % and, now and then, a slow outlier.
std::vector<double> noisy(std::size_t n, double level, std::mt19937_64& random) {
  std::normal_distribution<double> noise(0, 0.02 * level);
  std::uniform_real_distribution<double> chance(0, 1);
  std::vector<double> out;
  for (std::size_t i = 0; i < n; ++i)
    out.push_back(level + noise(random) + (chance(random) < 0.05 ? 0.3 * level : 0));
  return out;
}

TEST(ChangePoints, FindAPlantedStepWhereItIs) {
  std::mt19937_64 random(7);
  std::size_t found_there = 0;
  constexpr std::size_t kTrials = 40;
  for (std::size_t trial = 0; trial < kTrials; ++trial) {
    std::vector<double> series = noisy(25, 2.0, random);
    const std::vector<double> slower = noisy(15, 2.4, random);  // +20 %
    series.insert(series.end(), slower.begin(), slower.end());
    const auto points = change_points(series, {.seed = trial + 1});
    for (const auto& p : points) {
      if (p.index >= 24 && p.index <= 26 && p.change_percent() > 15 && p.change_percent() < 25)
        ++found_there;
    }
  }
  // A 20 % step is ten times the noise: nearly every trial finds it within a point.
  EXPECT_GE(found_there, kTrials - 2);
}

TEST(ChangePoints, FindTwoStepsAndTheirDirections) {
  std::mt19937_64 random(11);
  std::vector<double> series = noisy(20, 5.0, random);
  for (double level : {4.0, 6.0}) {
    const auto next = noisy(20, level, random);
    series.insert(series.end(), next.begin(), next.end());
  }
  const auto points = change_points(series);
  ASSERT_EQ(points.size(), 2u);
  EXPECT_NEAR(static_cast<double>(points[0].index), 20, 1);
  EXPECT_LT(points[0].change_percent(), -15);  // faster
  EXPECT_NEAR(static_cast<double>(points[1].index), 40, 1);
  EXPECT_GT(points[1].change_percent(), 40);  // slower
  EXPECT_LE(points[0].p_value, 0.01);
}

// The stated rate: on a series without a change, a change point is reported in about
// `significance` of the series (1 % by default). 300 series: 3 expected; more than 12 would be a
// rate four times the stated one (binomial tail below 1e-4).
TEST(ChangePoints, StayQuietOnNoiseAtTheStatedRate) {
  std::mt19937_64 random(3);
  std::size_t false_alarms = 0;
  constexpr std::size_t kSeries = 300;
  for (std::size_t i = 0; i < kSeries; ++i) {
    if (!change_points(noisy(40, 3.0, random), {.seed = i + 1}).empty()) ++false_alarms;
  }
  EXPECT_LE(false_alarms, 12u) << "of " << kSeries << " series without a change";
}

TEST(ChangePoints, SeriesTooShortOrFlatHaveNone) {
  EXPECT_TRUE(change_points({}).empty());
  EXPECT_TRUE(change_points({1, 2, 3, 4, 5}).empty());  // fewer than two segments of 3
  EXPECT_TRUE(change_points(std::vector<double>(30, 2.5)).empty());
}

TEST(ChangePoints, TheSameSeedGivesTheSameAnswer) {
  std::mt19937_64 random(5);
  std::vector<double> series = noisy(12, 1.0, random);
  const auto after = noisy(12, 1.08, random);
  series.insert(series.end(), after.begin(), after.end());
  const auto first = change_points(series, {.seed = 42});
  const auto second = change_points(series, {.seed = 42});
  ASSERT_EQ(first.size(), second.size());
  for (std::size_t i = 0; i < first.size(); ++i) {
    EXPECT_EQ(first[i].index, second[i].index);
    EXPECT_EQ(first[i].p_value, second[i].p_value);
  }
}

TEST(ChangePoints, RefuseWhatCannotBeTested) {
  EXPECT_THROW(change_points({1, 2, NAN, 4, 5, 6}), std::invalid_argument);
  EXPECT_THROW(change_points({1, 2, 3}, {.significance = 0.001, .permutations = 99}),
               std::invalid_argument);
  EXPECT_THROW(change_points({1, 2, 3}, {.min_segment = 1}), std::invalid_argument);
}

}  // namespace
}  // namespace robotperf::report
