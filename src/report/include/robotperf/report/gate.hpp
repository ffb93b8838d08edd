// The regression gate: a candidate's runs against a baseline's, benchmark by benchmark, failing
// on a difference that is both beyond the run-to-run noise and larger than a threshold
// (docs/design.md §8). `robotperf compare --baseline A --candidate B --fail-on-regression PCT`.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "robotperf/metrics/latency_stats.hpp"
#include "robotperf/report/report.hpp"

namespace robotperf::report {

// The fewest valid runs per side for a judgement: Welch's test on the runs' figures needs a
// spread on both sides; from kRunsForIntervals on, the medians' distribution-free intervals judge.
inline constexpr std::size_t kGateMinRuns = 3;
inline constexpr std::size_t kRunsForIntervals = 6;
// Welch's test judges a difference significant below this p (one metric of one benchmark).
inline constexpr double kGateAlpha = 0.01;

struct GateFinding {
  enum class Verdict {
    kRegression,   // worse, significant and beyond the threshold: fails the gate
    kWorseWithin,  // worse and significant, but within the threshold
    kImprovement,  // better and significant
    kNoise,        // no significant difference
    kNotJudged,    // too few runs, or rates that make the figure no result
  };
  std::string benchmark, metric, unit;
  Verdict verdict = Verdict::kNotJudged;
  double baseline = 0, candidate = 0;  // medians over the valid runs
  metrics::PercentileInterval baseline_interval, candidate_interval;
  std::size_t baseline_runs = 0, candidate_runs = 0;
  double change_percent = 0;  // (candidate - baseline) / baseline
  std::string basis;          // how it was judged, or why not
};

struct GateResult {
  std::string baseline, candidate;  // the selectors
  double threshold_percent = 0;
  std::vector<GateFinding> findings;
  std::vector<std::string> notes;  // unlike configurations, invalid candidate runs, ...
  std::size_t regressions() const;
  std::size_t judged() const;
};

// Judges every benchmark both sides ran: latency p50 and p99, throughput (only at one rate: at
// two an offered throughput is the input rate), energy per message, and the functional metrics
// that have a threshold (its side says which way is better). A candidate run that is INVALID where
// the baseline's are valid is a regression of its own ("validity"). Throws ReportError when the
// sides share no benchmark.
GateResult run_gate(const ReportInput& input, const std::string& baseline,
                    const std::string& candidate, double threshold_percent);

std::string gate_text(const GateResult& gate);      // for the terminal
std::string gate_markdown(const GateResult& gate);  // for a CI job summary
std::string gate_junit(const GateResult& gate);     // JUnit XML: one test case per finding

}  // namespace robotperf::report
