#include "backend_row.hpp"

#include <map>
#include <utility>
#include <vector>

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

std::string cuda_target(const std::string& id, const BackendRow& cpu, const BackendRow& cuda) {
  const std::map<std::string, double> speedup = {{"a1", 3}, {"a2", 3}, {"a3", 10}, {"a5", 3}};
  const auto t = speedup.find(id);
  if (t == speedup.end()) return "-";
  // Each part on its own: a1 can be under 1 ms and not 3x faster.
  std::vector<std::pair<std::string, bool>> parts = {
      {">= " + std::to_string(static_cast<int>(t->second)) + "x",
       cpu.p50_ms / cuda.p50_ms >= t->second}};
  if (id == "a1") parts.emplace_back("p50 <= 1 ms", cuda.p50_ms <= 1.0);
  const bool judged = cpu.valid && cuda.valid;
  std::string text;
  for (const auto& [target, met] : parts) {
    if (!text.empty()) text += judged ? "; " : ", ";
    text += target;
    if (judged) text += met ? ": met" : ": NOT met";
  }
  return judged ? text : text + ": not judged (an invalid run)";
}

}  // namespace robotperf::bench
