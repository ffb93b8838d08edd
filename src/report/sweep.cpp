#include "robotperf/report/sweep.hpp"

#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "robotperf/metrics/latency_stats.hpp"
#include "robotperf/report/results.hpp"
#include "robotperf/report/run_store.hpp"

namespace robotperf::report {
namespace {

constexpr double kNsPerMs = 1e6;

std::string ms(double ns) {
  return std::isfinite(ns) ? format_fixed(ns / kNsPerMs, 4) : "?";
}

}  // namespace

Sweep::Sweep(std::string benchmark_id, std::string parameter, std::size_t planned_runs)
    : benchmark_id_(std::move(benchmark_id)),
      parameter_(std::move(parameter)),
      completed_{planned_runs, ""} {}

void Sweep::add(const std::string& value, const harness::RunResult& run,
                const std::optional<std::filesystem::path>& json) {
  SweepRow row;
  row.value = value;
  row.valid = run.valid;
  if (json) row.file = json->string();
  row.latency_ns = run.latency_from_scheduled;
  row.loss_percent = run.loss_percent;
  row.throughput_hz = run.throughput_hz;
  for (const auto& p : run.resources.processes) {
    if (p.measured) row.cpu_percent.emplace_back(p.label, p.cpu_percent);
  }
  rows_.push_back(std::move(row));
}

std::pair<std::string, std::vector<std::string>> parse_sweep(const std::string& text) {
  const auto equals = text.find('=');
  if (equals == std::string::npos || equals == 0 || equals + 1 == text.size()) {
    throw std::invalid_argument("--sweep " + text +
                                ": expected KEY=V1,V2,... (a workload "
                                "parameter and its values)");
  }
  std::vector<std::string> values;
  std::stringstream list(text.substr(equals + 1));
  for (std::string value; std::getline(list, value, ',');) {
    if (value.empty()) throw std::invalid_argument("--sweep " + text + ": an empty value");
    values.push_back(value);
  }
  return {text.substr(0, equals), values};
}

std::string sweep_table(const Sweep& sweep) {
  std::ostringstream out;
  out << "sweep " << sweep.benchmark_id() << " over " << sweep.parameter() << ": "
      << sweep.rows().size() << " runs" << sweep.completed().note(sweep.rows().size())
      << "; latency from the scheduled send, ms (for a ping-pong: "
      << "the round trip on the ping side's clock; p50/2 is half of it)\n";
  char line[256];
  std::snprintf(line, sizeof line, "  %12s %9s %9s %9s %9s %9s %9s %7s %9s  %s\n",
                sweep.parameter().c_str(), "p50", "p90", "p99", "p99.9", "max", "p50/2", "loss%",
                "msgs/s", "CPU (% of a core)");
  out << line;
  for (const SweepRow& r : sweep.rows()) {
    std::string cpu;
    for (const auto& [label, percent] : r.cpu_percent) {
      cpu += (cpu.empty() ? "" : ", ") + label + " " + format_fixed(percent, 1);
    }
    const metrics::SampleStats& l = r.latency_ns;
    std::snprintf(line, sizeof line, "  %12s %9s %9s %9s %9s %9s %9s %7s %9s  %s%s\n",
                  r.value.c_str(), ms(l.p50).c_str(), ms(l.p90).c_str(), ms(l.p99).c_str(),
                  ms(l.p999).c_str(), ms(l.max).c_str(), ms(l.p50 / 2).c_str(),
                  format_fixed(r.loss_percent, 2).c_str(), format_fixed(r.throughput_hz, 1).c_str(),
                  cpu.c_str(), r.valid ? "" : "  INVALID");
    out << line;
  }
  return out.str();
}

nlohmann::json sweep_json(const Sweep& sweep) {
  nlohmann::json rows = nlohmann::json::array();
  for (const SweepRow& r : sweep.rows()) {
    nlohmann::json cpu = nlohmann::json::object();
    for (const auto& [label, percent] : r.cpu_percent) cpu[label] = finite_or_null(percent);
    const metrics::SampleStats& l = r.latency_ns;
    // As a results file writes its latency (metrics::to_json), plus half the median: the one-way
    // figure of a ping-pong.
    nlohmann::json latency = metrics::to_json(l, 1.0 / kNsPerMs, "ms");
    latency["half_p50"] = finite_or_null(l.p50 / kNsPerMs / 2);
    rows.push_back({{"value", r.value},
                    {"valid", r.valid},
                    {"file", r.file.empty() ? nlohmann::json(nullptr) : nlohmann::json(r.file)},
                    {"latency_ms", latency},
                    {"loss_percent", finite_or_null(r.loss_percent)},
                    {"throughput_hz", finite_or_null(r.throughput_hz)},
                    {"cpu_percent", cpu}});
  }
  nlohmann::json summary = {{"schema", "robotperf.sweep/1"},
                            {"benchmark", sweep.benchmark_id()},
                            {"parameter", sweep.parameter()},
                            {"runs", rows}};
  sweep.completed().add_to(summary);
  return summary;
}

}  // namespace robotperf::report
