// The results folder: reading results JSON files (robotperf.result/1) back into a form the
// results table, the RobotPerf export and the report share.
#pragma once

#include <filesystem>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "robotperf/report/histogram.hpp"

namespace robotperf::report {

// A results or benchmark file that cannot be used; the message names the file and what is wrong.
class ReportError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

inline constexpr double kNoValue = std::numeric_limits<double>::quiet_NaN();

// One latency block of a results file, in milliseconds; NaN where the file has null.
struct LatencySummary {
  std::size_t count = 0;
  double min = kNoValue, mean = kNoValue, rms = kNoValue, stddev = kNoValue, p50 = kNoValue,
         p90 = kNoValue, p99 = kNoValue, p999 = kNoValue, max = kNoValue;
  // The p50's distribution-free 95 % interval (docs/design.md §3.6); NaN where open or not stored.
  double p50_lower = kNoValue, p50_upper = kNoValue;
};

// One monitored output of a run (results `outputs`; the run's own first). Milliseconds.
struct StoredOutput {
  std::string topic;
  double loss_percent = kNoValue;
  LatencySummary latency;  // from the scheduled send
  double throughput_hz = kNoValue;
  double period_ms = kNoValue;  // the input period its intervals are compared with
  LatencySummary interval, jitter;
};

// A run as its results file records it.
struct StoredRun {
  std::filesystem::path path;
  nlohmann::json json;  // the whole file
  std::string benchmark_id, benchmark_name, category;
  std::string type;         // "black" or "grey"
  std::string started_utc;  // "2026-11-22T07:42:22Z"
  std::string rmw, processes;
  std::string timeline = "fixed";      // arrivals: "fixed", "poisson", "burst" or "bag"
  std::string monitor_wait = "sleep";  // "sleep" or "spin"
  // The path --netns made between the hosts, when not one plain subnet: "routed", or the tunnel
  // ("wireguard-go 0.0.20220316, MTU 1420", with ", routed" where so). A VPN's runs are never
  // pooled with plain ones (docs/design.md §3.9).
  std::string network = "plain";
  double rate_hz = kNoValue;
  std::string dataset;
  // What the nodes computed with, as one text ("relay (built-in util): delay_ms=0, ..."): runs that
  // differ in it did different work. Empty for results written before nodes recorded it.
  std::string node_settings;
  std::string robotperf_version = "?", git_revision = "?";  // of the robotperf that ran it
  // The run's --system name when it has one, else a short platform name: CPU model, plus GPU
  // models.
  std::string hardware;
  std::string hardware_category;              // RobotPerf category guessed from the machine
  std::map<std::string, std::string> labels;  // run --label and the automatic labels
  std::size_t measured = 0, matched = 0, lost = 0;
  std::size_t unobserved = 0;  // grey-box: messages whose trace events may have been discarded
  double loss_percent = kNoValue;
  LatencySummary latency;  // from the scheduled send time: the RobotPerf-compatible latency
  double throughput_hz = kNoValue;
  std::vector<StoredOutput> outputs;  // empty in files from before robotperf recorded them
  double offered_hz = kNoValue;
  // "offered" (the graph kept up with the rate it was fed) or "peak" (found by --find-peak).
  std::string throughput_kind = "offered";
  std::optional<double> power_w;  // average over the measured window, when a real source was read
  std::optional<double> energy_j;
  std::string power_note;  // the source, or why power is unavailable
  bool valid = false;
  std::vector<std::string> invalid_reasons;
  std::vector<std::string> warnings;  // run-rule warnings recorded by the run, if any
  // What else the run measured, as its summary shows it (empty / nullopt where it did not):
  // the functional check ("VALID: bad1 0.00267, ..." or "INVALID: why"), the graph processes'
  // CPU (% of one core, summed) and peak resident memory (MiB, summed), and the control loops
  // ("c3_controller_manager: period jitter p99 12.3 us, 0 deadline misses in 60000 cycles").
  std::string functional;
  // Grey-box runs: the trace analysis' hops (transport and node), in the order it lists them.
  struct Hop {
    std::string label, kind;
    double mean_ms = kNoValue, p50_ms = kNoValue, p99_ms = kNoValue;
  };
  std::vector<Hop> hops;
  // Grey-box runs: each callback's duration (node, what triggers it: a topic or a timer).
  struct Callback {
    std::string node, source;
    std::size_t count = 0;
    double mean_ms = kNoValue, p50_ms = kNoValue, p99_ms = kNoValue, max_ms = kNoValue;
  };
  std::vector<Callback> callbacks;
  // --find-peak: each step of the search, and why it stopped.
  struct PeakStep {
    double rate_hz = kNoValue, offered_hz = kNoValue, output_hz = kNoValue;
    double loss_percent = kNoValue, latency_ms = kNoValue;
    bool passed = false;
    std::string reason;  // why a step failed
  };
  std::vector<PeakStep> peak_steps;
  std::string peak_stop_reason;
  std::optional<double> cpu_percent;
  std::optional<double> peak_rss_mib;
  std::string control;
  std::optional<double> update_rate_hz;  // control benchmarks: the (first) controller loop's rate
  // The backends other than cpu its nodes ran on ("cuda", "cuda+opencl"); "" when all ran on cpu.
  std::string backend;
  std::optional<LogHistogram> histogram;
  std::optional<std::filesystem::path> csv_path;  // <stem>.latencies.csv beside the JSON

  // File name without ".json": "<id>-<rmw>-<UTC start>".
  std::string stem() const;
  // "2026-11-22 07:42:22": the start, as RobotPerf writes `timestampt`.
  std::string timestamp() const;
};

// Reads one results file; throws ReportError naming the file when it is not a readable
// robotperf.result/1 file, or when a field has another type than robotperf writes. Everything
// read from the file afterwards comes from the StoredRun's fields, or is type-checked.
StoredRun load_run(const std::filesystem::path& path);

// The same for a results file's content already parsed (`path` is where it is, or will be,
// written): for a writer that records the run it has just written without reading it back.
StoredRun run_from_json(nlohmann::json j, const std::filesystem::path& path);

// The member `key` of the object `j`; null when `j` is no object or has no such member.
const nlohmann::json& member(const nlohmann::json& j, const char* key);

// True when `path` holds a JSON object with "schema": "robotperf.result/1" (cheap check).
bool looks_like_result(const std::filesystem::path& path);

// Sorts runs as every reader lists them: by start time, then file.
void sort_by_start(std::vector<StoredRun>& runs);

struct RunScan {
  std::vector<StoredRun> runs;       // sorted by start time, then file name
  std::vector<std::string> skipped;  // one line per unreadable results file
};

// Every results file directly in `dir` (not recursive). Throws ReportError when `dir` does not
// exist.
RunScan scan_results(const std::filesystem::path& dir);

// A .json file that may be a run: not the summary of a --repeat series or --sweep written
// beside its runs (.series.json, .sweep.json), nor published rows imported with
// `results import --into` (may_be_imported_file).
bool may_be_run_file(const std::filesystem::path& path);
bool may_be_imported_file(const std::filesystem::path& path);

// Whether a folder's entry is a regular file, links followed. A link that cannot be followed (one
// that loops) is one line in `skipped` instead of the end of the folder's scan.
bool is_regular_file_or_skip(const std::filesystem::directory_entry& entry,
                             std::vector<std::string>& skipped);

// A short platform name from a machine description (robotperf sysinfo JSON):
// "AMD Ryzen 7 5800X", "Intel Core i7-12700H + NVIDIA GeForce RTX 3060", "NVIDIA Jetson AGX Orin".
std::string hardware_label(const nlohmann::json& machine);

// The RobotPerf category of a machine: "edge" (ARM boards, Jetson), "cloud" (virtual machines),
// "datacenter" (server CPUs: EPYC, Xeon, ...), else "workstation".
std::string hardware_category(const nlohmann::json& machine);

// The latencies (ms, from the scheduled send) of the measured, matched messages of a
// <stem>.latencies.csv file. Throws ReportError naming the file and line when it is malformed.
std::vector<double> read_latency_csv(const std::filesystem::path& csv);

// The `results list` table: one line per run.
std::string runs_table(const std::vector<StoredRun>& runs);
// The same runs for programs: a JSON array of objects, or CSV (RFC 4180, a header line), with
// the same fields ("" / null where a run has no value). Latencies in ms, rates in Hz.
nlohmann::json runs_json(const std::vector<StoredRun>& runs);
std::string runs_csv(const std::vector<StoredRun>& runs);

// "12.345" with `decimals` digits, or "-" for NaN.
std::string format_fixed(double value, int decimals);

// The strings of `items` (a vector, a set) in order, with `separator` between them.
template <class Strings>
std::string joined(const Strings& items, std::string_view separator) {
  std::string out;
  for (const auto& item : items) {
    if (!out.empty()) out += separator;
    out += item;
  }
  return out;
}

}  // namespace robotperf::report
