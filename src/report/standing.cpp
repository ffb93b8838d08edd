#include "robotperf/report/standing.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "robotperf/metrics/latency_stats.hpp"
#include "robotperf/report/run_store.hpp"

namespace robotperf::report {
namespace {

bool same_rate(double a, double b) {
  return std::fabs(a - b) <= 1e-6 * std::max(1.0, b);
}

}  // namespace

std::optional<Standing> standing_among(double max_ms, const std::string& id,
                                       const std::string& name, const std::vector<double>& rates_hz,
                                       const std::vector<PublishedBenchmark>& published) {
  if (!std::isfinite(max_ms)) return std::nullopt;
  Standing s;
  s.value_ms = max_ms;
  std::map<std::string, std::vector<double>> by_platform;
  for (const auto& benchmark : published) {
    if (benchmark.id != id && benchmark.name != name) continue;
    for (const auto& row : benchmark.results) {
      if (row.metric != "latency" || row.type != "black" || !row.flags.empty() ||
          !(row.value > 0) || !row.note_rate_hz ||
          row.note_rate_hz->first != row.note_rate_hz->second ||
          std::ranges::none_of(rates_hz,
                               [&](double hz) { return same_rate(row.note_rate_hz->first, hz); }))
        continue;
      by_platform[row.hardware].push_back(row.value);
      ++s.rows;
      s.rate = row.stated_rate();
    }
  }
  if (by_platform.empty()) return std::nullopt;
  s.platforms = by_platform.size();
  s.best_ms = std::numeric_limits<double>::infinity();
  std::vector<double> medians;
  for (const auto& [platform, values] : by_platform) {
    const double m = metrics::median(values);
    medians.push_back(m);
    s.slower += m > max_ms;
    if (m < s.best_ms) {
      s.best_ms = m;
      s.best_platform = platform;
    }
  }
  s.median_ms = metrics::median(medians);
  return s;
}

std::string published_standing(const harness::RunResult& run,
                               const std::vector<PublishedBenchmark>& published) {
  if (run.matched == 0) return {};
  std::vector<double> rates = {run.rate_hz};
  for (const auto& loop : run.control_loops) rates.push_back(loop.update_rate_hz);
  const auto s = standing_among(run.latency_from_scheduled.max / 1e6, run.benchmark_id,
                                run.benchmark_name, rates, published);
  if (!s) return {};
  return "RobotPerf max " + format_fixed(s->value_ms, 3) + " ms: lower than " +
         std::to_string(s->slower) + " of " + std::to_string(s->platforms) + " published platform" +
         (s->platforms == 1 ? "" : "s") + " (black-box, " + s->rate + "; best " +
         format_fixed(s->best_ms, 3) + " ms, median " + format_fixed(s->median_ms, 3) + " ms)";
}

}  // namespace robotperf::report
