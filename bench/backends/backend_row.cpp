#include "backend_row.hpp"

#include <algorithm>
#include <cstdio>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "robotperf/metrics/latency_stats.hpp"

namespace robotperf::bench {

BackendRow backend_row(const harness::RunResult& run) {
  BackendRow row;
  row.p50_ms = run.latency_from_sent.p50 / 1e6;
  row.p99_ms = run.latency_from_sent.p99 / 1e6;
  row.loss_percent = run.loss_percent;
  row.reasons = run.invalid_reasons;
  const bool functional_ok = !run.functional || run.functional->valid;
  if (!functional_ok) {
    for (const auto& why : run.functional->reasons)
      row.reasons.push_back("functional (" + run.functional->evaluator + "): " + why);
  }
  row.valid = run.valid && functional_ok;
  return row;
}

namespace {

std::string times(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%.2fx", x);
  return text;
}

}  // namespace

BackendRow combined(const std::vector<BackendRow>& runs) {
  if (runs.empty()) throw std::invalid_argument("combined: no runs");
  if (runs.size() == 1) return runs.front();
  BackendRow row;
  std::vector<double> p50, p99;
  row.valid = true;
  for (std::size_t k = 0; k < runs.size(); ++k) {
    const BackendRow& r = runs[k];
    p50.push_back(r.p50_ms);
    p99.push_back(r.p99_ms);
    row.loss_percent = std::max(row.loss_percent, r.loss_percent);
    row.valid = row.valid && r.valid;
    for (const auto& why : r.reasons)
      row.reasons.push_back("run " + std::to_string(k + 1) + ": " + why);
  }
  row.p50_ms = metrics::median(std::move(p50));
  row.p99_ms = metrics::median(std::move(p99));
  return row;
}

Speedup speedup(const std::vector<BackendRow>& cpu, const std::vector<BackendRow>& backend) {
  if (cpu.empty() || cpu.size() != backend.size()) {
    throw std::invalid_argument("speedup: " + std::to_string(cpu.size()) + " cpu runs and " +
                                std::to_string(backend.size()) + " of the backend's");
  }
  std::vector<double> ratios;
  for (std::size_t k = 0; k < cpu.size(); ++k) ratios.push_back(cpu[k].p50_ms / backend[k].p50_ms);
  std::sort(ratios.begin(), ratios.end());
  Speedup s;
  s.median = metrics::quantile_of_sorted(ratios, 0.5);
  s.least = ratios.front();
  s.most = ratios.back();
  s.pairs = ratios.size();
  return s;
}

std::string cuda_target(const std::string& id, const std::vector<BackendRow>& cpu,
                        const std::vector<BackendRow>& cuda) {
  const std::map<std::string, double> least_speedup = {{"a1", 3}, {"a2", 3}, {"a3", 10}, {"a5", 3}};
  const auto t = least_speedup.find(id);
  if (t == least_speedup.end()) return "-";
  const Speedup s = speedup(cpu, cuda);
  const BackendRow cuda_row = combined(cuda);
  // Each part on its own: a1 can be under 1 ms and not 3x faster.
  std::vector<std::pair<std::string, bool>> parts = {
      {">= " + std::to_string(static_cast<int>(t->second)) + "x", s.median >= t->second}};
  if (id == "a1") parts.emplace_back("p50 <= 1 ms", cuda_row.p50_ms <= 1.0);
  const bool judged = combined(cpu).valid && cuda_row.valid;
  std::string text;
  for (const auto& [target, met] : parts) {
    if (!text.empty()) text += judged ? "; " : ", ";
    text += target;
    if (judged) text += met ? ": met" : ": NOT met";
  }
  if (!judged) return text + ": not judged (an invalid run)";
  if (s.pairs > 1) {
    text += " (medians of " + std::to_string(s.pairs) + " pairs of runs; speed-ups " +
            times(s.least) + " to " + times(s.most) + ")";
  }
  return text;
}

}  // namespace robotperf::bench
