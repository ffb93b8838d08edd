#include "measurement.hpp"

#include <algorithm>
#include <chrono>
#include <thread>
#include <unordered_map>

#include "process_table.hpp"
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

std::vector<Descendants::Member> Descendants::snapshot() const {
  std::vector<Member> out;
  if (roots_.empty()) return out;
  const std::vector<ProcessEntry> all = list_processes();
  std::unordered_map<pid_t, pid_t> parent;
  for (const auto& p : all) parent[p.pid] = p.ppid;
  for (const auto& p : all) {
    if (std::ranges::count(roots_, p.pid) > 0) continue;
    // Up its ancestry to a root, or to a process that is none of theirs (a parent's parent is
    // older than the child, so the walk ends; the bound guards against a list read mid-change).
    pid_t up = p.ppid;
    for (std::size_t steps = 0; up > 1 && std::ranges::count(roots_, up) == 0 && steps < all.size();
         ++steps) {
      const auto it = parent.find(up);
      up = it == parent.end() ? 0 : it->second;
    }
    if (up <= 1 || std::ranges::count(roots_, up) == 0) continue;
    metrics::ProcessSnapshot counters = metrics::read_process("/proc", p.pid);
    if (counters.ok) out.push_back({up, p.pid, p.start_ticks, std::move(counters)});
  }
  return out;
}

void Descendants::add_to(metrics::ResourceUsage& usage) const {
  if (!usage.measured) return;
  double added_cpu_s = 0;
  for (auto& entry : usage.processes) {
    if (!entry.measured || std::ranges::count(roots_, entry.pid) == 0) continue;
    const auto delta = [](uint64_t before, uint64_t after) {
      return after >= before ? after - before : 0;
    };
    for (const Member& m : last_) {
      if (m.root != entry.pid) continue;
      // Started inside the window: all of it counts.
      metrics::ProcessSnapshot before;
      for (const Member& f : first_) {
        if (f.pid == m.pid && f.start_ticks == m.start_ticks) before = f.counters;
      }
      const double user_s = m.counters.cpu_user_s - before.cpu_user_s;
      const double system_s = m.counters.cpu_system_s - before.cpu_system_s;
      entry.cpu_user_s += user_s;
      entry.cpu_system_s += system_s;
      added_cpu_s += user_s + system_s;
      entry.voluntary_switches += delta(before.voluntary_switches, m.counters.voluntary_switches);
      entry.involuntary_switches +=
          delta(before.involuntary_switches, m.counters.involuntary_switches);
      entry.minor_faults += delta(before.minor_faults, m.counters.minor_faults);
      entry.major_faults += delta(before.major_faults, m.counters.major_faults);
      if (m.counters.peak_rss_bytes)
        entry.peak_rss_bytes = entry.peak_rss_bytes.value_or(0) + *m.counters.peak_rss_bytes;
    }
    entry.cpu_percent = 100.0 * (entry.cpu_user_s + entry.cpu_system_s) / usage.window_s;
  }
  if (usage.other_cpu_percent) {
    usage.other_cpu_percent =
        std::max(0.0, *usage.other_cpu_percent - 100.0 * added_cpu_s / usage.window_s);
  }
}

WindowMeasurement::WindowMeasurement(const RunOptions& options,
                                     std::vector<metrics::ResourceMonitor::Process> graph,
                                     std::vector<pid_t> with_descendants)
    : graph_(graph),
      with_descendants_(with_descendants),
      meter_(make_meter(options.power)),
      resources_("/proc", std::move(graph)),
      descendants_(std::move(with_descendants)),
      sampler_(meter_, options.power.period) {
  // Resources are read on the sampling thread at the power window's two ends: one window for all.
  sampler_.on_window_edges(
      [this](int64_t t) {
        resources_.begin(t);
        descendants_.begin();
      },
      [this](int64_t t) {
        resources_.end(t);
        descendants_.end();
      });
}

void WindowMeasurement::begin() {
  sampler_.begin();
}

void WindowMeasurement::end(RunResult& r) {
  r.power = sampler_.end();
  r.resources = resources_.usage();
  descendants_.add_to(r.resources);
}

std::optional<double> WindowMeasurement::probe_other_load() const {
  metrics::ResourceMonitor probe("/proc", graph_);
  Descendants descendants(with_descendants_);
  probe.begin(rmw::steady_now_ns());
  descendants.begin();
  std::this_thread::sleep_for(std::chrono::milliseconds(250));
  probe.end(rmw::steady_now_ns());
  descendants.end();
  metrics::ResourceUsage usage = probe.usage();
  descendants.add_to(usage);
  return usage.other_cpu_percent;
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
