// Repeated runs of one benchmark (run --repeat N): how much each headline figure moves from run
// to run, so that a difference between two configurations can be told from noise.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "robotperf/harness/run.hpp"
#include "robotperf/metrics/latency_stats.hpp"

namespace robotperf::report {

// One headline figure over the valid runs of a series.
struct SeriesFigure {
  std::string name;  // "latency p50", ...
  std::string unit;
  std::vector<double> values;  // one per valid run, in run order

  // The median over runs and its distribution-free 95 % interval (SampleStats::p50_ci: needs
  // at least 6 runs for both ends), min and max.
  metrics::SampleStats stats() const;
  // (max - min) / median, in percent; NaN without runs.
  double spread_percent() const;
};

// How far several runs of one benchmark (a series, a sweep) got: every run planned, or fewer and
// why. A summary over fewer runs than asked for says so, in its table and its file.
struct RunsCompleted {
  std::size_t planned = 0;
  std::string ended_early;  // why no further run was made; empty when all were

  // ", ended early after D of P runs: WHY" when it did, else "".
  std::string note(std::size_t done) const;
  // Adds "planned_runs", "complete" and "ended_early" (the reason, or null) to a summary file.
  void add_to(nlohmann::json& summary) const;
};

class Series {
 public:
  Series(std::string benchmark_id, std::size_t planned_runs);

  // A finished run: its file (when written) is listed; its figures count when it is valid.
  void add(const harness::RunResult& run, const std::optional<std::filesystem::path>& json);

  const std::string& benchmark_id() const { return benchmark_id_; }
  std::size_t runs() const { return runs_; }
  std::size_t valid_runs() const { return valid_runs_; }
  const std::vector<std::string>& files() const { return files_; }
  // Latency p50, p99 and max (ms, from the scheduled send), throughput (Hz), loss (%).
  const std::vector<SeriesFigure>& figures() const { return figures_; }
  // No further run will be added, before the planned number: the summary says why.
  void end_early(std::string why) { completed_.ended_early = std::move(why); }
  const RunsCompleted& completed() const { return completed_; }

 private:
  std::string benchmark_id_;
  RunsCompleted completed_;
  std::size_t runs_ = 0;
  std::size_t valid_runs_ = 0;
  std::vector<std::string> files_;
  std::vector<SeriesFigure> figures_;
};

// The series as a table: per figure the median, its 95 % interval, min, max and spread.
std::string series_table(const Series& series);
// The same for the series file ("robotperf.series/1"), with every run's value.
nlohmann::json series_json(const Series& series);

}  // namespace robotperf::report
