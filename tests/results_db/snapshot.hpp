// What a results database holds, through its queries, keyed by results file: two databases hold
// the same runs when their snapshots are equal, whatever ids their rows got.
#pragma once

#include <nlohmann/json.hpp>

#include "robotperf/results_db/results_db.hpp"

namespace robotperf::results_db::testing {

inline nlohmann::json snapshot(const Database& db) {
  nlohmann::json out = nlohmann::json::object();
  for (const RunRow& r : db.runs()) {
    nlohmann::json run = {{"benchmark", {r.benchmark_id, r.benchmark_name, r.category}},
                          {"started_utc", r.started_utc},
                          {"valid", r.valid},
                          {"how",
                           {r.mode, r.rmw, r.processes, r.backend, r.arrivals, r.monitor_wait,
                            r.rate_hz ? *r.rate_hz : -1.0}},
                          {"provenance", {r.hardware, r.robotperf_version, r.git_revision}},
                          {"configuration_key", r.configuration_key},
                          {"samples_source", r.samples_source},
                          {"labels", db.labels(r.id)},
                          {"samples_ns", db.samples_ns(r.id)}};
    for (const MetricRow& m : db.metrics(r.id)) {
      run["metrics"][m.name] = {m.value, m.unit, m.low ? nlohmann::json(*m.low) : nullptr,
                                m.high ? nlohmann::json(*m.high) : nullptr};
    }
    for (const HistogramBin& b : db.histogram(r.id)) {
      run["histogram"].push_back(
          {b.lower_ns ? nlohmann::json(*b.lower_ns) : nullptr, b.upper_ns, b.count});
    }
    out[r.file] = std::move(run);
  }
  return out;
}

}  // namespace robotperf::results_db::testing
