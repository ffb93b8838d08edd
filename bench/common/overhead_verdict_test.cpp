// The verdict every overhead bench prints: a graph faster than its reference beyond the noise,
// in every round, is a bench defect; anything else is judged against the target.
#include "overhead_verdict.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

namespace robotperf::bench {
namespace {

// n samples spread evenly over [centre - 2 %, centre + 2 %].
std::vector<double> around(double centre, std::size_t n = 60) {
  std::vector<double> v;
  for (std::size_t i = 0; i < n; ++i)
    v.push_back(centre * (0.98 + 0.04 * static_cast<double>(i) / static_cast<double>(n - 1)));
  return v;
}

TEST(OverheadVerdict, AGraphFasterThanItsReferenceInEveryRoundIsADefect) {
  const auto v = judge_overhead({{around(10), around(8)}, {around(10), around(8.1)}}, 0.10);
  EXPECT_NEAR(v.ratio, -0.195, 0.01);
  EXPECT_LT(v.band, 0.05);
  EXPECT_TRUE(v.defect);
  EXPECT_FALSE(v.met);
  EXPECT_NE(verdict_text(v, true).find("BENCH DEFECT"), std::string::npos);
}

TEST(OverheadVerdict, RoundsThatDisagreeWidenTheBandAndAreNoDefect) {
  // One round says 20 % faster, the other 4 % slower: the band is half their spread.
  const auto v = judge_overhead({{around(10), around(8)}, {around(10), around(10.4)}}, 0.10);
  EXPECT_NEAR(v.round_low, -0.20, 0.01);
  EXPECT_NEAR(v.round_high, 0.04, 0.01);
  EXPECT_GE(v.band, 0.11);
  EXPECT_FALSE(v.defect);
}

TEST(OverheadVerdict, AnOverheadIsJudgedAgainstTheTarget) {
  const auto small = judge_overhead({{around(10), around(10.5)}, {around(10), around(10.6)}}, 0.10);
  EXPECT_FALSE(small.defect);
  EXPECT_TRUE(small.met);
  EXPECT_EQ(verdict_text(small, true), "(met)");
  EXPECT_EQ(verdict_text(small, false), "(information)");
  const auto large = judge_overhead({{around(10), around(13)}, {around(10), around(13.1)}}, 0.10);
  EXPECT_FALSE(large.met);
  EXPECT_EQ(verdict_text(large, true), "(NOT met)");
}

// An overhead under the target whose band reaches over it is neither met nor not met: rounds of
// +2 % and +14 % (band 6 %) put the overhead at about +8 %, which may be +14 %.
TEST(OverheadVerdict, ABandThatHoldsTheTargetIsUndecided) {
  const auto v = judge_overhead({{around(10), around(10.2)}, {around(10), around(11.4)}}, 0.10);
  EXPECT_FALSE(v.defect);
  EXPECT_LT(v.ratio, 0.10);
  EXPECT_GT(v.ratio + v.band, 0.10);
  EXPECT_FALSE(v.met);
  EXPECT_TRUE(v.undecided);
  EXPECT_EQ(verdict_text(v, true), "(undecided)");
}

// A kernel running in two modes (its second thread placed well or badly): the graph caught more
// often in the fast one has a lower p50, but the same floor: no defect.
TEST(OverheadVerdict, AModeMixIsNoDefectWhenTheFloorsAgree) {
  auto modes = [](std::size_t fast) {
    std::vector<double> v = around(12, fast);
    const auto slow = around(17, 60 - fast);
    v.insert(v.end(), slow.begin(), slow.end());
    return v;
  };
  const auto v = judge_overhead({{modes(20), modes(45)}, {modes(22), modes(44)}}, 0.10);
  EXPECT_LT(v.ratio, -v.band);
  EXPECT_NEAR(v.floor_ratio, 0.0, 0.02);
  EXPECT_FALSE(v.defect);
}

TEST(OverheadVerdict, TooFewSamplesAreNoEvidence) {
  // Two samples give a median interval without ends: no defect can be claimed from them.
  const auto v = judge_overhead({{{10, 10.1}, {5, 5.1}}}, 0.10);
  EXPECT_FALSE(std::isfinite(v.band));
  EXPECT_FALSE(v.defect);
}

TEST(ConfirmDefect, OnlyADefectEveryFreshProcessFindsIsConfirmed) {
  EXPECT_TRUE(confirm_defect({"/bin/sh", "-c", "exit 1"}));
  EXPECT_FALSE(confirm_defect({"/bin/sh", "-c", "exit 0"}));
  // The first process finds the defect, the second does not: not confirmed.
  const std::string flag = ::testing::TempDir() + "confirm_defect_seen";
  std::remove(flag.c_str());
  EXPECT_FALSE(confirm_defect(
      {"/bin/sh", "-c", "if [ -e " + flag + " ]; then exit 0; fi; touch " + flag + "; exit 1"}));
  std::remove(flag.c_str());
  // A process that fails in another way is no verdict.
  EXPECT_THROW(confirm_defect({"/bin/sh", "-c", "exit 2"}), std::runtime_error);
  EXPECT_THROW(confirm_defect({"/nonexistent/bench"}), std::runtime_error);
}

// The confirming run measures the suspected benchmark alone: a defect in another one, which the
// whole bench run again would find, confirms nothing.
TEST(ConfirmDefect, TheConfirmingRunIsTheSameBenchOnTheSuspectedBenchmarkAlone) {
  char a0[] = "bench_x", a1[] = "--smoke", a2[] = "b3", a3[] = "b1";
  char* argv[] = {a0, a1, a2, a3, nullptr};
  const BenchOptions o = parse_bench_options(4, argv);
  EXPECT_TRUE(o.smoke);
  EXPECT_FALSE(o.confirming);
  EXPECT_EQ(o.args, (std::vector<std::string>{"b3", "b1"}));
  EXPECT_EQ(confirming_command(o, "b3"),
            (std::vector<std::string>{"/proc/self/exe", "--smoke", "b3", "--confirm"}));
  char c[] = "--confirm";
  char* with[] = {a0, a2, c, nullptr};
  const BenchOptions confirming = parse_bench_options(3, with);
  EXPECT_TRUE(confirming.confirming);
  EXPECT_EQ(confirming.args, (std::vector<std::string>{"b3"}));
}

// The body every overhead bench's main runs: its exit status says no defect (0), a confirmed
// defect (1) or an error (2, named after the bench).
TEST(RunOverheadBench, NoDefectIsStatusZeroAfterEveryComparisonAndTheLastStep) {
  std::vector<std::string> compared;
  bool after = false;
  const int status = run_overhead_bench(
      BenchOptions{}, "bench_x", {"b3", "b1"},
      [&](const std::string& id) {
        compared.push_back(id);
        return false;
      },
      [&] { after = true; });
  EXPECT_EQ(status, 0);
  EXPECT_EQ(compared, (std::vector<std::string>{"b3", "b1"}));
  EXPECT_TRUE(after);
}

// A confirming process reports the defect it found itself: no further process is started.
TEST(RunOverheadBench, ADefectInAConfirmingProcessIsStatusOne) {
  BenchOptions confirming;
  confirming.confirming = true;
  EXPECT_EQ(run_overhead_bench(confirming, "bench_x", {"b3", "b1"},
                               [](const std::string& id) { return id == "b1"; }),
            1);
}

TEST(RunOverheadBench, AnErrorIsStatusTwoAndOneLineNamingTheBench) {
  bool after = false;
  ::testing::internal::CaptureStderr();
  const int status = run_overhead_bench(
      BenchOptions{}, "bench_x", {"b9"},
      [](const std::string& id) -> bool { throw std::invalid_argument("no benchmark " + id); },
      [&] { after = true; });
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), "bench_x: no benchmark b9\n");
  EXPECT_EQ(status, 2);
  EXPECT_FALSE(after);
  EXPECT_EQ(run_overhead_bench(
                BenchOptions{}, "bench_x", {}, [](const std::string&) { return false; },
                [] { throw std::runtime_error("the last step failed"); }),
            2);
}

TEST(OverheadRow, ShowsBothMediansTheOverheadItsNoiseAndTheVerdict) {
  OverheadVerdict v;
  v.reference_p50 = 10;
  v.graph_p50 = 10.5;
  v.ratio = 0.05;
  v.band = 0.01;
  v.round_low = 0.04;
  v.round_high = 0.06;
  v.floor_ratio = 0.03;
  v.met = true;
  ::testing::internal::CaptureStdout();
  print_overhead_row("a3 stereo", v, 0.10);
  EXPECT_EQ(::testing::internal::GetCapturedStdout(),
            "a3 stereo                              10.000     10.500      0.500       5.0 %   "
            "noise +-1.0 % (rounds +4.0..+6.0 %, p10 +3.0 %)   target <= 10 %: ratio 0.50 (met)\n");
}

}  // namespace
}  // namespace robotperf::bench
