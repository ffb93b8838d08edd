// Results files for report tests, written by the real results writer from synthetic runs.
#pragma once

#include <cmath>
#include <filesystem>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "robotperf/files/atomic_file.hpp"
#include "robotperf/report/results.hpp"

namespace robotperf::report::testing {

struct SampleRun {
  std::string id = "a1";
  std::string name = "a1_perception_2nodes";
  std::string rmw = "intra";
  std::string cpu = "AMD Ryzen 7 5800X 8-Core Processor";
  std::string gpu{};             // NVIDIA model, empty for none
  double base_latency_ms = 5.0;  // latencies spread from base to about 2x base
  std::size_t messages = 100;
  std::size_t lost = 0;
  int64_t start_unix_ns = 1'790'000'000'000'000'000;
  std::vector<std::pair<std::string, std::string>> warnings{};  // run rules: (rule, message)
  std::map<std::string, std::string> labels{};                  // run --label
};

inline harness::RunResult make_run(const SampleRun& s) {
  harness::RunResult r;
  r.benchmark_id = s.id;
  r.benchmark_name = s.name;
  r.category = "perception";
  r.labels = s.labels;
  for (const auto& [rule, message] : s.warnings) r.warnings.push_back({rule, message});
  r.rate_hz = 30;
  r.count = s.messages + 5;
  r.warmup = 5;
  r.drain_s = 2;
  r.rmw = s.rmw;
  r.processes = "single";
  r.output_topic = "/resize/image";
  r.dataset = "perception/image";
  r.dataset_hash = "fnv1a64:0123456789abcdef";
  r.dataset_frames = 68;
  r.started_unix_ns = s.start_unix_ns;
  std::vector<double> from_scheduled, from_sent, lateness;
  const int64_t period = 33'333'333;
  for (std::size_t k = 0; k < r.count; ++k) {
    harness::MessageRecord rec;
    rec.id = k;
    rec.warmup = k < r.warmup;
    rec.scheduled_ns = 1'000'000'000 + static_cast<int64_t>(k) * period;
    rec.sent_ns = rec.scheduled_ns + 20'000;
    const bool lost = !rec.warmup && k >= r.count - s.lost;
    // A deterministic spread: base .. 2 base, with a tail.
    const double frac = static_cast<double>((k * 37) % 100) / 100.0;
    const double latency_ms = s.base_latency_ms * (1.0 + frac * frac);
    rec.received_ns = lost ? -1 : rec.scheduled_ns + static_cast<int64_t>(latency_ms * 1e6);
    lateness.push_back(20'000);
    if (!rec.warmup) {
      ++r.measured;
      if (!lost) {
        ++r.matched;
        from_scheduled.push_back(static_cast<double>(rec.received_ns - rec.scheduled_ns));
        from_sent.push_back(static_cast<double>(rec.received_ns - rec.sent_ns));
      }
    }
    r.records.push_back(rec);
  }
  r.sent = r.records.size();
  r.lost = r.measured - r.matched;
  r.loss_percent = 100.0 * static_cast<double>(r.lost) / static_cast<double>(r.measured);
  r.latency_from_scheduled = metrics::compute_stats(from_scheduled);
  r.latency_from_sent = metrics::compute_stats(from_sent);
  r.send_lateness = metrics::compute_stats(lateness);
  r.throughput_hz = 30.0;
  r.offered_rate_hz = 30.0;
  r.window_s = static_cast<double>(r.measured) / 30.0;
  r.completed = true;
  r.valid = r.lost == 0;
  if (!r.valid) r.invalid_reasons.push_back("lost messages");
  harness::NodeReport node;
  node.name = "rectify";
  node.kernel = "image_proc/rectify";
  node.exit_status = "ok";
  r.nodes.push_back(node);
  return r;
}

inline sysinfo::MachineInfo make_machine(const SampleRun& s) {
  sysinfo::MachineInfo m;
  m.hostname = "bench-host";
  m.architecture = "x86_64";
  m.cpu_model = s.cpu;
  m.logical_cpus = 16;
  m.physical_cores = 8;
  m.memory_total_bytes = 32ull << 30;
  m.kernel_release = "6.1.0-18-amd64";
  if (!s.gpu.empty()) {
    sysinfo::GpuInfo g;
    g.source = "nvidia";
    g.model = s.gpu;
    m.gpus.push_back(g);
  }
  return m;
}

// Writes <dir>/<basename>.json (and the CSV when `csv`); returns the JSON path. `power_w` > 0
// adds a power section as the metrics piece writes it.
inline std::filesystem::path write_sample(const std::filesystem::path& dir, const SampleRun& s,
                                          bool csv = false, double power_w = 0) {
  const auto run = make_run(s);
  auto j = result_to_json(run, make_machine(s));
  if (power_w > 0) {
    // As the metrics piece writes it (metrics::to_json(PowerReport)).
    j["power"] = {
        {"available", true},
        {"unavailable_reason", nullptr},
        {"total",
         {{"average_w", power_w},
          {"energy_j", power_w * run.window_s},
          {"sources", {"rapl:package-0"}}}},
        {"sources", {{{"name", "rapl:package-0"}, {"available", true}, {"average_w", power_w}}}}};
    j["warnings"] = {{{"rule", "governor"}, {"message", "CPU governor is powersave"}}};
  }
  const auto base = dir / result_basename(run);
  files::write_file_atomically(base.string() + ".json", j.dump(2) + "\n");
  if (csv) files::write_file_atomically(base.string() + ".latencies.csv", latencies_csv(run));
  return base.string() + ".json";
}

}  // namespace robotperf::report::testing
