#include "measurement.hpp"

#include <chrono>
#include <thread>

#include "robotperf/build_info.hpp"
#include "robotperf/metrics/latency_stats.hpp"
#include "robotperf/rmw/transport.hpp"

namespace robotperf::harness {
namespace {

metrics::PowerMeter make_meter(const metrics::PowerOptions& options) {
  auto found = metrics::discover_power_sources(options);
  return metrics::PowerMeter(std::move(found.sources), std::move(found.notes));
}

}  // namespace

WindowMeasurement::WindowMeasurement(const RunOptions& options,
                                     std::vector<metrics::ResourceMonitor::Process> graph)
    : graph_(graph),
      meter_(make_meter(options.power)),
      resources_("/proc", std::move(graph)),
      sampler_(meter_, options.power.period) {
  // Resources are read on the sampling thread at the power window's two ends: one window for all.
  sampler_.on_window_edges([this](int64_t t) { resources_.begin(t); },
                           [this](int64_t t) { resources_.end(t); });
}

void WindowMeasurement::begin() {
  sampler_.begin();
}

void WindowMeasurement::end(RunResult& r) {
  r.power = sampler_.end();
  r.resources = resources_.usage();
}

std::optional<double> WindowMeasurement::probe_other_load() const {
  metrics::ResourceMonitor probe("/proc", graph_);
  probe.begin(rmw::steady_now_ns());
  std::this_thread::sleep_for(std::chrono::milliseconds(250));
  probe.end(rmw::steady_now_ns());
  return probe.usage().other_cpu_percent;
}

std::vector<sysinfo::RunWarning> check_run_rules_for(const RunResult& r,
                                                     std::optional<double> other_load_percent) {
  sysinfo::RunRuleInputs in;
  in.machine = sysinfo::collect_machine_info();
  in.build_type = build_info::kBuildType;
  in.sanitized = build_info::kSanitized;
  in.measured_messages = r.count - r.warmup;
  in.samples_for_p99_bound = metrics::samples_for_upper_bound(0.99);
  in.other_load_percent = other_load_percent;
  in.grey_box = !r.trace_dir.empty();  // set when the grey-box recording started
  return sysinfo::check_run_rules(in);
}

}  // namespace robotperf::harness
