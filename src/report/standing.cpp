#include "robotperf/report/standing.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "robotperf/report/run_store.hpp"

namespace robotperf::report {
namespace {

bool same_rate(double a, double b) {
  return std::fabs(a - b) <= 1e-6 * std::max(1.0, b);
}

// The rates a published row of this run's benchmark may state for it: the input rate, or a
// control loop's update rate (RobotPerf's control rows state the controller's).
bool at_the_run_rate(const PublishedResult& row, const harness::RunResult& run) {
  if (!row.note_rate_hz || row.note_rate_hz->first != row.note_rate_hz->second) return false;
  const double hz = row.note_rate_hz->first;
  if (same_rate(hz, run.rate_hz)) return true;
  return std::ranges::any_of(run.control_loops,
                             [&](const auto& loop) { return same_rate(hz, loop.update_rate_hz); });
}

double median(std::vector<double> v) {
  std::ranges::sort(v);
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : (v[n / 2 - 1] + v[n / 2]) / 2;
}

}  // namespace

std::string published_standing(const harness::RunResult& run,
                               const std::vector<PublishedBenchmark>& published) {
  if (run.matched == 0 || !std::isfinite(run.latency_from_scheduled.max)) return {};
  std::map<std::string, std::vector<double>> by_platform;
  std::string rate;  // as the rows state it
  for (const auto& benchmark : published) {
    if (benchmark.id != run.benchmark_id && benchmark.name != run.benchmark_name) continue;
    for (const auto& row : benchmark.results) {
      if (row.metric != "latency" || row.type != "black" || !row.flags.empty() ||
          !(row.value > 0) || !at_the_run_rate(row, run))
        continue;
      by_platform[row.hardware].push_back(row.value);
      rate = row.stated_rate();
    }
  }
  if (by_platform.empty()) return {};
  const double ours = run.latency_from_scheduled.max / 1e6;
  std::size_t slower = 0;
  double fastest = std::numeric_limits<double>::infinity();
  std::vector<double> medians;
  for (const auto& platform : by_platform) {
    const double m = median(platform.second);
    medians.push_back(m);
    slower += m > ours;
    fastest = std::min(fastest, m);
  }
  const std::size_t n = by_platform.size();
  return "RobotPerf max " + format_fixed(ours, 3) + " ms: lower than " + std::to_string(slower) +
         " of " + std::to_string(n) + " published platform" + (n == 1 ? "" : "s") +
         " (black-box, " + rate + "; best " + format_fixed(fastest, 3) + " ms, median " +
         format_fixed(median(medians), 3) + " ms)";
}

}  // namespace robotperf::report
