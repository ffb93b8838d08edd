#include "robotperf/report/series.hpp"

#include <cmath>
#include <cstdio>
#include <sstream>

#include "robotperf/report/results.hpp"
#include "robotperf/report/run_store.hpp"

namespace robotperf::report {
namespace {

constexpr double kNsPerMs = 1e6;

std::string shown(double v) {
  return std::isfinite(v) ? format_fixed(v, 3) : "?";
}

double spread_of(const metrics::SampleStats& s) {
  if (s.count == 0 || s.p50 == 0) return metrics::SampleStats::kNoValue;
  return 100.0 * (s.max - s.min) / std::fabs(s.p50);
}

}  // namespace

metrics::SampleStats SeriesFigure::stats() const {
  return metrics::compute_stats(values);
}

double SeriesFigure::spread_percent() const {
  return spread_of(stats());
}

std::string RunsCompleted::note(std::size_t done) const {
  if (ended_early.empty()) return "";
  return ", ended early after " + std::to_string(done) + " of " + std::to_string(planned) +
         " runs: " + ended_early;
}

void RunsCompleted::add_to(nlohmann::json& summary) const {
  summary["planned_runs"] = planned;
  summary["complete"] = ended_early.empty();
  summary["ended_early"] =
      ended_early.empty() ? nlohmann::json(nullptr) : nlohmann::json(ended_early);
}

Series::Series(std::string benchmark_id, std::size_t planned_runs)
    : benchmark_id_(std::move(benchmark_id)),
      completed_{planned_runs, ""},
      figures_{{"latency p50", "ms", {}},
               {"latency p99", "ms", {}},
               {"latency max", "ms", {}},
               {"throughput", "Hz", {}},
               {"loss", "%", {}}} {}

void Series::add(const harness::RunResult& run, const std::optional<std::filesystem::path>& json) {
  ++runs_;
  if (json) files_.push_back(json->string());
  // An invalid run's figures describe a broken measurement: listed, never summarised.
  if (!run.valid) return;
  ++valid_runs_;
  const metrics::SampleStats& l = run.latency_from_scheduled;
  const double values[] = {l.p50 / kNsPerMs, l.p99 / kNsPerMs, l.max / kNsPerMs, run.throughput_hz,
                           run.loss_percent};
  for (std::size_t i = 0; i < figures_.size(); ++i) {
    if (std::isfinite(values[i])) figures_[i].values.push_back(values[i]);
  }
}

std::string series_table(const Series& series) {
  std::ostringstream out;
  out << "series " << series.benchmark_id() << ": " << series.runs() << " runs"
      << series.completed().note(series.runs()) << ", " << series.valid_runs()
      << " valid (figures over the valid runs; the median's 95 % interval "
      << "is distribution-free and needs at least 6 runs for both ends)\n";
  char line[200];
  std::snprintf(line, sizeof line, "  %-18s %10s %23s %10s %10s %9s\n", "figure", "median",
                "95 % interval", "min", "max", "spread");
  out << line;
  for (const auto& f : series.figures()) {
    const metrics::SampleStats s = f.stats();
    const std::string interval = shown(s.p50_ci.lower) + " .. " + shown(s.p50_ci.upper);
    const double spread = spread_of(s);
    std::snprintf(line, sizeof line, "  %-18s %10s %23s %10s %10s %9s\n",
                  (f.name + " (" + f.unit + ")").c_str(), shown(s.p50).c_str(), interval.c_str(),
                  shown(s.min).c_str(), shown(s.max).c_str(),
                  std::isfinite(spread) ? (shown(spread) + "%").c_str() : "?");
    out << line;
  }
  return out.str();
}

nlohmann::json series_json(const Series& series) {
  nlohmann::json figures = nlohmann::json::object();
  for (const auto& f : series.figures()) {
    const metrics::SampleStats s = f.stats();
    figures[f.name] = {
        {"unit", f.unit},
        {"runs", s.count},
        {"median", finite_or_null(s.p50)},
        {"median_ci95", {finite_or_null(s.p50_ci.lower), finite_or_null(s.p50_ci.upper)}},
        {"min", finite_or_null(s.min)},
        {"max", finite_or_null(s.max)},
        {"spread_percent", finite_or_null(spread_of(s))},
        {"values", f.values}};
  }
  nlohmann::json summary = {{"schema", "robotperf.series/1"}, {"benchmark", series.benchmark_id()},
                            {"runs", series.runs()},          {"valid_runs", series.valid_runs()},
                            {"files", series.files()},        {"figures", figures}};
  series.completed().add_to(summary);
  return summary;
}

}  // namespace robotperf::report
