#include "backend_row.hpp"

#include <map>

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
  std::string text = ">= " + std::to_string(static_cast<int>(t->second)) + "x";
  bool met = cpu.p50_ms / cuda.p50_ms >= t->second;
  if (id == "a1") {
    text += ", p50 <= 1 ms";
    met = met && cuda.p50_ms <= 1.0;
  }
  if (!cpu.valid || !cuda.valid) return text + ": not judged (an invalid run)";
  return text + (met ? ": met" : ": NOT met");
}

}  // namespace robotperf::bench
