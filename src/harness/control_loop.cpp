#include "control_loop.hpp"

namespace robotperf::harness {
namespace {

using nlohmann::json;

json stats_to_wire(const metrics::SampleStats& s) {
  // NaN (no samples) goes out as null.
  return metrics::to_json(s);
}

metrics::SampleStats stats_from_wire(const json& j) {
  auto value = [&](const char* key) {
    const auto& v = j.at(key);
    return v.is_null() ? metrics::SampleStats::kNoValue : v.get<double>();
  };
  metrics::SampleStats s;
  s.count = j.at("count").get<std::size_t>();
  s.min = value("min");
  s.mean = value("mean");
  s.rms = value("rms");
  s.stddev = value("stddev");
  s.p50 = value("p50");
  s.p90 = value("p90");
  s.p99 = value("p99");
  s.p999 = value("p999");
  s.max = value("max");
  return s;
}

}  // namespace

ControlLoopResult control_loop_timing(const plugin::LoopReport& loop) {
  ControlLoopResult c;
  c.node = loop.name;
  c.update_rate_hz = loop.update_rate_hz;
  c.cpu = loop.cpu;
  c.rt_priority = loop.rt_priority;
  c.cycles = loop.cycles;
  c.recorded_cycles = loop.records.size();
  c.deadline_misses = loop.deadline_misses;
  const double period_ns = 1e9 / loop.update_rate_hz;
  const std::size_t n = loop.records.size();
  std::vector<double> update, cycle, jitter, wake;
  update.reserve(n);
  cycle.reserve(n);
  jitter.reserve(n);
  wake.reserve(n);
  for (std::size_t k = 0; k < n; ++k) {
    const auto& rec = loop.records[k];
    update.push_back(static_cast<double>(rec.update_end_ns - rec.read_end_ns));
    cycle.push_back(static_cast<double>(rec.write_end_ns - rec.wake_ns));
    wake.push_back(static_cast<double>(rec.wake_ns - rec.deadline_ns));
    if (k > 0)
      jitter.push_back(static_cast<double>(rec.wake_ns - loop.records[k - 1].wake_ns) - period_ns);
  }
  c.update_duration = metrics::compute_stats(update);
  c.cycle_duration = metrics::compute_stats(cycle);
  c.period_jitter = metrics::compute_stats(jitter);
  c.wake_latency = metrics::compute_stats(wake);
  return c;
}

metrics::SampleStats command_to_write(const std::vector<plugin::CommandWrite>& writes,
                                      const MessageIds& ids,
                                      const std::vector<MessageRecord>& records,
                                      std::size_t warmup) {
  std::vector<double> to_write;
  for (const auto& w : writes) {
    const auto id = ids.id_of(w.command_id);
    if (!id || *id < warmup || *id >= records.size()) continue;
    to_write.push_back(static_cast<double>(w.write_end_ns - records[*id].scheduled_ns));
  }
  return metrics::compute_stats(to_write);
}

json control_loop_to_wire(const plugin::LoopReport& loop) {
  const ControlLoopResult c = control_loop_timing(loop);
  json writes = json::array();
  for (const auto& w : loop.writes) writes.push_back({w.command_id, w.write_end_ns});
  return {{"node", c.node},
          {"update_rate_hz", c.update_rate_hz},
          {"cpu", c.cpu},
          {"rt_priority", c.rt_priority},
          {"cycles", c.cycles},
          {"recorded_cycles", c.recorded_cycles},
          {"deadline_misses", c.deadline_misses},
          {"update_duration_ns", stats_to_wire(c.update_duration)},
          {"cycle_duration_ns", stats_to_wire(c.cycle_duration)},
          {"period_jitter_ns", stats_to_wire(c.period_jitter)},
          {"wake_latency_ns", stats_to_wire(c.wake_latency)},
          {"writes", writes}};
}

ControlLoopResult control_loop_from_wire(const json& wire, const MessageIds& ids,
                                         const std::vector<MessageRecord>& records,
                                         std::size_t warmup) {
  ControlLoopResult c;
  c.node = wire.at("node").get<std::string>();
  c.update_rate_hz = wire.at("update_rate_hz").get<double>();
  c.cpu = wire.at("cpu").get<int>();
  c.rt_priority = wire.at("rt_priority").get<int>();
  c.cycles = wire.at("cycles").get<uint64_t>();
  c.recorded_cycles = wire.at("recorded_cycles").get<uint64_t>();
  c.deadline_misses = wire.at("deadline_misses").get<uint64_t>();
  c.update_duration = stats_from_wire(wire.at("update_duration_ns"));
  c.cycle_duration = stats_from_wire(wire.at("cycle_duration_ns"));
  c.period_jitter = stats_from_wire(wire.at("period_jitter_ns"));
  c.wake_latency = stats_from_wire(wire.at("wake_latency_ns"));
  std::vector<plugin::CommandWrite> writes;
  for (const auto& w : wire.at("writes"))
    writes.push_back({w.at(0).get<int64_t>(), w.at(1).get<int64_t>()});
  // The writes are times of the child's CLOCK_MONOTONIC: against the runner's send times only on
  // the runner's machine (another machine's clock counts from its own boot).
  if (wire.value("same_machine", true))
    c.command_to_write = command_to_write(writes, ids, records, warmup);
  return c;
}

}  // namespace robotperf::harness
