#include "robotperf/report/results.hpp"

#include <gnu/libc-version.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <sstream>
#include <tuple>

#include "robotperf/build_info.hpp"
#include "robotperf/git_revision.hpp"
#include "robotperf/report/histogram.hpp"
#include "robotperf/report/run_store.hpp"
#include "robotperf/rmw/security.hpp"

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

// One short line: the figures, the sources in the total; what failed or was estimated is in the
// results file (power.sources, power.estimated).
std::string power_line(const harness::RunResult& r) {
  const auto& p = r.power;
  if (!p.available) {
    // The reason's first clause ("no power source found"); each source's own is in the results.
    const std::string& why = p.unavailable_reason;
    return "power: not measured (" + why.substr(0, why.find(": ")) +
           "; why, per source: the results file's power section)\n";
  }
  std::ostringstream out;
  out << "power: " << format_fixed(p.total_average_w, 2) << " W, "
      << format_fixed(p.total_energy_j, 3) << " J";
  if (r.matched > 0) {
    out << ", " << format_fixed(p.total_energy_j * 1e3 / static_cast<double>(r.matched), 3)
        << " mJ/msg";
  }
  if (r.throughput_hz > 0 && p.total_average_w > 0)
    out << ", " << format_fixed(r.throughput_hz / p.total_average_w, 3) << " msg/s per W";
  std::string parts;
  std::size_t unavailable = 0;
  for (const auto& s : p.sources) {
    unavailable += !s.available;
    if (s.available && s.info.in_total)
      parts +=
          (parts.empty() ? "" : ", ") + s.info.name + " " + format_fixed(s.average_w, 2) + " W";
  }
  out << " (" << parts << ")";
  if (!p.estimated.empty() || unavailable > 0) {
    out << "; " << (p.estimated.empty() ? "" : "partly estimated")
        << (!p.estimated.empty() && unavailable > 0 ? ", " : "")
        << (unavailable > 0 ? std::to_string(unavailable) + " source(s) unavailable" : "")
        << ": see the results file";
  }
  out << "\n";
  return out.str();
}

std::string resources_line(const harness::RunResult& r) {
  const auto& u = r.resources;
  if (!u.measured) return "resources: not measured (the measured window never started)\n";
  std::ostringstream out;
  out << "resources over " << format_fixed(u.window_s, 2) << " s:\n";
  for (const auto& p : u.processes) {
    out << "  " << p.label << " (pid " << p.pid << "): ";
    if (!p.measured) {
      out << p.error << "\n";
      continue;
    }
    out << format_fixed(p.cpu_percent, 1) << " % CPU";
    if (p.peak_rss_bytes) {
      out << ", peak RSS " << format_fixed(static_cast<double>(*p.peak_rss_bytes) / (1 << 20), 1)
          << " MiB";
    }
    out << ", context switches " << p.voluntary_switches << " voluntary / "
        << p.involuntary_switches << " involuntary, page faults " << p.minor_faults << " minor / "
        << p.major_faults << " major\n";
  }
  if (u.system_busy_percent) {
    out << "  system: " << format_fixed(*u.system_busy_percent, 1) << " % busy";
    if (u.other_cpu_percent) {
      out << ", other processes " << format_fixed(*u.other_cpu_percent, 1) << " % of a core";
    }
    out << "; per CPU";
    for (std::size_t i = 0; i < u.per_cpu_busy_percent.size(); ++i) {
      out << " " << u.cpu_ids[i] << ":" << format_fixed(u.per_cpu_busy_percent[i], 0) << "%";
    }
    out << "\n";
  }
  // Devices whose power source also reports their load (NVML: GPUs).
  for (const auto& source : r.power.sources) {
    if (!source.load) continue;
    const auto& l = *source.load;
    out << "  " << source.info.name;
    if (!source.info.description.empty()) out << " (" << source.info.description << ")";
    out << ": busy " << format_fixed(l.utilisation_mean_percent, 1) << " % mean, "
        << format_fixed(l.utilisation_max_percent, 1) << " % max; memory in use up to "
        << format_fixed(static_cast<double>(l.memory_used_max_bytes) / (1 << 30), 2) << " of "
        << format_fixed(static_cast<double>(l.memory_total_bytes) / (1 << 30), 2) << " GiB ("
        << l.readings << " readings)\n";
  }
  return out.str();
}

// Four significant digits: accuracy metrics span from micrometres to whole fractions.
std::string general(double v) {
  if (!std::isfinite(v)) return "-";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}

nlohmann::json optional_number(const std::optional<double>& v) {
  return v ? nlohmann::json(*v) : nlohmann::json(nullptr);
}

nlohmann::json functional_json(const std::optional<harness::FunctionalResult>& f) {
  if (!f) return nullptr;
  nlohmann::json metrics = nlohmann::json::object();
  for (const auto& m : f->metrics) {
    metrics[m.name] = {{"value", finite_or_null(m.value)},
                       {"unit", m.unit},
                       {"min", optional_number(m.threshold.min)},
                       {"max", optional_number(m.threshold.max)},
                       {"passed", m.passed}};
  }
  return {{"evaluator", f->evaluator},
          {"samples", {{"requested", f->requested}, {"evaluated", f->evaluated}}},
          {"checked_on_arrival", f->on_arrival},
          {"metrics", metrics},
          {"valid", f->valid},
          {"reasons", f->reasons}};
}

// Empty in every run that is not device-resident: its messages all lived in host memory.
nlohmann::json device_resident_json(const std::vector<harness::ResidentTopic>& topics) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& t : topics)
    out.push_back({{"topic", t.topic}, {"from", t.from}, {"to", t.to}, {"backend", t.backend}});
  return out;
}

nlohmann::json backend_check_json(const std::optional<harness::BackendCheck>& c) {
  if (!c) return nullptr;
  return {{"backend", c->backend},     {"output_type", c->output_type}, {"compared", c->compared},
          {"criterion", c->criterion}, {"agreement", c->agreement},     {"required", c->required},
          {"passed", c->passed},       {"reasons", c->reasons}};
}

nlohmann::json dataset_json(const harness::RunResult& r) {
  nlohmann::json d{{"name", r.dataset}, {"hash", r.dataset_hash}, {"frames", r.dataset_frames}};
  // Generated request streams: the seed and sizes that reproduce them.
  if (!r.dataset_parameters.empty()) d["parameters"] = r.dataset_parameters;
  return d;
}

}  // namespace

nlohmann::json finite_or_null(double v) {
  return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
}

nlohmann::json software_json() {
  return {{"robotperf_version", build_info::kVersion},
          {"git_revision", build_info::kGitRevision},
          {"compiler", build_info::kCompiler},
          {"build_type", build_info::kBuildType},
          {"cxx_flags", build_info::kCxxFlags},
          {"sanitized", build_info::kSanitized},
          {"libraries",
           {{"fastdds", build_info::kFastDdsVersion},
            {"cyclonedds", build_info::kCycloneDdsVersion},
            {"fastcdr", build_info::kFastCdrVersion},
            {"opencv", build_info::kOpenCvVersion},
            {"yaml-cpp", build_info::kYamlCppVersion},
            {"nlohmann_json", build_info::kNlohmannJsonVersion},
            {"sqlite3", build_info::kSqliteVersion},
            {"glibc", gnu_get_libc_version()}}}};
}

nlohmann::json transport_json(const std::string& rmw, int domain_id, const std::string& processes) {
  nlohmann::json t = {{"rmw", rmw}, {"processes", processes}};
  if (rmw == "intra") {
    t["settings"] = "in-process shared pointers: no serialization, no copies";
    return t;
  }
  t["domain_id"] = domain_id;
  if (rmw == "cyclonedds") {
    // Cyclone DDS reads its configuration (interfaces, buffers, shared memory) from this variable.
    const char* uri = std::getenv("CYCLONEDDS_URI");
    t["config_uri"] = uri && *uri ? nlohmann::json(uri) : nlohmann::json(nullptr);
    t["settings"] = t["config_uri"].is_null()
                        ? "Cyclone DDS defaults (UDPv4, XCDR1) but socket receive buffers up "
                          "to 8 MiB, QoS per topic as in graph.yaml"
                        : "Cyclone DDS with the configuration in config_uri";
    return t;
  }
  // Fast DDS reads an XML profile from these variables; it changes the transports and QoS used.
  nlohmann::json profiles = nullptr;
  for (const char* variable : {"FASTDDS_DEFAULT_PROFILES_FILE", "FASTRTPS_DEFAULT_PROFILES_FILE"}) {
    if (const char* file = std::getenv(variable); file && *file) profiles = file;
  }
  t["profiles_file"] = profiles;
  t["settings"] = profiles.is_null()
                      ? "Fast DDS defaults (UDPv4 + shared memory, XCDR1) but a 16 MiB "
                        "shared-memory segment and socket receive buffers up to 8 MiB, QoS per "
                        "topic as in graph.yaml"
                      : "Fast DDS with the XML profile in profiles_file";
  return t;
}

namespace {

// Where a multi-host run's nodes ran, and the link robotperf made between the hosts (--netns).
nlohmann::json network_json(const harness::RunResult& r) {
  using nlohmann::json;
  json hosts = json::array();
  for (const auto& [host, launcher] : r.host_launchers) {
    json h = {{"name", host}, {"launcher", launcher}, {"nodes", json::array()}};
    for (const auto& n : r.nodes) {
      if (n.host != host) continue;
      h["nodes"].push_back(n.name);
      if (!n.hostname.empty()) h["hostname"] = n.hostname;
      h["same_machine"] = n.same_machine;
    }
    hosts.push_back(std::move(h));
  }
  json out = {{"hosts", hosts}, {"link", nullptr}};
  if (const auto& use = r.network_link) {
    const auto& d = use->link;
    const auto& t = use->traffic;
    json tunnel = nullptr;
    if (d.tunnel) {
      tunnel = {{"implementation", d.tunnel->implementation},
                {"version", d.tunnel->version},
                {"mtu", d.mtu},
                {"runner_endpoint", d.tunnel->runner_endpoint},
                {"remote_endpoint", d.tunnel->remote_endpoint},
                {"underlay_mtu", d.tunnel->underlay_mtu}};
    }
    out["link"] = {{"kind", "veth pair between network namespaces on this machine (--netns)"},
                   {"runner_namespace", d.runner_namespace},
                   {"remote_namespace", d.remote_namespace},
                   {"topology", harness::to_string(d.layout.topology)},
                   {"tunnel", tunnel},
                   {"runner_address", d.runner_address},
                   {"remote_address", d.remote_address},
                   {"mtu", d.mtu},
                   {"rate", d.shaping.rate.empty() ? json(nullptr) : json(d.shaping.rate)},
                   {"netem", d.shaping.netem.empty() ? json(nullptr) : json(d.shaping.netem)},
                   {"traffic",
                    {{"bytes_out", t.bytes_out},
                     {"bytes_in", t.bytes_in},
                     {"packets_out", t.packets_out},
                     {"packets_in", t.packets_in},
                     {"dropped", t.dropped}}}};
  }
  return out;
}

}  // namespace

namespace {

using nlohmann::json;

// Per node: what ran, where, how it ended and what it used.
json nodes_json(const harness::RunResult& r) {
  json nodes = json::array();
  for (const auto& n : r.nodes) {
    json node = {
        {"name", n.name},     {"kernel", n.kernel},         {"backend", n.backend},
        {"origin", n.origin}, {"parameters", n.parameters}, {"exit_status", n.exit_status}};
    if (n.pid > 0) node["pid"] = n.pid;
    node["cpu_user_s"] = n.cpu_user_s >= 0 ? json(n.cpu_user_s) : json(nullptr);
    node["cpu_system_s"] = n.cpu_system_s >= 0 ? json(n.cpu_system_s) : json(nullptr);
    if (!n.counters.empty()) node["counters"] = n.counters;
    if (n.device) node["device"] = harness::device_to_json(*n.device);
    if (!n.hostname.empty()) node["hostname"] = n.hostname;
    if (!n.host.empty()) {
      node["host"] = n.host;
      node["same_machine"] = n.same_machine;
    }
    nodes.push_back(std::move(node));
  }
  return nodes;
}

// The other DDS participants seen on the run's domain.
json peers_json(const harness::RunResult& r) {
  json peers = json::array();
  for (const auto& p : r.domain_peers) {
    peers.push_back({{"id", rmw::to_hex(p.id)},
                     {"name", p.name},
                     {"user_data", p.user_data},
                     {"addresses", p.addresses},
                     {"topics", p.topics}});
  }
  return peers;
}

// robotperf's build and the transport as the run used it: QoS per endpoint, the ROS 2 release
// announced, security.
json software_of(const harness::RunResult& r) {
  json software = software_json();
  software["transport"] = transport_json(r.rmw, r.domain_id, r.processes);
  json qos = json::array();
  for (const auto& e : r.qos) {
    qos.push_back({{"owner", e.owner},
                   {"topic", e.topic},
                   {"history", e.qos.history == rmw::History::kKeepLast ? "keep_last" : "keep_all"},
                   {"depth", e.qos.depth},
                   {"reliability", rmw::to_string(e.qos.reliability)},
                   {"durability", rmw::to_string(e.qos.durability)}});
  }
  software["transport"]["qos"] = qos;
  if (!r.ros_distro.empty()) software["transport"]["ros_distro"] = r.ros_distro;
  software["transport"]["security"] = r.security.empty() ? json(nullptr)
                                                         : json{{"keystore", r.keystore.string()},
                                                                {"enclave", rmw::kDefaultEnclave},
                                                                {"plugins", r.security}};
  return software;
}

// Every monitored output, the run's own first: counts, latency, rate and jitter (milliseconds).
json outputs_json(const harness::RunResult& r) {
  json out = json::array();
  for (const auto& o : r.outputs) {
    out.push_back(
        {{"topic", o.topic},
         {"matched", o.matched},
         {"lost", o.lost},
         {"loss_percent", o.loss_percent},
         {"latency_ms",
          {{"from_scheduled", metrics::to_json(o.latency_from_scheduled, 1.0 / kNsPerMs, "ms")},
           {"from_sent", metrics::to_json(o.latency_from_sent, 1.0 / kNsPerMs, "ms")}}},
         {"throughput_hz", o.throughput_hz},
         {"period_ms", o.period_ns / kNsPerMs},
         {"interval_ms", metrics::to_json(o.interval, 1.0 / kNsPerMs, "ms")},
         {"jitter_ms", metrics::to_json(o.jitter, 1.0 / kNsPerMs, "ms")}});
  }
  return out;
}

// How the run was configured: its rate and timeline, counts, transport, scheduling.
json configuration_json(const harness::RunResult& r) {
  const auto& sched = r.scheduling;
  const json scheduling = {
      {"cpus", sched.cpus.empty() ? json(nullptr) : json(harness::format_cpu_list(sched.cpus))},
      {"rt_priority", sched.rt_priority ? json(sched.rt_priority) : json(nullptr)},
      {"lock_memory", sched.lock_memory}};
  const bool closed = r.timeline == "single-stream" || r.timeline == "offline";
  return {{"rate_hz", r.rate_hz},
          {"timeline", r.timeline},
          {"scenario", closed ? r.timeline : "open-loop"},
          {"rate_scale", r.timeline == "bag" ? json(r.rate_scale) : json(nullptr)},
          {"burst", r.timeline == "burst" ? json(r.burst) : json(nullptr)},
          {"arrival_seed", r.timeline == "poisson" ? json(r.arrival_seed) : json(nullptr)},
          {"count", r.count},
          {"warmup", r.warmup},
          {"warmup_repeated_s", r.warmup_repeated_s},
          {"drain_s", r.drain_s},
          {"rmw", r.rmw},
          {"processes", r.processes},
          {"monitor_wait", r.monitor_wait},
          {"device_resident", device_resident_json(r.device_resident)},
          {"executor_threads", r.executor_threads},
          {"output_topic", r.output_topic},
          {"domain_id", r.domain_id},
          {"id_base_ns", r.id_base_ns},
          {"run_token", r.run_token},
          {"update_rate_hz", r.update_rate_hz ? json(*r.update_rate_hz) : json(nullptr)},
          {"scheduling", scheduling}};
}

json launched_json(const harness::RunResult& r) {
  json launched = json::array();
  for (const auto& l : r.launched) {
    launched.push_back({{"name", l.name},
                        {"command", l.command},
                        {"pid", l.pid},
                        {"exit_status", l.exit_status},
                        {"stopped_by", l.stopped_by},
                        {"log", l.log}});
  }
  return launched;
}

json control_loops_json(const harness::RunResult& r) {
  json loops = json::array();
  const double us = 1e-3;
  for (const auto& c : r.control_loops) {
    loops.push_back(
        {{"node", c.node},
         {"update_rate_hz", c.update_rate_hz},
         {"cpu", c.cpu >= 0 ? json(c.cpu) : json(nullptr)},
         {"rt_priority", c.rt_priority ? json(c.rt_priority) : json(nullptr)},
         {"cycles", c.cycles},
         {"recorded_cycles", c.recorded_cycles},
         {"deadline_misses", c.deadline_misses},
         {"update_duration_us", metrics::to_json(c.update_duration, us, "us")},
         {"cycle_duration_us", metrics::to_json(c.cycle_duration, us, "us")},
         {"period_jitter_us", metrics::to_json(c.period_jitter, us, "us")},
         {"wake_latency_us", metrics::to_json(c.wake_latency, us, "us")},
         {"command_to_write_ms", metrics::to_json(c.command_to_write, 1.0 / kNsPerMs, "ms")}});
  }
  return loops;
}

}  // namespace

nlohmann::json result_to_json(const harness::RunResult& r, const sysinfo::MachineInfo& machine) {
  // The RobotPerf headline is the maximum latency, taken from the same block so the two agree
  // exactly.
  const json from_scheduled = metrics::to_json(r.latency_from_scheduled, 1.0 / kNsPerMs, "ms");
  // The distribution itself, compactly, so that a report can draw it without the CSV.
  const std::vector<double> latencies_ms = harness::scheduled_latencies_ms(r);
  json warnings = json::array();
  for (const auto& w : r.warnings) warnings.push_back({{"rule", w.rule}, {"message", w.message}});
  json out = {
      {"schema", kResultSchema},
      {"benchmark", {{"id", r.benchmark_id}, {"name", r.benchmark_name}, {"category", r.category}}},
      {"type", r.grey ? "grey" : "black"},
      {"started_utc", utc_time(r.started_unix_ns, "%Y-%m-%dT%H:%M:%SZ")},
      {"configuration", configuration_json(r)},
      {"dataset", dataset_json(r)},
      {"machine", sysinfo::to_json(machine)},
      {"software", software_of(r)},
      {"labels", r.labels},
      {"warnings", warnings},
      {"domain_peers", peers_json(r)},
      {"counts",
       {{"sent", r.sent},
        {"measured", r.measured},
        {"matched", r.matched},
        {"lost", r.lost},
        {"unobserved", r.unobserved},
        {"loss_percent", r.loss_percent},
        {"duplicates", r.duplicates},
        {"unknown", r.unknown},
        {"foreign", r.foreign},
        {"repeats", r.repeats}}},
      {"latency_ms",
       {{"from_scheduled", from_scheduled},
        {"from_sent", metrics::to_json(r.latency_from_sent, 1.0 / kNsPerMs, "ms")},
        {"send_lateness", metrics::to_json(r.send_lateness, 1.0 / kNsPerMs, "ms")},
        {"from_scheduled_histogram", to_json(make_log_histogram(latencies_ms))}}},
      {"headline", {{"latency_ms", from_scheduled["max"]}, {"throughput_hz", r.throughput_hz}}},
      {"throughput",
       {{"output_hz", r.throughput_hz},
        {"kind", r.throughput_kind},
        {"offered_hz", r.offered_rate_hz},
        {"window_s", r.window_s}}},
      {"outputs", outputs_json(r)},
      {"power", metrics::to_json(r.power, r.matched, r.throughput_hz)},
      {"resources", metrics::to_json(r.resources)},
      {"nodes", nodes_json(r)},
      {"completed", r.completed},
      {"interrupted", r.interrupted},
      {"errors", r.errors},
      {"validity", {{"valid", r.valid}, {"reasons", r.invalid_reasons}}},
      {"functional", functional_json(r.functional)},
      {"backend_check", backend_check_json(r.backend_check)},
  };
  if (!r.system.empty()) out["system"] = r.system;
  if (!r.host_launchers.empty()) out["network"] = network_json(r);
  if (!r.launched.empty()) out["launched"] = launched_json(r);
  if (!r.control_loops.empty()) out["control_loops"] = control_loops_json(r);
  if (r.peak_search) out["peak_search"] = peak_search_json(*r.peak_search);
  if (r.grey) {
    // Grey-box: where the trace is and what it says beyond end-to-end latency.
    out["grey"] = tracing::to_json(*r.grey);
    out["grey"]["trace"]["path"] = r.trace_dir.string();
    out["grey"]["trace"]["subbuf_bytes"] = r.trace_subbuf_bytes;
  }
  return out;
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

std::string peak_search_table(const harness::PeakSearchRecord& p) {
  std::ostringstream out;
  out << "peak search: loss <= " << p.loss_bound_percent << " %";
  if (p.latency_bound_ms)
    out << ", p" << p.latency_percentile << " latency <= " << *p.latency_bound_ms << " ms";
  out << ", rates " << p.rate_low_hz << ".." << p.rate_high_hz << " Hz, resolution "
      << p.resolution_percent << " %, " << p.step_duration_s << " s per step\n";
  char line[160];
  std::snprintf(line, sizeof line, "  %4s %12s %12s %12s %8s %12s  %s\n", "step", "rate Hz",
                "offered Hz", "output Hz", "loss %", "latency ms", "verdict");
  out << line;
  for (std::size_t i = 0; i < p.steps.size(); ++i) {
    const auto& s = p.steps[i];
    std::snprintf(line, sizeof line, "  %4zu %12s %12s %12s %8s %12s  ", i + 1,
                  format_fixed(s.rate_hz, 1).c_str(), format_fixed(s.offered_hz, 1).c_str(),
                  format_fixed(s.output_hz, 1).c_str(), format_fixed(s.loss_percent, 2).c_str(),
                  format_fixed(s.latency_ms, 3).c_str());
    out << line << (s.passed ? "sustained" : "failed: " + s.reason) << "\n";
  }
  out << "  " << (p.finished ? "" : "unfinished: ") << p.stop_reason << "\n";
  return out.str();
}

nlohmann::json peak_search_json(const harness::PeakSearchRecord& p) {
  nlohmann::json steps = nlohmann::json::array();
  for (const auto& s : p.steps) {
    steps.push_back({{"rate_hz", s.rate_hz},
                     {"offered_hz", s.offered_hz},
                     {"output_hz", s.output_hz},
                     {"loss_percent", s.loss_percent},
                     {"latency_ms", finite_or_null(s.latency_ms)},
                     {"passed", s.passed},
                     {"reason", s.reason}});
  }
  return {{"loss_bound_percent", p.loss_bound_percent},
          {"latency_bound_ms",
           p.latency_bound_ms ? nlohmann::json(*p.latency_bound_ms) : nlohmann::json(nullptr)},
          {"latency_percentile", p.latency_percentile},
          {"rate_low_hz", p.rate_low_hz},
          {"rate_high_hz", p.rate_high_hz},
          {"resolution_percent", p.resolution_percent},
          {"step_duration_s", p.step_duration_s},
          {"steps", steps},
          {"stop_reason", p.stop_reason},
          {"finished", p.finished}};
}

std::string percentile_intervals_line(const metrics::SampleStats& s, double scale,
                                      const std::string& unit, const std::string& of) {
  if (s.count == 0) return {};
  std::string out = "95 % intervals (" + of + ", " + unit + "):";
  const char* separator = " ";
  for (const auto& [name, q, ci] : {std::tuple{"p50", 0.50, s.p50_ci},
                                    {"p90", 0.90, s.p90_ci},
                                    {"p99", 0.99, s.p99_ci},
                                    {"p99.9", 0.999, s.p999_ci}}) {
    out += separator;
    separator = ", ";
    out += std::string(name) + " ";
    out += std::isnan(ci.lower) ? "?" : format_fixed(ci.lower * scale, 3);
    out += "..";
    out += std::isnan(ci.upper)
               ? "? (needs " + std::to_string(metrics::samples_for_upper_bound(q)) + " samples)"
               : format_fixed(ci.upper * scale, 3);
  }
  return out + "\n";
}

namespace {

// The summary's first lines: what ran, how, on what, fed with what.
void write_configuration(std::ostream& out, const harness::RunResult& r) {
  out << r.benchmark_id << " (" << r.benchmark_name << ") · " << (r.grey ? "grey-box · " : "")
      << r.rmw << " · " << r.processes << " process" << (r.processes == "single" ? "" : "es");
  if (r.timeline == "single-stream") {
    out << " · single-stream (the next message when the last output arrived)";
  } else if (r.timeline == "offline") {
    out << " · offline (as many in flight as the graph's queues hold)";
  } else {
    out << " · " << format_fixed(r.rate_hz, 1) << " Hz";
  }
  if (r.timeline == "bag") {
    out << " (the bag's timeline";
    if (r.rate_scale != 1.0) out << " x" << r.rate_scale;
    out << ")";
  } else if (r.timeline == "poisson") {
    out << " (Poisson arrivals, seed " << r.arrival_seed << ")";
  } else if (r.timeline == "burst") {
    out << " (bursts of " << r.burst << ")";
  }
  if (r.monitor_wait == "spin") out << " · Monitor spinning (one core kept busy)";
  out << " · dataset " << r.dataset;
  if (!r.dataset_parameters.empty()) {
    std::string parameters;
    for (const auto& [k, v] : r.dataset_parameters)
      parameters += (parameters.empty() ? "" : ", ") + k + " " + v;
    out << " (" << parameters << ")";
  }
  out << "\n";
  // What the user named the run by (the automatic labels are in the results file).
  std::string named;
  if (!r.system.empty()) named = "system " + r.system;
  for (const auto& [key, value] : r.labels) {
    if (!key.starts_with("robotperf.")) named += (named.empty() ? "" : " · ") + key + "=" + value;
  }
  if (!named.empty()) out << "labels: " << named << "\n";
}

// Where the graph ran: backends, device-resident topics, hosts, the network link, launched
// processes, security.
void write_placement(std::ostream& out, const harness::RunResult& r) {
  // Which node ran where, when any ran on a backend other than the host CPU.
  if (std::ranges::any_of(r.nodes, [](const auto& n) { return n.backend != "cpu"; })) {
    out << "backends:";
    for (const auto& n : r.nodes) {
      out << " " << n.name << " " << n.backend;
      if (n.device) out << " (" << n.device->name << ", " << n.device->runtime << ")";
      out << (&n == &r.nodes.back() ? "\n" : ";");
    }
  }
  for (const auto& t : r.device_resident) {
    std::string to;
    for (const auto& name : t.to) to += (to.empty() ? "" : ", ") + name;
    out << "device-resident: " << t.topic << " stays on the " << t.backend << " device from "
        << t.from << " to " << to << " (no download, no upload: not the host-memory baseline)\n";
  }
  for (const auto& [host, launcher] : r.host_launchers) {
    std::string nodes, hostname;
    for (const auto& n : r.nodes) {
      if (n.host != host) continue;
      nodes += (nodes.empty() ? "" : ", ") + n.name;
      if (!n.hostname.empty()) hostname = n.hostname + (n.same_machine ? ", this machine" : "");
    }
    out << "host " << host << ": " << nodes << " (started with '" << launcher << "'"
        << (hostname.empty() ? "" : "; ran on " + hostname) << ")\n";
  }
  if (const auto& use = r.network_link) {
    const auto& d = use->link;
    const auto& t = use->traffic;
    out << "link: "
        << (d.tunnel ? d.tunnel->implementation + " " + d.tunnel->version + " tunnel" : "veth")
        << " " << d.runner_address << " <-> " << d.remote_address << ", MTU " << d.mtu
        << (d.layout.topology == harness::NetworkLayout::Topology::kRouted ? ", routed" : "")
        << ", " << (d.shaping.rate.empty() ? "unshaped" : d.shaping.rate)
        << (d.shaping.netem.empty() ? "" : ", netem " + d.shaping.netem) << "; during the run "
        << format_fixed(static_cast<double>(t.bytes_out) / (1 << 20), 2) << " MiB out, "
        << format_fixed(static_cast<double>(t.bytes_in) / (1 << 20), 2) << " MiB in, " << t.dropped
        << " packets dropped by the shaping\n";
  }
  for (const auto& l : r.launched) {
    out << "launched " << l.name << " (pid " << l.pid << "): " << l.stopped_by << ", "
        << l.exit_status << "; log " << l.log << "\n";
  }
  if (!r.security.empty())
    out << "security: " << r.security << " (keystore " << r.keystore.string() << ")\n";
}

// The message counts: sent, measured, matched, lost and what else arrived.
void write_messages(std::ostream& out, const harness::RunResult& r) {
  out << "messages: sent " << r.sent << " (warm-up " << r.warmup;
  if (r.warmup_repeated_s > 0) {
    out << ", repeated for " << format_fixed(r.warmup_repeated_s, 2)
        << " s until the graph delivered";
  }
  out << "), measured " << r.measured << ", matched " << r.matched << ", lost " << r.lost << " ("
      << format_fixed(r.loss_percent, 2) << " %)";
  if (r.duplicates) out << ", duplicates " << r.duplicates;
  if (r.unknown) out << ", unknown " << r.unknown;
  if (r.foreign) out << ", another run's " << r.foreign << " (not counted)";
  if (r.unobserved) out << ", unobserved " << r.unobserved << " (trace events discarded)";
  if (r.repeats) out << ", state repeats " << r.repeats;
  out << "\n\n";
}

// The latency table (ms), its percentiles' intervals, and a control loop's command latency.
void write_latency(std::ostream& out, const harness::RunResult& r) {
  char line[256];
  std::snprintf(line, sizeof line, "%-24s %9s %9s %9s %9s %9s %9s %9s %9s\n", "latency (ms)", "min",
                "mean", "rms", "p50", "p90", "p99", "p99.9", "max");
  out << line;
  auto row = [&](const char* name, const metrics::SampleStats& s) {
    auto v = [](double ns) { return format_fixed(ns / kNsPerMs, 3); };
    std::snprintf(line, sizeof line, "%-24s %9s %9s %9s %9s %9s %9s %9s %9s\n", name,
                  v(s.min).c_str(), v(s.mean).c_str(), v(s.rms).c_str(), v(s.p50).c_str(),
                  v(s.p90).c_str(), v(s.p99).c_str(), v(s.p999).c_str(), v(s.max).c_str());
    out << line;
  };
  row("from scheduled send", r.latency_from_scheduled);
  row("from actual send", r.latency_from_sent);
  row("send lateness", r.send_lateness);
  out << percentile_intervals_line(r.latency_from_scheduled, 1.0 / kNsPerMs, "ms",
                                   "from scheduled send");
  for (const auto& c : r.control_loops) {
    row("command -> hw write", c.command_to_write);
  }
}

// Whether a node of the run is wired to tf2's topics: its share of the latency is then a figure
// only the trace gives.
bool wired_to_tf2(const harness::RunResult& r) {
  return std::ranges::any_of(r.qos, [](const harness::RunResult::EndpointQos& e) {
    return e.topic == "/tf" || e.topic == "/tf_static";
  });
}

// The peak search's steps, the grey-box breakdown, and RobotPerf's headline, named as what it is.
// Each monitored output: its counts, latency, rate and jitter (a table when the graph has
// several, a line for one).
void write_outputs(std::ostream& out, const harness::RunResult& r) {
  if (r.outputs.empty()) return;
  auto ms = [](double ns) { return format_fixed(ns / kNsPerMs, 3); };
  if (r.outputs.size() == 1) {
    const auto& o = r.outputs.front();
    if (o.interval.count == 0) return;
    out << "output jitter: interval p50 " << ms(o.interval.p50) << " ms against the input period "
        << ms(o.period_ns) << " ms; |interval - period| mean " << ms(o.jitter.mean) << ", p99 "
        << ms(o.jitter.p99) << ", max " << ms(o.jitter.max) << " ms\n";
    return;
  }
  char line[320];
  std::snprintf(line, sizeof line, "\n%-32s %8s %8s %10s %10s %10s %10s %10s\n",
                "outputs (ms; jitter: |interval - period|)", "matched", "lost %", "p50", "p99",
                "Hz", "jitter", "jitter p99");
  out << line;
  for (const auto& o : r.outputs) {
    std::snprintf(
        line, sizeof line, "%-32s %8zu %8s %10s %10s %10s %10s %10s\n", o.topic.c_str(), o.matched,
        format_fixed(o.loss_percent, 2).c_str(), ms(o.latency_from_scheduled.p50).c_str(),
        ms(o.latency_from_scheduled.p99).c_str(), format_fixed(o.throughput_hz, 2).c_str(),
        ms(o.jitter.mean).c_str(), ms(o.jitter.p99).c_str());
    out << line;
  }
}

void write_throughput_details(std::ostream& out, const harness::RunResult& r) {
  write_outputs(out, r);
  if (r.peak_search) out << "\n" << peak_search_table(*r.peak_search);
  if (r.grey) {
    out << "\n" << tracing::breakdown_table(*r.grey) << "\n";
  } else if (wired_to_tf2(r)) {
    out << "\ntf2 share: needs --mode grey (the robotperf:tf2 tracepoints time the buffers' "
           "calls)\n";
  }
  out << "\nRobotPerf headline (its latency is the maximum, not a typical message): latency "
      << format_fixed(r.latency_from_scheduled.max / kNsPerMs, 3) << " ms, throughput "
      << format_fixed(r.throughput_hz, 3) << " Hz\n";
}

// Each control loop's cycle timing (us) and deadline misses.
void write_control_loops(std::ostream& out, const harness::RunResult& r) {
  char line[256];
  for (const auto& c : r.control_loops) {
    out << "\ncontrol loop " << c.node << " at " << format_fixed(c.update_rate_hz, 1) << " Hz"
        << (c.cpu >= 0 ? ", CPU " + std::to_string(c.cpu) : std::string())
        << (c.rt_priority ? ", SCHED_FIFO " + std::to_string(c.rt_priority) : std::string()) << ": "
        << c.cycles << " cycles, deadline misses " << c.deadline_misses << "\n";
    std::snprintf(line, sizeof line, "%-28s %9s %9s %9s %9s %9s\n", "  loop (us)", "mean", "p50",
                  "p99", "max", "min");
    out << line;
    auto loop_row = [&](const char* name, const metrics::SampleStats& s) {
      auto v = [](double ns) { return format_fixed(ns / 1e3, 1); };
      std::snprintf(line, sizeof line, "  %-26s %9s %9s %9s %9s %9s\n", name, v(s.mean).c_str(),
                    v(s.p50).c_str(), v(s.p99).c_str(), v(s.max).c_str(), v(s.min).c_str());
      out << line;
    };
    loop_row("controller update", c.update_duration);
    loop_row("cycle (read-update-write)", c.cycle_duration);
    loop_row("period jitter", c.period_jitter);
    loop_row("wake-up latency", c.wake_latency);
  }
}

// Run-rule warnings, and the inputs each node received but could not use. The warnings that hold
// for every run on this machine (a VM, a container, ...) are one line of a few words: repeated in
// full on every run they would hide the ones about this run; the results file keeps them whole.
void write_warnings(std::ostream& out, const harness::RunResult& r) {
  std::string conditions;
  std::vector<const sysinfo::RunWarning*> this_run;
  for (const auto& w : r.warnings) {
    if (const std::string c = sysinfo::machine_condition(w); !c.empty())
      conditions += (conditions.empty() ? "" : ", ") + c;
    else
      this_run.push_back(&w);
  }
  if (!conditions.empty()) {
    out << "machine conditions (every run here; in full in the results file and `robotperf "
           "sysinfo`): "
        << conditions << "\n";
  }
  if (!this_run.empty()) {
    out << "warnings (this run):\n";
    for (const auto* w : this_run) {
      out << "  " << w->rule << ": " << w->message;
      if (w->rule == "samples" && !r.sample.empty()) out << " (one sample: " << r.sample << ")";
      out << "\n";
    }
  }
  for (const auto& n : r.nodes) {
    std::string unused;
    for (const auto& [name, value] : n.counters) {
      if (name.starts_with("unpaired_") || name.starts_with("rejected_")) {
        if (value > 0) unused += (unused.empty() ? "" : ", ") + name + " " + std::to_string(value);
      }
    }
    if (!unused.empty()) out << "node " << n.name << " dropped inputs: " << unused << "\n";
  }
}

// The functional evaluation and the backend check: whether the answers were right.
void write_answers(std::ostream& out, const harness::RunResult& r) {
  char line[256];
  if (r.functional) {
    const auto& f = *r.functional;
    out << "\nfunctional (" << f.evaluator << ", " << f.evaluated << " of " << f.requested
        << (f.on_arrival ? " chosen outputs, each checked on arrival):\n" : " sampled outputs):\n");
    // The names' column as wide as the longest, so that the values line up.
    int width = 20;
    for (const auto& m : f.metrics) width = std::max(width, static_cast<int>(m.name.size()));
    for (const auto& m : f.metrics) {
      std::snprintf(line, sizeof line, "  %-*s %12s %-9s", width, m.name.c_str(),
                    general(m.value).c_str(), m.unit.c_str());
      out << line;
      if (m.threshold.min) out << "  min " << general(*m.threshold.min);
      if (m.threshold.max) out << "  max " << general(*m.threshold.max);
      if (m.threshold.min || m.threshold.max) out << (m.passed ? "  ok" : "  FAILED");
      out << "\n";
    }
    out << "functional result: " << (f.valid ? "VALID" : "INVALID");
    for (std::size_t i = 0; i < f.reasons.size(); ++i)
      out << (i == 0 ? " — " : "; ") << f.reasons[i];
    out << "\n";
  }
  if (r.backend_check) {
    const auto& c = *r.backend_check;
    std::snprintf(line, sizeof line, "%.3f %% in the worst output (>= %.1f %%)", 100 * c.agreement,
                  100 * c.required);
    out << "backend check (" << c.backend << " against cpu on the same inputs, " << c.compared
        << " outputs): " << (c.compared > 0 ? c.criterion + " " + line : std::string("none"))
        << (c.passed ? "  ok" : "  FAILED") << "\n";
  }
}

// "p99 12.896 ms (11.403 .. 12.915)": a percentile and its 95 % interval, an end the samples
// cannot give written as "?" with the samples that would give it.
std::string percentile_with_interval(const char* name, double q, double value_ns,
                                     const metrics::PercentileInterval& ci) {
  std::string out = std::string(name) + " " + format_fixed(value_ns / kNsPerMs, 3) + " ms (";
  out += std::isnan(ci.lower) ? "?" : format_fixed(ci.lower / kNsPerMs, 3);
  out += " .. ";
  out += std::isnan(ci.upper)
             ? "?: " + std::to_string(metrics::samples_for_upper_bound(q)) + " samples give it"
             : format_fixed(ci.upper / kNsPerMs, 3);
  return out + ")";
}

// The lead: the typical and the tail latency with their intervals, the throughput and its kind,
// then one verdict line (valid or not, and where the run stands against the published results),
// the errors that ended the run under it.
void write_lead(std::ostream& out, const harness::RunResult& r, const std::string& standing) {
  const auto& s = r.latency_from_scheduled;
  if (s.count == 0) {
    out << "latency: none measured (no measured message came out of the graph)\n";
  } else if (r.timeline == "single-stream") {
    // LoadGen's SingleStream metric is the 90th percentile.
    out << "latency: " << percentile_with_interval("p90", 0.90, s.p90, s.p90_ci) << " · "
        << percentile_with_interval("p50", 0.50, s.p50, s.p50_ci)
        << " · 95 % intervals, single-stream (no queueing: each sent when the last answered)\n";
  } else if (r.timeline == "offline") {
    out << "throughput: " << format_fixed(r.throughput_hz, 3)
        << " samples/s (offline: outputs over the time from the first send to the last output; "
           "LoadGen Offline's metric)\n";
    out << "latency: " << percentile_with_interval("p50", 0.50, s.p50, s.p50_ci) << " · "
        << percentile_with_interval("p99", 0.99, s.p99, s.p99_ci)
        << " · 95 % intervals, from the batch's issue (queueing included)\n";
  } else {
    out << "latency: " << percentile_with_interval("p50", 0.50, s.p50, s.p50_ci) << " · "
        << percentile_with_interval("p99", 0.99, s.p99, s.p99_ci)
        << " · 95 % intervals, from the scheduled send\n";
  }
  if (!r.sample.empty() && r.measured < metrics::samples_for_upper_bound(0.99))
    out << "samples: " << r.measured << " by the benchmark's nature: one is " << r.sample << "\n";
  if (r.timeline == "single-stream") {
    out << "throughput: " << format_fixed(r.throughput_hz, 3)
        << " Hz out (one message in flight at a time: the inverse of the latency, not a peak)\n";
  } else if (r.timeline != "offline") {
    out << "throughput: " << format_fixed(r.throughput_hz, 3) << " Hz out at "
        << format_fixed(r.offered_rate_hz, 3) << " Hz offered"
        << (r.throughput_kind == "peak" ? " (peak: the highest rate the search found sustained)"
            : r.peak_search
                ? " (the highest rate sustained before the search was cut short: not the peak)"
                : " (keeping up with the offered load; --find-peak searches for the peak)")
        << "\n";
  }
  const bool answers_ok = !r.functional || r.functional->valid;
  out << "result: " << (r.valid && answers_ok ? "VALID" : "INVALID");
  std::vector<std::string> reasons = r.invalid_reasons;
  if (!answers_ok) reasons.push_back("wrong answers (functional check below)");
  for (std::size_t i = 0; i < reasons.size(); ++i) out << (i == 0 ? " — " : "; ") << reasons[i];
  if (!standing.empty()) out << " · " << standing;
  out << "\n";
  for (const auto& e : r.errors) out << "error: " << e << "\n";
}

}  // namespace

std::string summary_table(const harness::RunResult& r, const std::string& standing) {
  std::ostringstream out;
  write_configuration(out, r);
  write_placement(out, r);
  write_lead(out, r, standing);
  out << "\n";
  write_messages(out, r);
  write_latency(out, r);
  write_throughput_details(out, r);
  write_control_loops(out, r);
  out << power_line(r) << resources_line(r);
  write_warnings(out, r);
  write_answers(out, r);
  return out.str();
}

std::string result_basename(const harness::RunResult& r) {
  char ms[8];
  std::snprintf(ms, sizeof ms, "%03d", static_cast<int>((r.started_unix_ns / 1'000'000) % 1000));
  return r.benchmark_id + "-" + r.rmw + "-" + utc_time(r.started_unix_ns, "%Y%m%dT%H%M%S") + ms +
         "Z";
}

}  // namespace robotperf::report
