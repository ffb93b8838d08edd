// The peak-throughput search against graphs whose limit is known.
#include "robotperf/harness/peak_search.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <csignal>

#include "../sanitized_build.hpp"
#include "test_package.hpp"

namespace robotperf::harness {
namespace {

using testing::relay_graph;
using testing::TestPackage;

// A relay that holds each message 10 ms on a one-thread executor serves at most 100 per second:
// the search must find that limit within 5 %, in few steps, and say why the next rate failed.
TEST(PeakSearch, FindsTheServiceLimitOfARelay) {
  TestPackage p("peak", relay_graph("delay_ms: 10"));
  const BenchmarkSpec spec = load_benchmark(p.dir());
  RunOptions o;
  o.load.rate_hz = 20;
  PeakSearchOptions search;
  search.step_duration_s = 1.5;
  search.rate_high_hz = 400;
  std::size_t seen = 0;
  const PeakSearchResult found = find_peak(spec, o, search, [&](const PeakStep&) { ++seen; });
  ASSERT_TRUE(found.peak.has_value()) << found.record.stop_reason;
  const RunResult& peak = *found.peak;
  EXPECT_EQ(peak.throughput_kind, "peak");
  ASSERT_TRUE(peak.peak_search.has_value());
  EXPECT_EQ(seen, found.record.steps.size());
  // 1 / (10 ms + the relay's own overhead): a little below 100 Hz (the overhead is larger in a
  // sanitized build).
  EXPECT_GT(peak.rate_hz, test_rate(90, 80));
  EXPECT_LT(peak.rate_hz, 101.0);
  EXPECT_NEAR(peak.throughput_hz, peak.rate_hz, 0.05 * peak.rate_hz);
  EXPECT_TRUE(peak.valid) << (peak.invalid_reasons.empty() ? "" : peak.invalid_reasons[0]);
  // Doubling 20 -> 160 brackets it in 4 steps; bisecting 80..160 to 5 % takes 4 more.
  EXPECT_LE(found.record.steps.size(), 10u);
  // Over its limit the relay's queue (KEEP_LAST 10) overflows, or, just over it, the outputs
  // lag the inputs: the search stops naming which.
  const std::string& stop = found.record.stop_reason;
  EXPECT_NE(stop.find("failed: "), std::string::npos) << stop;
  EXPECT_TRUE(stop.find("lost, above the 0 % bound") != std::string::npos ||
              stop.find("the graph fell behind") != std::string::npos)
      << stop;
  // Rates well below the limit passed, rates well above it failed, each failure with its reason
  // (near the limit a noisy machine may decide either way).
  for (const auto& s : found.record.steps) {
    if (s.rate_hz < 80) {
      EXPECT_TRUE(s.passed) << s.rate_hz << " Hz: " << s.reason;
    }
    if (s.rate_hz > 110) {
      EXPECT_FALSE(s.passed) << s.rate_hz << " Hz";
    }
    EXPECT_EQ(s.passed, s.reason.empty()) << s.reason;
  }
}

// A latency bound the graph can never meet (its service time alone is above it): no rate passes,
// each step says it was the latency, and the search stops going down once a step would measure
// too few messages to judge.
TEST(PeakSearch, ALatencyBoundBelowTheServiceTimeStopsEveryRate) {
  TestPackage p("peak_latency", relay_graph("delay_ms: 5"));
  const BenchmarkSpec spec = load_benchmark(p.dir());
  RunOptions o;
  o.load.rate_hz = 40;
  PeakSearchOptions search;
  search.step_duration_s = 1.0;
  search.latency_bound_ms = 3.0;
  search.latency_percentile = 50;
  const PeakSearchResult found = find_peak(spec, o, search);
  EXPECT_FALSE(found.peak.has_value());
  ASSERT_GE(found.record.steps.size(), 2u);
  for (const auto& s : found.record.steps) {
    EXPECT_FALSE(s.passed);
    EXPECT_NE(s.reason.find("above the 3 ms bound"), std::string::npos) << s.reason;
    EXPECT_GE(s.latency_ms, 5.0);
    EXPECT_GE(s.rate_hz * search.step_duration_s, 5.0);  // min_samples of relay_graph
  }
  EXPECT_NE(found.record.stop_reason.find("no rate down to"), std::string::npos)
      << found.record.stop_reason;
}

// A graph that loses a quarter of its messages at any rate fails a 10 % loss bound at every
// step, each saying so.
TEST(PeakSearch, ALossBoundStopsAGraphThatDropsAtEveryRate) {
  TestPackage p("peak_loss", relay_graph("drop_every: 4"));
  const BenchmarkSpec spec = load_benchmark(p.dir());
  RunOptions o;
  o.load.rate_hz = 40;
  PeakSearchOptions search;
  search.step_duration_s = 1.0;
  search.loss_bound_percent = 10;
  const PeakSearchResult found = find_peak(spec, o, search);
  EXPECT_FALSE(found.peak.has_value());
  ASSERT_GE(found.record.steps.size(), 2u);
  for (const auto& s : found.record.steps) {
    EXPECT_FALSE(s.passed);
    // One in four, give or take one message of a short step.
    EXPECT_GT(s.loss_percent, 15.0);
    EXPECT_LT(s.loss_percent, 35.0);
    EXPECT_NE(s.reason.find("lost, above the 10 % bound"), std::string::npos) << s.reason;
  }
  EXPECT_DOUBLE_EQ(found.record.loss_bound_percent, 10.0);
}

// An interrupt after the first sustained rate ends the search there: the best run it had is
// kept, but as a rate the graph sustained, marked interrupted, never as the peak.
TEST(PeakSearch, AnInterruptedSearchReportsNoPeak) {
  TestPackage p("peak_interrupted", relay_graph("delay_ms: 1"));
  const BenchmarkSpec spec = load_benchmark(p.dir());
  std::atomic<int> interrupted = 0;
  RunOptions o;
  o.load.rate_hz = 20;
  o.interrupted = &interrupted;
  PeakSearchOptions search;
  search.step_duration_s = 1.0;
  search.rate_high_hz = 400;
  const PeakSearchResult found = find_peak(spec, o, search, [&](const PeakStep& s) {
    if (s.passed) interrupted = SIGINT;
  });
  ASSERT_TRUE(found.peak.has_value()) << found.record.stop_reason;
  EXPECT_FALSE(found.record.finished);
  EXPECT_EQ(found.record.steps.size(), 1u);
  EXPECT_NE(found.record.stop_reason.find("interrupted"), std::string::npos)
      << found.record.stop_reason;
  const RunResult& best = *found.peak;
  EXPECT_NE(best.throughput_kind, "peak");
  EXPECT_TRUE(best.interrupted);
  ASSERT_TRUE(best.peak_search.has_value());
  EXPECT_FALSE(best.peak_search->finished);
  ASSERT_FALSE(best.warnings.empty());
  EXPECT_EQ(best.warnings.back().rule, "peak_search_unfinished");
}

TEST(PeakSearch, BadBoundsAreRejectedBeforeAnyStep) {
  TestPackage p("peak_bad", relay_graph(""));
  const BenchmarkSpec spec = load_benchmark(p.dir());
  RunOptions o;
  PeakSearchOptions s;
  s.loss_bound_percent = 100;
  EXPECT_THROW(find_peak(spec, o, s), std::invalid_argument);
  s = {};
  s.latency_bound_ms = -1;
  EXPECT_THROW(find_peak(spec, o, s), std::invalid_argument);
  s = {};
  s.rate_low_hz = 50;
  s.rate_high_hz = 10;
  EXPECT_THROW(find_peak(spec, o, s), std::invalid_argument);
  s = {};
  o.load.count = 100;
  EXPECT_THROW(find_peak(spec, o, s), std::invalid_argument);
}

}  // namespace
}  // namespace robotperf::harness
