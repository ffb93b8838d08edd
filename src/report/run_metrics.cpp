#include "robotperf/report/run_metrics.hpp"

#include <cmath>

namespace robotperf::report {

namespace {

using nlohmann::json;

double number(const json& j) {
  return j.is_number() ? j.get<double>() : std::nan("");
}

// A latency block of the results file (robotperf's statistics, in ms) as metrics "<prefix>.<stat>",
// each percentile with its distribution-free 95 % interval.
void latency_metrics(const json& block, const std::string& prefix, std::vector<RunMetric>& out) {
  for (const char* stat : {"min", "mean", "rms", "stddev", "p50", "p90", "p99", "p999", "max"}) {
    RunMetric m{prefix + "." + stat, number(member(block, stat)), "ms"};
    m.better = RunMetric::Better::kSmaller;
    const json& interval = member(block, (std::string(stat) + "_ci95").c_str());
    if (interval.is_array() && interval.size() == 2) {
      m.low = number(interval[0]);
      m.high = number(interval[1]);
    }
    out.push_back(std::move(m));
  }
}

}  // namespace

std::vector<RunMetric> run_metrics(const StoredRun& run) {
  std::vector<RunMetric> out;
  const json& latency = member(run.json, "latency_ms");
  latency_metrics(member(latency, "from_scheduled"), "latency", out);
  latency_metrics(member(latency, "from_sent"), "latency_from_sent", out);
  latency_metrics(member(latency, "send_lateness"), "send_lateness", out);
  const json& counts = member(run.json, "counts");
  for (const char* count :
       {"sent", "measured", "matched", "lost", "unobserved", "duplicates", "unknown", "foreign"})
    out.push_back({std::string("count.") + count, number(member(counts, count)), "messages"});
  constexpr auto smaller = RunMetric::Better::kSmaller, larger = RunMetric::Better::kLarger;
  out.push_back({"loss", run.loss_percent, "%", kNoValue, kNoValue, smaller});
  out.push_back({"throughput", run.throughput_hz, "Hz", kNoValue, kNoValue, larger});
  out.push_back({"throughput.offered", run.offered_hz, "Hz"});
  if (run.power_w) {
    out.push_back({"power", *run.power_w, "W", kNoValue, kNoValue, smaller});
    out.push_back({"energy", run.energy_j.value_or(kNoValue), "J", kNoValue, kNoValue, smaller});
    out.push_back(
        {"energy_per_message",
         number(member(member(member(run.json, "power"), "total"), "energy_per_message_mj")), "mJ",
         kNoValue, kNoValue, smaller});
  }
  if (run.cpu_percent)
    out.push_back({"cpu", *run.cpu_percent, "% of one core", kNoValue, kNoValue, smaller});
  if (run.peak_rss_mib)
    out.push_back({"peak_rss", *run.peak_rss_mib, "MiB", kNoValue, kNoValue, smaller});
  if (run.update_rate_hz) out.push_back({"control.update_rate", *run.update_rate_hz, "Hz"});
  const json& functional = member(member(run.json, "functional"), "metrics");
  if (functional.is_object()) {
    for (const auto& [name, metric] : functional.items()) {
      const json& unit = member(metric, "unit");
      const auto better = member(metric, "max").is_number()   ? smaller
                          : member(metric, "min").is_number() ? larger
                                                              : RunMetric::Better::kUnknown;
      out.push_back({"functional." + name, number(member(metric, "value")),
                     unit.is_string() ? unit.get<std::string>() : "", kNoValue, kNoValue, better});
    }
  }
  return out;
}

std::string better_text(RunMetric::Better better) {
  switch (better) {
    case RunMetric::Better::kSmaller:
      return "smaller";
    case RunMetric::Better::kLarger:
      return "larger";
    case RunMetric::Better::kUnknown:
      break;
  }
  return "";
}

RunMetric::Better better_from_text(const std::string& text) {
  if (text == "smaller") return RunMetric::Better::kSmaller;
  if (text == "larger") return RunMetric::Better::kLarger;
  return RunMetric::Better::kUnknown;
}

std::optional<RunMetric> run_metric(const StoredRun& run, const std::string& name) {
  for (RunMetric& m : run_metrics(run)) {
    if (m.name == name && std::isfinite(m.value)) return std::move(m);
  }
  return std::nullopt;
}

}  // namespace robotperf::report
