// A sweep of one workload parameter (run --sweep KEY=V1,V2,...): one run per value, and the
// latency distribution, loss, rate and CPU of each side side by side. For a ping-pong (n1, n2)
// the latency is the round trip, timed on the ping side's clock, and half of it is shown too.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "robotperf/harness/run.hpp"
#include "robotperf/report/series.hpp"

namespace robotperf::report {

struct SweepRow {
  std::string value;  // the parameter's value in this run
  bool valid = false;
  std::string file;                 // its results file, when written
  metrics::SampleStats latency_ns;  // from the scheduled send
  double loss_percent = 0;
  double throughput_hz = 0;
  // % of one core per process of the run, by its label (the graph's side and robotperf's).
  std::vector<std::pair<std::string, double>> cpu_percent;
};

class Sweep {
 public:
  Sweep(std::string benchmark_id, std::string parameter, std::size_t planned_runs);
  void add(const std::string& value, const harness::RunResult& run,
           const std::optional<std::filesystem::path>& json);

  const std::string& benchmark_id() const { return benchmark_id_; }
  const std::string& parameter() const { return parameter_; }
  const std::vector<SweepRow>& rows() const { return rows_; }
  // No further value will be run, before the last one: the summary says why.
  void end_early(std::string why) { completed_.ended_early = std::move(why); }
  const RunsCompleted& completed() const { return completed_; }

 private:
  std::string benchmark_id_;
  std::string parameter_;
  RunsCompleted completed_;
  std::vector<SweepRow> rows_;
};

// "KEY=V1,V2,...": the parameter and its values; throws std::invalid_argument naming the option.
std::pair<std::string, std::vector<std::string>> parse_sweep(const std::string& text);

// One line per value: latency p50, p90, p99, p99.9 and max (ms), p50 / 2, loss, output rate and
// each process's CPU; INVALID runs are marked.
std::string sweep_table(const Sweep& sweep);
// The same for the sweep file ("robotperf.sweep/1").
nlohmann::json sweep_json(const Sweep& sweep);

}  // namespace robotperf::report
