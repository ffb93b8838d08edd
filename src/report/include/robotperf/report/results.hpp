// The results of a run as files: the results JSON (schema robotperf.result/1),
// the raw per-message latencies as CSV, and the summary table for a terminal.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "robotperf/harness/run.hpp"
#include "robotperf/sysinfo/machine.hpp"

namespace robotperf::report {

inline constexpr const char* kResultSchema = "robotperf.result/1";

// robotperf's own version, revision, compiler, build and library versions.
nlohmann::json software_json();

// The transport and its settings, as recorded under software.transport.
nlohmann::json transport_json(const std::string& rmw, int domain_id, const std::string& processes);

nlohmann::json result_to_json(const harness::RunResult& result,
                              const sysinfo::MachineInfo& machine);

// id,warmup,scheduled_ns,sent_ns,received_ns,latency_scheduled_ns,latency_sent_ns (empty when
// lost).
std::string latencies_csv(const harness::RunResult& result);

// A number as JSON, or null where it is NaN or infinite.
nlohmann::json finite_or_null(double value);

// The steps of a peak-throughput search, one line each, and why it stopped.
std::string peak_search_table(const harness::PeakSearchRecord& search);
nlohmann::json peak_search_json(const harness::PeakSearchRecord& search);

// One line: the 95 % intervals of p50, p90, p99 and p99.9 of `stats` (of what: `of`), times
// `scale` in `unit`; an end the samples cannot give is "?" with the samples it needs.
std::string percentile_intervals_line(const metrics::SampleStats& stats, double scale,
                                      const std::string& unit, const std::string& of);

// A human-readable summary: what ran, then the lead (p50 and p99 with their intervals, throughput
// and its kind, the verdict with `standing`, published_standing's line), then the details:
// counts, the latency distribution, power, resources, warnings, the answers' checks.
std::string summary_table(const harness::RunResult& result, const std::string& standing = {});

// "<benchmark>-<rmw>-<UTC time>", unique per run start, safe as a file name.
std::string result_basename(const harness::RunResult& result);

}  // namespace robotperf::report
