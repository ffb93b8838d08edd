#include "robotperf/report/results.hpp"

#include <cmath>
#include <cstdio>
#include <ctime>
#include <sstream>

#include "robotperf/build_info.hpp"
#include "robotperf/report/histogram.hpp"

namespace robotperf::report {
namespace {

constexpr double kNsPerMs = 1e6;

std::string utc_time(int64_t unix_ns, const char* format) {
  const std::time_t seconds = static_cast<std::time_t>(unix_ns / 1'000'000'000);
  std::tm tm{};
  gmtime_r(&seconds, &tm);
  char buf[64];
  std::strftime(buf, sizeof buf, format, &tm);
  return buf;
}

std::string fixed(double v, int decimals) {
  if (!std::isfinite(v)) return "-";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

}  // namespace

nlohmann::json software_json() {
  return {{"robotperf_version", build_info::kVersion},
          {"git_revision", build_info::kGitRevision},
          {"compiler", build_info::kCompiler},
          {"build_type", build_info::kBuildType},
          {"cxx_flags", build_info::kCxxFlags},
          {"sanitized", build_info::kSanitized},
          {"libraries",
           {{"fastdds", build_info::kFastDdsVersion}, {"opencv", build_info::kOpenCvVersion}}}};
}

nlohmann::json result_to_json(const harness::RunResult& r, const sysinfo::MachineInfo& machine) {
  using nlohmann::json;
  json nodes = json::array();
  for (const auto& n : r.nodes) {
    json node = {{"name", n.name}, {"kernel", n.kernel}, {"exit_status", n.exit_status}};
    if (n.pid > 0) node["pid"] = n.pid;
    node["cpu_user_s"] = n.cpu_user_s >= 0 ? json(n.cpu_user_s) : json(nullptr);
    node["cpu_system_s"] = n.cpu_system_s >= 0 ? json(n.cpu_system_s) : json(nullptr);
    nodes.push_back(std::move(node));
  }
  // The RobotPerf headline is the maximum latency, taken from the same block so the two agree
  // exactly.
  const json from_scheduled = metrics::to_json(r.latency_from_scheduled, 1.0 / kNsPerMs, "ms");
  // The distribution itself, compactly, so that a report can draw it without the CSV.
  std::vector<double> latencies_ms;
  latencies_ms.reserve(r.records.size());
  for (const auto& rec : r.records) {
    if (!rec.warmup && rec.received_ns >= 0)
      latencies_ms.push_back(static_cast<double>(rec.received_ns - rec.scheduled_ns) / kNsPerMs);
  }
  return {
      {"schema", kResultSchema},
      {"benchmark", {{"id", r.benchmark_id}, {"name", r.benchmark_name}, {"category", r.category}}},
      {"type", "black"},
      {"started_utc", utc_time(r.started_unix_ns, "%Y-%m-%dT%H:%M:%SZ")},
      {"configuration",
       {{"rate_hz", r.rate_hz},
        {"count", r.count},
        {"warmup", r.warmup},
        {"drain_s", r.drain_s},
        {"rmw", r.rmw},
        {"processes", r.processes},
        {"executor_threads", r.executor_threads},
        {"output_topic", r.output_topic}}},
      {"dataset", {{"name", r.dataset}, {"hash", r.dataset_hash}, {"frames", r.dataset_frames}}},
      {"machine", sysinfo::to_json(machine)},
      {"software", software_json()},
      {"counts",
       {{"sent", r.sent},
        {"measured", r.measured},
        {"matched", r.matched},
        {"lost", r.lost},
        {"loss_percent", r.loss_percent},
        {"duplicates", r.duplicates},
        {"unknown", r.unknown}}},
      {"latency_ms",
       {{"from_scheduled", from_scheduled},
        {"from_sent", metrics::to_json(r.latency_from_sent, 1.0 / kNsPerMs, "ms")},
        {"send_lateness", metrics::to_json(r.send_lateness, 1.0 / kNsPerMs, "ms")},
        {"from_scheduled_histogram", to_json(make_log_histogram(latencies_ms))}}},
      {"headline", {{"latency_ms", from_scheduled["max"]}, {"throughput_hz", r.throughput_hz}}},
      {"throughput",
       {{"output_hz", r.throughput_hz},
        {"offered_hz", r.offered_rate_hz},
        {"window_s", r.window_s}}},
      {"nodes", nodes},
      {"completed", r.completed},
      {"errors", r.errors},
      {"validity", {{"valid", r.valid}, {"reasons", r.invalid_reasons}}},
  };
}

std::string latencies_csv(const harness::RunResult& r) {
  std::ostringstream out;
  out << "id,warmup,scheduled_ns,sent_ns,received_ns,latency_scheduled_ns,latency_sent_ns\n";
  for (const auto& rec : r.records) {
    out << rec.id << ',' << (rec.warmup ? 1 : 0) << ',' << rec.scheduled_ns << ',' << rec.sent_ns
        << ',';
    if (rec.received_ns >= 0) {
      out << rec.received_ns << ',' << rec.received_ns - rec.scheduled_ns << ','
          << rec.received_ns - rec.sent_ns;
    } else {
      out << ",,";
    }
    out << '\n';
  }
  return out.str();
}

std::string summary_table(const harness::RunResult& r) {
  std::ostringstream out;
  out << r.benchmark_id << " (" << r.benchmark_name << ") · " << r.rmw << " · " << r.processes
      << " process" << (r.processes == "single" ? "" : "es") << " · " << fixed(r.rate_hz, 1)
      << " Hz · dataset " << r.dataset << "\n";
  out << "messages: sent " << r.sent << " (warm-up " << r.warmup << "), measured " << r.measured
      << ", matched " << r.matched << ", lost " << r.lost << " (" << fixed(r.loss_percent, 2)
      << " %)";
  if (r.duplicates) out << ", duplicates " << r.duplicates;
  if (r.unknown) out << ", unknown " << r.unknown;
  out << "\n\n";
  char line[256];
  std::snprintf(line, sizeof line, "%-24s %9s %9s %9s %9s %9s %9s %9s %9s\n", "latency (ms)", "min",
                "mean", "rms", "p50", "p90", "p99", "p99.9", "max");
  out << line;
  auto row = [&](const char* name, const metrics::SampleStats& s) {
    auto v = [](double ns) { return fixed(ns / kNsPerMs, 3); };
    std::snprintf(line, sizeof line, "%-24s %9s %9s %9s %9s %9s %9s %9s %9s\n", name,
                  v(s.min).c_str(), v(s.mean).c_str(), v(s.rms).c_str(), v(s.p50).c_str(),
                  v(s.p90).c_str(), v(s.p99).c_str(), v(s.p999).c_str(), v(s.max).c_str());
    out << line;
  };
  row("from scheduled send", r.latency_from_scheduled);
  row("from actual send", r.latency_from_sent);
  row("send lateness", r.send_lateness);
  out << "\nthroughput: " << fixed(r.throughput_hz, 3) << " Hz out, " << fixed(r.offered_rate_hz, 3)
      << " Hz offered\n";
  out << "headline (RobotPerf): latency " << fixed(r.latency_from_scheduled.max / kNsPerMs, 3)
      << " ms (max), throughput " << fixed(r.throughput_hz, 3) << " Hz\n";
  for (const auto& e : r.errors) out << "error: " << e << "\n";
  out << "result: " << (r.valid ? "VALID" : "INVALID");
  for (std::size_t i = 0; i < r.invalid_reasons.size(); ++i) {
    out << (i == 0 ? " — " : "; ") << r.invalid_reasons[i];
  }
  out << "\n";
  return out.str();
}

std::string result_basename(const harness::RunResult& r) {
  char ms[8];
  std::snprintf(ms, sizeof ms, "%03d", static_cast<int>((r.started_unix_ns / 1'000'000) % 1000));
  return r.benchmark_id + "-" + r.rmw + "-" + utc_time(r.started_unix_ns, "%Y%m%dT%H%M%S") + ms +
         "Z";
}

}  // namespace robotperf::report
