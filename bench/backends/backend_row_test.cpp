// What bench_backends makes of a run: a run that lost messages or answered wrongly is invalid,
// and no target is met on its latency.
#include "backend_row.hpp"

#include <gtest/gtest.h>

namespace robotperf::bench {
namespace {

harness::RunResult run_of(double p50_ms) {
  harness::RunResult r;
  r.valid = true;
  r.latency_from_sent.p50 = p50_ms * 1e6;
  r.latency_from_sent.p99 = 2 * p50_ms * 1e6;
  return r;
}

BackendRow valid_row(double p50_ms) {
  return backend_row(run_of(p50_ms));
}

TEST(BackendRow, ARunThatLostMessagesIsInvalidWithItsReasons) {
  // As a3 on pocl's opencl at 30 Hz: the device cannot keep up and most messages are lost.
  harness::RunResult r = run_of(622.708);
  r.loss_percent = 70.91;
  r.valid = false;
  r.invalid_reasons = {"70.91 % of the measured messages lost (at most 1 % allowed)"};
  const BackendRow row = backend_row(r);
  EXPECT_FALSE(row.valid);
  EXPECT_DOUBLE_EQ(row.loss_percent, 70.91);
  EXPECT_DOUBLE_EQ(row.p50_ms, 622.708);
  ASSERT_EQ(row.reasons.size(), 1u);
  EXPECT_EQ(row.reasons[0], r.invalid_reasons[0]);
  EXPECT_TRUE(valid_row(1.0).valid);
  EXPECT_TRUE(valid_row(1.0).reasons.empty());
}

TEST(BackendRow, AnAnswerThatFailedItsChecksMakesTheRowInvalid) {
  harness::RunResult r = run_of(1.0);
  r.functional.emplace();
  r.functional->evaluator = "backend check";
  r.functional->valid = false;
  r.functional->reasons = {"cuda drifts from cpu"};
  const BackendRow row = backend_row(r);
  EXPECT_FALSE(row.valid);
  ASSERT_EQ(row.reasons.size(), 1u);
  EXPECT_EQ(row.reasons[0], "functional (backend check): cuda drifts from cpu");
}

// One run of each.
std::string target(const std::string& id, const BackendRow& cpu, const BackendRow& cuda) {
  return cuda_target(id, {cpu}, {cuda});
}

TEST(BackendRow, TargetsAreJudgedOnlyOnValidRuns) {
  EXPECT_EQ(target("a3", valid_row(20.0), valid_row(1.9)), ">= 10x: met");
  EXPECT_EQ(target("a3", valid_row(20.0), valid_row(2.1)), ">= 10x: NOT met");
  EXPECT_EQ(target("a1", valid_row(2.0), valid_row(1.2)), ">= 3x: NOT met; p50 <= 1 ms: NOT met");
  // Each part judged on its own.
  EXPECT_EQ(target("a1", valid_row(1.5), valid_row(0.75)), ">= 3x: NOT met; p50 <= 1 ms: met");
  EXPECT_EQ(target("a1", valid_row(3.6), valid_row(1.1)), ">= 3x: met; p50 <= 1 ms: NOT met");
  EXPECT_EQ(target("a4", valid_row(4.0), valid_row(1.0)), "-");
  // Ten times faster, but on a run that lost most of its messages (or a cpu run that did).
  harness::RunResult lost = run_of(1.0);
  lost.valid = false;
  lost.loss_percent = 70.0;
  EXPECT_EQ(target("a3", valid_row(20.0), backend_row(lost)),
            ">= 10x: not judged (an invalid run)");
  lost.latency_from_sent.p50 = 200e6;
  EXPECT_EQ(target("a3", backend_row(lost), valid_row(1.0)), ">= 10x: not judged (an invalid run)");
  EXPECT_EQ(target("a1", backend_row(lost), valid_row(0.1)),
            ">= 3x, p50 <= 1 ms: not judged (an invalid run)");
}

// As a3 on the H200: the cpu's p50 moved 10.2 - 11.5 ms between runs, cuda's hardly. Several
// pairs of runs are judged on their median speed-up, each pair's own cpu run against its cuda
// run, and the pairs' range is said.
TEST(BackendRow, SeveralRunsAreJudgedOnTheMedianOfTheirPairs) {
  const std::vector<BackendRow> cpu = {valid_row(10.2), valid_row(11.5), valid_row(10.9)};
  const std::vector<BackendRow> cuda = {valid_row(1.065), valid_row(1.091), valid_row(1.05)};
  const Speedup s = speedup(cpu, cuda);
  EXPECT_EQ(s.pairs, 3u);
  EXPECT_NEAR(s.median, 10.9 / 1.05, 1e-12);  // 10.38: pair 3's, not 10.9 / 1.065
  EXPECT_NEAR(s.least, 10.2 / 1.065, 1e-12);
  EXPECT_NEAR(s.most, 11.5 / 1.091, 1e-12);
  EXPECT_EQ(cuda_target("a3", cpu, cuda),
            ">= 10x: met (medians of 3 pairs of runs; speed-ups 9.58x to 10.54x)");
  // An even number: the middle two's mean.
  EXPECT_NEAR(speedup({valid_row(10.0), valid_row(12.0)}, {valid_row(1.0), valid_row(1.0)}).median,
              11.0, 1e-12);
  EXPECT_THROW(speedup(cpu, {valid_row(1.0)}), std::invalid_argument);
  EXPECT_THROW(speedup({}, {}), std::invalid_argument);
  // a1's p50 is cuda's median (0.95 ms), its speed-up the pairs' (2.84x).
  EXPECT_EQ(cuda_target("a1", {valid_row(2.7), valid_row(2.7), valid_row(2.7)},
                        {valid_row(0.9), valid_row(1.2), valid_row(0.95)}),
            ">= 3x: NOT met; p50 <= 1 ms: met (medians of 3 pairs of runs; speed-ups 2.25x to "
            "3.00x)");
}

TEST(BackendRow, SeveralRunsMakeOneRowValidOnlyWhenEachIs) {
  harness::RunResult lost = run_of(1.3);
  lost.valid = false;
  lost.loss_percent = 4.0;
  lost.invalid_reasons = {"4 % lost"};
  const BackendRow row = combined({valid_row(1.0), backend_row(lost), valid_row(1.2)});
  EXPECT_FALSE(row.valid);
  EXPECT_DOUBLE_EQ(row.p50_ms, 1.2);
  EXPECT_DOUBLE_EQ(row.p99_ms, 2.4);
  EXPECT_DOUBLE_EQ(row.loss_percent, 4.0);
  ASSERT_EQ(row.reasons.size(), 1u);
  EXPECT_EQ(row.reasons[0], "run 2: 4 % lost");
  EXPECT_EQ(cuda_target("a3", {valid_row(20.0), valid_row(20.0), valid_row(20.0)},
                        {valid_row(1.0), backend_row(lost), valid_row(1.2)}),
            ">= 10x: not judged (an invalid run)");
  const BackendRow one = combined({backend_row(lost)});
  EXPECT_EQ(one.reasons, lost.invalid_reasons);  // one run: its reasons as they are
  EXPECT_THROW(combined({}), std::invalid_argument);
}

}  // namespace
}  // namespace robotperf::bench
