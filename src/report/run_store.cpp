#include "robotperf/report/run_store.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>

#include "report_model.hpp"

namespace robotperf::report {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

double number_or_nan(const json& j, const char* key) {
  const auto it = j.find(key);
  return it != j.end() && it->is_number() ? it->get<double>() : kNoValue;
}

std::string string_or(const json& j, const char* key, std::string fallback) {
  const auto it = j.find(key);
  return it != j.end() && it->is_string() ? it->get<std::string>() : std::move(fallback);
}

std::string string_or_empty(const json& j, const char* key) {
  return string_or(j, key, {});
}

std::vector<std::string> strings(const json& j) {
  std::vector<std::string> out;
  if (!j.is_array()) return out;
  for (const auto& e : j) {
    if (e.is_string()) out.push_back(e.get<std::string>());
    // Run-rule warnings: {"rule": ..., "message": ...}.
    if (e.is_object() && e.contains("message") && e["message"].is_string())
      out.push_back((e.contains("rule") && e["rule"].is_string()
                         ? e["rule"].get<std::string>() + ": "
                         : std::string()) +
                    e["message"].get<std::string>());
  }
  return out;
}

std::string short_number(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", v);
  return text;
}

std::string count_text(const json& j, const char* key) {
  const json& v = member(j, key);
  return v.is_number_unsigned() ? std::to_string(v.get<uint64_t>()) : "?";
}

void read_also_measured(const json& j, StoredRun& run) {
  const json& functional = member(j, "functional");
  if (functional.is_object() && member(functional, "valid").is_boolean()) {
    if (functional["valid"].get<bool>()) {
      std::string metrics;
      const json& m = member(functional, "metrics");
      if (m.is_object()) {
        for (const auto& [name, metric] : m.items()) {
          const double v = number_or_nan(metric, "value");
          if (!std::isfinite(v)) continue;
          const std::string unit = string_or_empty(metric, "unit");
          metrics += (metrics.empty() ? "" : ", ") + name + " " + short_number(v) +
                     (unit.empty() || unit == "fraction" ? "" : " " + unit);
        }
      }
      run.functional = "VALID" + (metrics.empty() ? "" : ": " + metrics);
    } else {
      const std::string why = joined(strings(member(functional, "reasons")), "; ");
      run.functional = "INVALID" + (why.empty() ? "" : ": " + why);
    }
  }
  const json& processes = member(member(j, "resources"), "processes");
  if (processes.is_array()) {
    double cpu = 0, rss = 0;
    bool any = false;
    for (const auto& p : processes) {
      const double c = number_or_nan(p, "cpu_percent");
      const double r = number_or_nan(p, "peak_rss_bytes");
      if (std::isfinite(c)) cpu += c;
      if (std::isfinite(r)) rss += r;
      any = any || std::isfinite(c);
    }
    if (any) {
      run.cpu_percent = cpu;
      run.peak_rss_mib = rss / (1024.0 * 1024.0);
    }
  }
  const json& grey = member(j, "grey");
  const json& hops = member(grey, "hops");
  if (hops.is_array()) {
    for (const auto& hop : hops) {
      const json& d = member(hop, "duration_ms");
      run.hops.push_back({string_or(hop, "label", "?"), string_or_empty(hop, "kind"),
                          number_or_nan(d, "mean"), number_or_nan(d, "p50"),
                          number_or_nan(d, "p99")});
    }
  }
  if (const json& nodes = member(j, "nodes"); nodes.is_array()) {
    // Nodes that handed images over on the device ran a configuration of their own: their
    // backend reads "<backend>-resident", so that no comparison takes them for the baseline.
    std::set<std::string> resident;
    if (const json& kept = member(member(j, "configuration"), "device_resident"); kept.is_array()) {
      for (const auto& topic : kept) {
        resident.insert(string_or_empty(topic, "from"));
        if (const json& to = member(topic, "to"); to.is_array()) {
          for (const auto& name : to)
            if (name.is_string()) resident.insert(name.get<std::string>());
        }
      }
    }
    std::vector<std::string> settings;
    for (const auto& node : nodes) {
      const json& parameters = member(node, "parameters");
      const std::string origin = string_or_empty(node, "origin");
      if (!parameters.is_object() || (parameters.empty() && origin.empty())) continue;
      std::vector<std::string> values;
      for (const auto& [name, value] : parameters.items())
        values.push_back(name + "=" +
                         (value.is_string() ? value.get<std::string>() : value.dump()));
      settings.push_back(string_or_empty(node, "name") + " (" + origin +
                         "): " + joined(values, ", "));
    }
    run.node_settings = joined(settings, "; ");
    std::set<std::string> backends;
    for (const auto& node : nodes) {
      const json& b = member(node, "backend");
      if (!b.is_string() || b.get<std::string>() == "cpu") continue;
      backends.insert(b.get<std::string>() +
                      (resident.contains(string_or_empty(node, "name")) ? "-resident" : ""));
    }
    run.backend = joined(backends, "+");
  }
  const json& peak = member(j, "peak_search");
  if (const json& steps = member(peak, "steps"); steps.is_array()) {
    for (const auto& step : steps) {
      const json& passed = member(step, "passed");
      run.peak_steps.push_back(
          {number_or_nan(step, "rate_hz"), number_or_nan(step, "offered_hz"),
           number_or_nan(step, "output_hz"), number_or_nan(step, "loss_percent"),
           number_or_nan(step, "latency_ms"), passed.is_boolean() && passed.get<bool>(),
           string_or_empty(step, "reason")});
    }
    if (const json& why = member(peak, "stop_reason"); why.is_string())
      run.peak_stop_reason = why.get<std::string>();
  }
  const json& callbacks = member(grey, "callbacks");
  if (callbacks.is_array()) {
    for (const auto& cb : callbacks) {
      const json& d = member(cb, "duration_ms");
      const double count = number_or_nan(d, "count");
      run.callbacks.push_back(
          {string_or(cb, "node", "?"), string_or_empty(cb, "source"),
           std::isfinite(count) && count >= 0 ? static_cast<std::size_t>(count) : 0,
           number_or_nan(d, "mean"), number_or_nan(d, "p50"), number_or_nan(d, "p99"),
           number_or_nan(d, "max")});
    }
  }
  const json& loops = member(j, "control_loops");
  if (loops.is_array()) {
    for (const auto& loop : loops) {
      if (const double hz = number_or_nan(loop, "update_rate_hz");
          !run.update_rate_hz && std::isfinite(hz))
        run.update_rate_hz = hz;
      const double jitter = number_or_nan(member(loop, "period_jitter_us"), "p99");
      run.control += (run.control.empty() ? "" : "; ") + string_or(loop, "node", "loop") +
                     ": period jitter p99 " + (std::isfinite(jitter) ? short_number(jitter) : "?") +
                     " us, " + count_text(loop, "deadline_misses") + " deadline misses in " +
                     count_text(loop, "cycles") + " cycles";
    }
  }
}

// A count of the results file: absent is 0; anything but a non-negative integer is a file that
// cannot be trusted, named with the field.
std::size_t count_of(const json& j, const char* key, const std::string& field) {
  const auto it = j.find(key);
  if (it == j.end() || it->is_null()) return 0;
  if (!it->is_number_unsigned())
    throw ReportError(field + " is " + it->dump() + ", expected a count (an integer >= 0)");
  return it->get<std::size_t>();
}

LatencySummary latency_summary(const json& block) {
  LatencySummary s;
  if (!block.is_object()) return s;
  s.count = count_of(block, "count", "latency_ms.from_scheduled.count");
  s.min = number_or_nan(block, "min");
  s.mean = number_or_nan(block, "mean");
  s.rms = number_or_nan(block, "rms");
  s.stddev = number_or_nan(block, "stddev");
  s.p50 = number_or_nan(block, "p50");
  s.p90 = number_or_nan(block, "p90");
  s.p99 = number_or_nan(block, "p99");
  s.p999 = number_or_nan(block, "p999");
  s.max = number_or_nan(block, "max");
  // Older files have no interval; an open end is null: both read as NaN.
  if (const auto it = block.find("p50_ci95");
      it != block.end() && it->is_array() && it->size() == 2) {
    if ((*it)[0].is_number()) s.p50_lower = (*it)[0].get<double>();
    if ((*it)[1].is_number()) s.p50_upper = (*it)[1].get<double>();
  }
  return s;
}

// The power section is written by the metrics piece; read the average and energy from the names
// it may use, and treat anything else as "no power figure".
void read_power(const json& power, StoredRun& run) {
  if (power.is_null()) {
    run.power_note = "not recorded";
    return;
  }
  if (power.is_string()) {
    run.power_note = power.get<std::string>();
    return;
  }
  if (!power.is_object()) return;
  const json& total = member(power, "total");
  for (const json* scope : {&power, &total}) {
    for (const char* key : {"average_w", "average_watts", "avg_w", "watts"}) {
      const double w = number_or_nan(*scope, key);
      if (std::isfinite(w) && !run.power_w) run.power_w = w;
    }
    for (const char* key : {"energy_j", "energy_joules"}) {
      const double e = number_or_nan(*scope, key);
      if (std::isfinite(e) && !run.energy_j) run.energy_j = e;
    }
  }
  if (member(power, "available").is_boolean() && !power["available"].get<bool>()) {
    run.power_w.reset();
    run.energy_j.reset();
  }
  for (const char* key : {"reason", "unavailable_reason", "why", "status"}) {
    if (run.power_note.empty()) run.power_note = string_or_empty(power, key);
  }
  if (run.power_note.empty() && run.power_w) {
    // The sources summed into the total, else every source that was read.
    std::vector<std::string> names = strings(member(total, "sources"));
    const json& sources = member(power, "sources");
    if (names.empty() && sources.is_array()) {
      for (const auto& s : sources) {
        const json& available = member(s, "available");
        if (!available.is_null() && !available.is_boolean()) {
          throw ReportError("power.sources[].available is " + available.dump() +
                            ", expected true or false");
        }
        if (s.is_object() && (available.is_null() || available.get<bool>())) {
          const auto name = string_or_empty(s, "name");
          if (!name.empty()) names.push_back(name);
        }
      }
    }
    for (std::size_t i = 0; i < names.size(); ++i) run.power_note += (i ? ", " : "") + names[i];
  }
  if (run.power_note.empty() && !run.power_w) run.power_note = "unavailable";
}

std::string collapse_spaces(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == ' ' && (out.empty() || out.back() == ' ')) continue;
    out += c;
  }
  while (!out.empty() && out.back() == ' ') out.pop_back();
  return out;
}

std::vector<std::string> impossible_figures(const StoredRun& run) {
  std::vector<std::string> out;
  auto fmt = [](double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", v);
    return std::string(buf);
  };
  if (run.latency.min < 0) out.push_back("latency min " + fmt(run.latency.min) + " ms < 0");
  if (run.loss_percent < 0 || run.loss_percent > 100)
    out.push_back("loss " + fmt(run.loss_percent) + " % outside 0-100 %");
  if (run.matched > run.measured) {
    out.push_back(std::to_string(run.matched) + " matched of " + std::to_string(run.measured) +
                  " measured");
  }
  if (run.measured > 0 &&
      run.lost + run.unobserved != run.measured - std::min(run.matched, run.measured)) {
    out.push_back("lost " + std::to_string(run.lost) + " is not measured - matched" +
                  (run.unobserved ? " - unobserved" : ""));
  }
  if (run.throughput_hz < 0) out.push_back("throughput " + fmt(run.throughput_hz) + " Hz < 0");
  if (run.power_w && !(*run.power_w >= 0)) out.push_back("power " + fmt(*run.power_w) + " W");
  return out;
}

}  // namespace

const json& member(const json& j, const char* key) {
  static const json null_json;
  if (!j.is_object()) return null_json;
  const auto it = j.find(key);
  return it == j.end() ? null_json : *it;
}

std::string StoredRun::stem() const {
  return path.stem().string();
}

std::string StoredRun::timestamp() const {
  std::string t = started_utc;
  if (t.size() >= 19 && t[10] == 'T') {
    t[10] = ' ';
    t.resize(19);
  }
  return t;
}

bool looks_like_result(const fs::path& path) {
  std::ifstream in(path);
  if (!in) return false;
  const json j = json::parse(in, nullptr, /*allow_exceptions=*/false);
  return j.is_object() && member(j, "schema") == "robotperf.result/1";
}

namespace {

// network.link as StoredRun::network names it; "plain" for a run without a link robotperf made.
std::string network_path(const json& link) {
  if (!link.is_object()) return "plain";
  const bool routed = string_or(link, "topology", "same-subnet") == "routed";
  const json& tunnel = member(link, "tunnel");
  if (!tunnel.is_object()) return routed ? "routed" : "plain";
  return string_or(tunnel, "implementation", "?") + " " + string_or(tunnel, "version", "?") +
         ", MTU " + std::to_string(tunnel.value("mtu", 0)) + (routed ? ", routed" : "");
}

// Every field of a results file, read into `run`. Throws ReportError (without the file name) for
// a file that is not a usable result, and json::exception for a field of another type than
// robotperf writes.
void read_run(const json& j, StoredRun& run) {
  if (!j.is_object() || member(j, "schema") != "robotperf.result/1")
    throw ReportError("not a robotperf results file (expected \"schema\": \"robotperf.result/1\")");
  const json& benchmark = member(j, "benchmark");
  run.benchmark_id = string_or_empty(benchmark, "id");
  if (run.benchmark_id.empty()) throw ReportError("results file without benchmark.id");
  run.benchmark_name = string_or_empty(benchmark, "name");
  run.category = string_or_empty(benchmark, "category");
  run.type = string_or_empty(j, "type");
  run.started_utc = string_or_empty(j, "started_utc");
  const json& config = member(j, "configuration");
  run.rmw = string_or_empty(config, "rmw");
  run.processes = string_or_empty(config, "processes");
  run.rate_hz = number_or_nan(config, "rate_hz");
  // Older files have neither: they sent at a fixed rate, and their Monitor slept.
  run.timeline = string_or(config, "timeline", "fixed");
  run.monitor_wait = string_or(config, "monitor_wait", "sleep");
  run.network = network_path(member(member(j, "network"), "link"));
  run.dataset = string_or_empty(member(j, "dataset"), "name");
  const json& software = member(j, "software");
  run.robotperf_version = string_or(software, "robotperf_version", "?");
  run.git_revision = string_or(software, "git_revision", "?");
  const json& machine = member(j, "machine");
  run.hardware = string_or(j, "system", hardware_label(machine));
  if (const json& labels = member(j, "labels"); labels.is_object()) {
    for (const auto& [key, value] : labels.items()) {
      if (value.is_string()) run.labels[key] = value.get<std::string>();
    }
  }
  run.hardware_category = hardware_category(machine);
  const json& counts = member(j, "counts");
  const json& latency = member(j, "latency_ms");
  run.measured = count_of(counts, "measured", "counts.measured");
  run.matched = count_of(counts, "matched", "counts.matched");
  run.lost = count_of(counts, "lost", "counts.lost");
  run.unobserved = count_of(counts, "unobserved", "counts.unobserved");
  run.latency = latency_summary(member(latency, "from_scheduled"));
  run.loss_percent = number_or_nan(counts, "loss_percent");
  run.histogram = log_histogram_from_json(member(latency, "from_scheduled_histogram"));
  if (const json& outputs = member(j, "outputs"); outputs.is_array()) {
    for (const json& o : outputs) {
      StoredOutput out;
      out.topic = string_or(o, "topic", "?");
      out.loss_percent = number_or_nan(o, "loss_percent");
      out.latency = latency_summary(member(member(o, "latency_ms"), "from_scheduled"));
      out.throughput_hz = number_or_nan(o, "throughput_hz");
      out.period_ms = number_or_nan(o, "period_ms");
      out.interval = latency_summary(member(o, "interval_ms"));
      out.jitter = latency_summary(member(o, "jitter_ms"));
      run.outputs.push_back(std::move(out));
    }
  }
  const json& throughput = member(j, "throughput");
  run.throughput_hz = number_or_nan(throughput, "output_hz");
  run.offered_hz = number_or_nan(throughput, "offered_hz");
  if (member(throughput, "kind") == "peak") run.throughput_kind = "peak";
  read_power(member(j, "power"), run);
  const json& validity = member(j, "validity");
  run.valid = member(validity, "valid").is_boolean() && validity["valid"].get<bool>();
  run.invalid_reasons = strings(member(validity, "reasons"));
  read_also_measured(j, run);
  run.warnings = strings(member(j, "warnings"));
  if (run.warnings.empty()) run.warnings = strings(member(member(j, "run_rules"), "warnings"));
  // Figures no measurement can produce make the run invalid, as they make a published row flagged
  // (an edited or corrupted file, or a defect of whatever wrote it).
  for (auto& why : impossible_figures(run)) {
    run.valid = false;
    run.invalid_reasons.push_back("impossible figure: " + why);
  }
}

}  // namespace

StoredRun load_run(const fs::path& path) {
  std::ifstream in(path);
  if (!in) throw ReportError(path.string() + ": cannot open the results file");
  json j;
  try {
    j = json::parse(in);
  } catch (const json::exception& e) {  // parse_error, and out_of_range for a number too large
    throw ReportError(path.string() + ": not valid JSON (" + e.what() +
                      "); is it a robotperf results file?");
  }
  return run_from_json(std::move(j), path);
}

StoredRun run_from_json(json j, const fs::path& path) {
  StoredRun run;
  run.path = path;
  run.json = std::move(j);
  // The one place where what is wrong with a file's content becomes the line naming the file:
  // callers skip it, never the folder it is in.
  try {
    read_run(run.json, run);
  } catch (const ReportError& e) {
    throw ReportError(path.string() + ": " + e.what());
  } catch (const json::exception& e) {
    throw ReportError(path.string() + ": a field is not what robotperf writes (" + e.what() + ")");
  }
  fs::path csv = path;
  csv.replace_extension(".latencies.csv");
  if (fs::exists(csv)) run.csv_path = csv;
  return run;
}

// Results folders also hold series and sweep summaries, and published rows imported with
// `results import --into` (published-<category>-<name>.json): none of them is a run.
bool may_be_run_file(const fs::path& path) {
  const std::string name = path.filename().string();
  return path.extension() == ".json" && !name.ends_with(".series.json") &&
         !name.ends_with(".sweep.json") && !may_be_imported_file(path);
}

bool may_be_imported_file(const fs::path& path) {
  return path.extension() == ".json" && path.filename().string().starts_with("published-");
}

bool is_regular_file_or_skip(const fs::directory_entry& entry, std::vector<std::string>& skipped) {
  std::error_code error;
  const bool regular = entry.is_regular_file(error);
  // A link to nothing is not an error here (there is no file to read), a loop is.
  if (error && error != std::errc::no_such_file_or_directory)
    skipped.push_back(entry.path().string() + ": cannot be read: " + error.message());
  return regular && !error;
}

RunScan scan_results(const fs::path& dir) {
  if (!fs::is_directory(dir))
    throw ReportError(dir.string() +
                      ": no such results folder (runs write to ./results, or to "
                      "the folder given by run --output)");
  RunScan scan;
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (may_be_run_file(e.path()) && is_regular_file_or_skip(e, scan.skipped))
      files.push_back(e.path());
  }
  std::ranges::sort(files);
  for (const auto& f : files) {
    try {
      scan.runs.push_back(load_run(f));
    } catch (const ReportError& e) {
      scan.skipped.push_back(e.what());
    }
  }
  sort_by_start(scan.runs);
  return scan;
}

void sort_by_start(std::vector<StoredRun>& runs) {
  std::ranges::stable_sort(runs, [](const StoredRun& a, const StoredRun& b) {
    return std::tie(a.started_utc, a.path) < std::tie(b.started_utc, b.path);
  });
}

std::string hardware_label(const json& machine) {
  std::string name;
  const std::string board = string_or_empty(machine, "board_model");
  if (!board.empty()) {
    name = std::regex_replace(board, std::regex(" Developer Kit$| Dev(\\.|elopment)? Kit$"), "");
  } else {
    name = string_or_empty(member(machine, "cpu"), "model");
    // "Intel(R) Core(TM) i7-12700H CPU @ 2.30GHz" -> "Intel Core i7-12700H".
    name = std::regex_replace(name, std::regex("\\((R|TM|r|tm)\\)"), "");
    name = std::regex_replace(name, std::regex(" CPU @ .*$| @ [0-9.]+ ?GHz$"), "");
    name = std::regex_replace(name, std::regex(" [0-9]+-Core Processor$| Processor$"), "");
    name = collapse_spaces(name);
  }
  if (name.empty()) name = "unknown machine";
  std::set<std::string> seen;
  const json& gpus = member(machine, "gpus");
  if (gpus.is_array()) {
    for (const auto& g : gpus) {
      std::string model = string_or_empty(g, "model");
      if (model.empty() && string_or_empty(g, "driver") == "amdgpu")
        model = "AMD GPU " + string_or_empty(g, "device_id");
      if (!model.empty() && seen.insert(model).second) name += " + " + model;
    }
  }
  return name;
}

std::string hardware_category(const json& machine) {
  const std::string arch = string_or_empty(machine, "architecture");
  const std::string board = string_or_empty(machine, "board_model");
  const std::string cpu = string_or_empty(member(machine, "cpu"), "model");
  if (!board.empty() || arch == "aarch64" || arch.starts_with("arm")) return "edge";
  if (member(machine, "virtual_machine").is_boolean() && machine["virtual_machine"].get<bool>())
    return "cloud";
  static const std::regex server("EPYC|Xeon|Opteron|Ampere|Neoverse|Graviton");
  if (std::regex_search(cpu, server)) return "datacenter";
  return "workstation";
}

std::vector<double> read_latency_csv(const fs::path& csv) {
  std::ifstream in(csv);
  if (!in) throw ReportError(csv.string() + ": cannot open the latency CSV");
  std::string line;
  std::getline(in, line);
  if (!line.starts_with("id,warmup,scheduled_ns,sent_ns,received_ns,latency_scheduled_ns"))
    throw ReportError(csv.string() + ":1: not a robotperf latency CSV (unexpected header)");
  std::vector<double> out;
  std::size_t number = 1;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty()) continue;
    std::vector<std::string> cells;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) cells.push_back(cell);
    if (line.back() == ',') cells.emplace_back();
    if (cells.size() != 7)
      throw ReportError(csv.string() + ":" + std::to_string(number) + ": expected 7 columns");
    if (cells[1] == "1" || cells[5].empty()) continue;  // warm-up or lost
    try {
      out.push_back(static_cast<double>(std::stoll(cells[5])) / 1e6);
    } catch (const std::exception&) {
      throw ReportError(csv.string() + ":" + std::to_string(number) + ": latency '" + cells[5] +
                        "' is not an integer");
    }
  }
  return out;
}

std::string format_fixed(double value, int decimals) {
  if (!std::isfinite(value)) return "-";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, value);
  return buf;
}

std::string runs_table(const std::vector<StoredRun>& runs) {
  detail::Table t;
  t.header = {"file",    "bench",   "type",   "hardware", "transport", "date (UTC)",
              "lat max", "lat p50", "thr Hz", "power W",  "validity"};
  t.numeric = {false, false, false, false, false, false, true, true, true, true, false};
  for (const auto& r : runs) {
    std::string validity = r.valid ? "valid" : "INVALID";
    if (!r.valid && !r.invalid_reasons.empty()) validity += ": " + r.invalid_reasons.front();
    t.rows.push_back({r.stem(), r.benchmark_id, r.type, r.hardware,
                      r.rmw + (r.processes == "per-node" ? "/per-node" : ""), r.timestamp(),
                      format_fixed(r.latency.max, 3), format_fixed(r.latency.p50, 3),
                      format_fixed(r.throughput_hz, 2),
                      r.power_w ? format_fixed(*r.power_w, 2) : "-", validity});
  }
  return detail::table_text(t);
}

namespace {

// "key=value;key=value", in key order (no comma: the CSV stays one field per comma for programs
// that split it so).
std::string labels_text(const std::map<std::string, std::string>& labels) {
  std::string out;
  for (const auto& [key, value] : labels) out += (out.empty() ? "" : ";") + key + "=" + value;
  return out;
}

// One row of `results list --format json|csv`: (field, value) in column order.
std::vector<std::pair<const char*, json>> run_fields(const StoredRun& r) {
  auto number = [](double v) { return std::isfinite(v) ? json(v) : json(nullptr); };
  auto optional = [](const std::optional<double>& v) { return v ? json(*v) : json(nullptr); };
  return {{"file", r.path.string()},
          {"benchmark", r.benchmark_id},
          {"name", r.benchmark_name},
          {"category", r.category},
          {"mode", r.type},
          {"hardware", r.hardware},
          {"labels", labels_text(r.labels)},
          {"rmw", r.rmw},
          {"processes", r.processes},
          {"backend", r.backend.empty() ? "cpu" : r.backend},
          {"arrivals", r.timeline},
          {"monitor", r.monitor_wait},
          {"network", r.network},
          {"rate_hz", number(r.rate_hz)},
          {"update_rate_hz", optional(r.update_rate_hz)},
          {"started_utc", r.started_utc},
          {"measured", r.measured},
          {"lost", r.lost},
          {"loss_percent", number(r.loss_percent)},
          {"latency_mean_ms", number(r.latency.mean)},
          {"latency_p50_ms", number(r.latency.p50)},
          {"latency_p99_ms", number(r.latency.p99)},
          {"latency_max_ms", number(r.latency.max)},
          {"throughput_hz", number(r.throughput_hz)},
          {"throughput_kind", r.throughput_kind},
          {"power_w", optional(r.power_w)},
          {"energy_j", optional(r.energy_j)},
          {"cpu_percent", optional(r.cpu_percent)},
          {"peak_rss_mib", optional(r.peak_rss_mib)},
          {"valid", r.valid},
          {"invalid_reasons", joined(r.invalid_reasons, "; ")},
          {"warnings", r.warnings.size()}};
}

std::string csv_cell(const json& v) {
  if (v.is_null()) return "";
  if (v.is_boolean()) return v.get<bool>() ? "true" : "false";
  if (!v.is_string()) return v.dump();
  const std::string text = v.get<std::string>();
  if (text.find_first_of(",\"\r\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

}  // namespace

json runs_json(const std::vector<StoredRun>& runs) {
  json out = json::array();
  for (const auto& r : runs) {
    json row = json::object();
    for (auto& [field, value] : run_fields(r)) row[field] = std::move(value);
    out.push_back(std::move(row));
  }
  return out;
}

std::string runs_csv(const std::vector<StoredRun>& runs) {
  std::string out;
  for (const auto& [field, value] : run_fields(StoredRun{}))
    out += (out.empty() ? "" : ",") + std::string(field);
  out += "\r\n";
  for (const auto& r : runs) {
    std::string line;
    for (const auto& [field, value] : run_fields(r)) {
      line += (line.empty() ? "" : ",") + csv_cell(value);
    }
    out += line + "\r\n";
  }
  return out;
}

}  // namespace robotperf::report
