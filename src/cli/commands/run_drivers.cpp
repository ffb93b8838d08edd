// How `run` runs: once, as a series (--repeat), a sweep (--sweep) or a peak search
// (--find-peak); and how each run's summary and files are written.
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <iostream>
#include <map>
#include <stdexcept>
#include <thread>

#include "../interrupts.hpp"
#include "robotperf/cli/exit_codes.hpp"
#include "robotperf/files/atomic_file.hpp"
#include "robotperf/files/paths.hpp"
#include "robotperf/harness/dataset.hpp"
#include "robotperf/harness/peak_search.hpp"
#include "robotperf/report/benchmark_yaml.hpp"
#include "robotperf/report/report.hpp"
#include "robotperf/report/results.hpp"
#include "robotperf/report/run_store.hpp"
#include "robotperf/report/series.hpp"
#include "robotperf/report/standing.hpp"
#include "robotperf/report/sweep.hpp"
#include "robotperf/results_db/results_db.hpp"
#include "robotperf/sysinfo/git_revision.hpp"
#include "robotperf/sysinfo/machine.hpp"
#include "robotperf/tracing/leftovers.hpp"
#include "run.hpp"

namespace robotperf::cli {

namespace {

// Writes a run's files (<base><suffix> for each) atomically, never over another run's: a base
// taken (two runs started in the same millisecond) becomes <base>-2, ... (files::write_new_files).
// When the output folder refuses them (a full disk, say), they go to a folder of their own under
// the temporary directory instead and stderr says where: a measured run is not thrown away.
// Returns the base the files were written under, or nothing when they could be written nowhere
// (stderr says why).
std::optional<fs::path> write_result_files(const fs::path& base,
                                           const std::map<std::string, std::string>& files) {
  try {
    return files::write_new_files(base, files);
  } catch (const std::exception& e) {
    std::cerr << "robotperf: " << e.what() << "\n";
  }
  const fs::path elsewhere = fs::temp_directory_path() /
                             ("robotperf-unsaved-" + std::to_string(getpid())) / base.filename();
  try {
    fs::create_directories(elsewhere.parent_path());
    const fs::path kept = files::write_new_files(elsewhere, files);
    std::cerr << "robotperf: the results were written to " << elsewhere.parent_path().string()
              << " instead; move them where they belong once " << base.parent_path().string()
              << " has room\n";
    return kept;
  } catch (const std::exception& e) {
    std::cerr << "robotperf: the results could not be kept anywhere (" << e.what()
              << "): the summary above is all there is\n";
    return std::nullopt;
  }
}

// Records a written run in the results folder's database too (docs/design.md §8). The JSON file
// is the record: a database that cannot take the run costs one line on stderr naming the fix,
// never the run's files or exit status.
void record_in_database(const fs::path& output, const nlohmann::json& result,
                        const fs::path& json_file) {
  const fs::path database = output / results_db::kDatabaseFile;
  try {
    results_db::Database::open(database).record(result, json_file);
  } catch (const std::exception& e) {
    std::string why = e.what();
    if (why.starts_with(database.string() + ": ")) why.erase(0, database.string().size() + 2);
    std::cerr << "robotperf: the run is not in " << database.string() << " (" << why
              << "); its results file is kept";
    // The error may name the fix already (a database of an unknown schema does).
    if (why.find("rebuild-db") == std::string::npos)
      std::cerr << ": robotperf results rebuild-db " << output.string()
                << " makes the database again from the files";
    std::cerr << "\n";
  }
}

// The first name under --output no other run has; a grey run's trace is moved there (one that
// could not be analysed too, to be looked at).
fs::path name_run(const RunArgs& a, harness::RunResult& result) {
  fs::path base = files::path_inside(a.output, report::result_basename(result));
  if (!result.trace_dir.empty() && fs::exists(result.trace_dir)) {
    // The trace folder takes the first name no other run has; the files follow it.
    for (int n = 2; fs::exists(base.string() + ".trace") || fs::exists(base.string() + ".json");
         ++n)
      base =
          files::path_inside(a.output, report::result_basename(result) + "-" + std::to_string(n));
    harness::move_trace(result, base.string() + ".trace");
  }
  return base;
}

// --report: the run's HTML report beside its results, with the package's accepted results.
void write_run_report(const harness::BenchmarkSpec& spec, const harness::RunResult& result,
                      const fs::path& base) {
  report::ReportInput input;
  input.runs.push_back(report::load_run(base.string() + ".json"));
  const auto accepted = report::import_benchmark_yaml(spec.dir / "benchmark.yaml");
  if (!accepted.results.empty()) input.published.push_back(accepted);
  report::ReportOptions options;
  options.title = "robotperf " + spec.id + " — " + report::result_basename(result);
  files::write_file_atomically(base.string() + ".report.html", report::render_html(input, options));
  std::cout << "report: " << base.string() << ".report.html\n";
}

// The published rows this run is ranked against: the package's accepted results and those
// `results import --into` stored in the output folder (published-<category>-<name>.json). A file
// that cannot be read is named on stderr and left out: a reference, not the run.
std::vector<report::PublishedBenchmark> published_rows(const harness::BenchmarkSpec& spec,
                                                       const fs::path& output) {
  std::vector<report::PublishedBenchmark> rows;
  const fs::path accepted = spec.dir / "benchmark.yaml";
  const fs::path imported = output / ("published-" + spec.category + "-" + spec.name + ".json");
  try {
    rows.push_back(report::import_benchmark_yaml(accepted, spec.category));
    if (fs::exists(imported)) {
      for (auto& b : report::load_report_inputs({imported}).published) rows.push_back(std::move(b));
    }
  } catch (const std::exception& e) {
    std::cerr << "robotperf: published rows left out of the verdict: " << e.what() << "\n";
  }
  return rows;
}

// A progress line: on stderr when it is a terminal (a log gets the summaries alone, in order),
// after what stdout holds so far, so that the two never interleave on one screen.
void progress_line(const RunArgs& a, const std::string& line) {
  if (a.quiet || !isatty(STDERR_FILENO)) return;
  std::cout.flush();
  std::cerr << line << std::endl;
}

// The run's labels: the automatic ones (robotperf's version and revision; for an external graph
// the git revision its package is checked out at), then --label's, which may replace them (the
// software section keeps what really ran), and --system.
void label_run(const harness::BenchmarkSpec& spec, const RunArgs& a, harness::RunResult& result) {
  const nlohmann::json software = report::software_json();
  result.labels["robotperf.version"] = software["robotperf_version"];
  result.labels["robotperf.revision"] = software["git_revision"];
  if (spec.external()) {
    if (const auto revision = sysinfo::git_revision_of(spec.dir))
      result.labels["package.revision"] = *revision;
  }
  for (const auto& label : a.labels) {
    const auto equals = label.find('=');
    result.labels[label.substr(0, equals)] = label.substr(equals + 1);
  }
  result.system = a.system;
}

struct WrittenRun {
  int code = kExitOk;            // the exit status this run alone would give
  std::optional<fs::path> json;  // where its results file went, when it was written
};

// Prints the run's summary, then writes its results (and report, trace, CSV as asked).
WrittenRun write_run(const harness::BenchmarkSpec& spec, const RunArgs& a,
                     harness::RunResult& result) {
  label_run(spec, a, result);
  fs::path base = name_run(a, result);
  const auto machine = sysinfo::collect_machine_info();
  // The summary first: whatever happens to the files, what was measured is on the screen.
  std::string standing = report::published_standing(result, published_rows(spec, a.output));
  if (standing.empty() && result.matched > 0) {
    standing = "not ranked: no published row of " + spec.id +
               " to compare with (robotperf results import puts them in " + a.output + "/)";
  }
  std::cout << report::summary_table(result, standing);
  std::cout << "machine: " << sysinfo::summary_line(machine) << "\n";
  const nlohmann::json result_json = report::result_to_json(result, machine);
  std::map<std::string, std::string> files = {{".json", json_text(result_json, 2) + "\n"}};
  if (a.csv) files[".latencies.csv"] = report::latencies_csv(result);
  const auto kept = write_result_files(base, files);
  const bool moved = kept && kept->parent_path() != base.parent_path();
  if (kept) base = *kept;
  if (kept)
    std::cout << "results: " << base.string() << ".json" << (a.csv ? " (+ .latencies.csv)" : "")
              << (result.grey ? " (+ .trace)" : "") << "\n";
  if (kept && !moved) record_in_database(a.output, result_json, base.string() + ".json");
  if (a.report && kept && !moved) write_run_report(spec, result, base);
  WrittenRun out;
  const bool functional_ok = !result.functional || result.functional->valid;
  out.code = result.valid && functional_ok ? kExitOk : kExitInvalidResult;
  if (result.interrupted) out.code = interrupted_exit_code();
  // Results not where they were asked for are an error of the run, whatever it measured.
  if (!kept || moved) out.code = kExitError;
  if (kept) out.json = base.string() + ".json";
  if (result.threads_abandoned) {
    // A callback that never returned still runs on objects that must never be destroyed: end
    // here, with everything written, without running destructors.
    std::cout.flush();
    std::fflush(nullptr);
    std::_Exit(out.code);
  }
  return out;
}

struct MeasuredRun {
  harness::RunResult result;
  WrittenRun written;
};

// One run of `spec`, its summary and files written. A grey run records its trace in a temporary
// folder of its own under --output (name_run moves the trace out), which goes once the run is
// written or fails.
MeasuredRun measure_and_write(const harness::BenchmarkSpec& spec, const RunArgs& a,
                              harness::RunOptions o) {
  std::optional<tracing::TemporaryTraceFolder> trace_folder;
  if (o.tracing.mode == harness::RunMode::kGrey) {
    trace_folder.emplace(a.output);
    o.tracing.trace_dir = trace_folder->trace_path();
  }
  MeasuredRun run{harness::run_benchmark(spec, o), {}};
  run.written = write_run(spec, a, run.result);
  return run;
}

// Several runs of one benchmark (--repeat, --sweep), each with a fresh graph and written as usual.
// Before run i, `prepare(i)` sets it up (it may change `spec`, which run i then measures) and
// names it for the progress line; after it, `record` keeps its figures. Ends early on an interrupt
// (during a run or a preparation) or when a result cannot be written. The exit status is the
// first failing run's, or 128 + the signal when interrupted; `first` is the first results file
// written; `ended_early` why the runs stopped before the last one (empty when they did not).
struct SeveralRuns {
  int code = kExitOk;
  std::optional<fs::path> first;
  std::string ended_early;
};
SeveralRuns run_several(
    const harness::BenchmarkSpec& spec, const RunArgs& a, const harness::RunOptions& o,
    std::size_t runs, const std::function<std::string(std::size_t)>& prepare,
    const std::function<void(const harness::RunResult&, const WrittenRun&)>& record) {
  SeveralRuns out;
  for (std::size_t i = 0; i < runs; ++i) {
    const std::string label = prepare(i);
    if (g_interrupted.load() != 0) break;
    progress_line(a, "[" + spec.id + "] " + label);
    const auto [result, written] = measure_and_write(spec, a, o);
    record(result, written);
    if (!out.first) out.first = written.json;
    if (written.code != kExitOk && out.code == kExitOk) out.code = written.code;
    if (written.code == kExitError) {
      if (i + 1 < runs) out.ended_early = "a run's results could not be written where asked";
      break;
    }
    if (result.interrupted) break;
  }
  if (g_interrupted.load() != 0) {
    if (out.code == kExitOk) out.code = interrupted_exit_code();
    out.ended_early = harness::interrupted_by(g_interrupted.load());
  }
  return out;
}

// The summary of several runs: printed, and written beside the first of them as
// <first>.<kind>.json ("series", "sweep").
void write_summary(const SeveralRuns& runs, const std::string& kind, const std::string& table,
                   const nlohmann::json& summary) {
  std::cout << "\n" << table;
  if (!runs.first) return;
  const fs::path path = fs::path(*runs.first).replace_extension("." + kind + ".json");
  files::write_file_atomically(path, json_text(summary, 2) + "\n");
  std::cout << kind << ": " << path.string() << "\n";
}

// --repeat-pause: interruptible, a Ctrl-C during the pause ends the series like one during a run.
void pause_between_runs(double seconds) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < until && g_interrupted.load() == 0)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
}

// --find-peak's bounds from the command line; the step length is --duration (default 5 s), the
// start --rate-range's low end, else --rate, else the benchmark's rate.
harness::PeakSearchOptions peak_search_options(const RunArgs& a) {
  harness::PeakSearchOptions search;
  search.loss_bound_percent = a.loss_bound;
  search.latency_bound_ms = a.latency_bound;
  search.latency_percentile = a.latency_percentile;
  search.resolution_percent = a.peak_resolution;
  if (a.duration) search.step_duration_s = *a.duration;
  if (a.rate_range) {
    const auto colon = a.rate_range->find(':');
    std::optional<double> low, high;
    if (colon != std::string::npos) {
      low = decimal<double>(a.rate_range->substr(0, colon));
      high = decimal<double>(a.rate_range->substr(colon + 1));
    }
    if (!low || !high || !(*low > 0) || !(*high >= *low) || !std::isfinite(*high))
      throw std::invalid_argument("--rate-range " + *a.rate_range +
                                  ": expected LO:HI in Hz with 0 < LO <= HI");
    search.rate_low_hz = low;
    search.rate_high_hz = high;
  }
  return search;
}

}  // namespace

int run_once(const harness::BenchmarkSpec& spec, const RunArgs& args,
             const harness::RunOptions& options) {
  return measure_and_write(spec, args, options).written.code;
}

void remove_grey_leftovers(const RunArgs& args) {
  const std::vector<std::string> removed = tracing::remove_leftovers(args.output);
  if (removed.empty()) return;
  std::string what;
  for (const auto& r : removed) what += (what.empty() ? "" : "; ") + r;
  std::cerr << "robotperf: removed what killed grey runs left: " << what << "\n";
}

// --repeat N: N runs; then the run-to-run view of the headline figures (report::series_summary).
int run_series(const harness::BenchmarkSpec& spec, const RunArgs& a, const harness::RunOptions& o) {
  report::Series series(spec.id, a.repeat);
  const SeveralRuns runs = run_several(
      spec, a, o, a.repeat,
      [&](std::size_t i) {
        if (i > 0 && a.repeat_pause > 0) pause_between_runs(a.repeat_pause);
        return "run " + std::to_string(i + 1) + " of " + std::to_string(a.repeat);
      },
      [&](const harness::RunResult& result, const WrittenRun& written) {
        series.add(result, written.json);
      });
  if (!runs.ended_early.empty()) series.end_early(runs.ended_early);
  write_summary(runs, "series", report::series_table(series), report::series_json(series));
  return runs.code;
}

// --sweep KEY=V1,V2,...: one run per value of a workload parameter; then the values side by side
// (report::sweep_table).
int run_sweep(harness::BenchmarkSpec spec, const RunArgs& a, const harness::RunOptions& o) {
  const auto [parameter, values] = report::parse_sweep(*a.sweep);
  // Every value is checked before the first run: a typo in the last would waste the others.
  for (const std::string& value : values) {
    auto workload = spec.workload;
    workload[parameter] = value;
    harness::check_workload(spec.dataset, workload);
  }
  report::Sweep sweep(spec.id, parameter, values.size());
  const SeveralRuns runs = run_several(
      spec, a, o, values.size(),
      [&](std::size_t i) {
        spec.workload[parameter] = values[i];
        return parameter + " = " + values[i];
      },
      [&](const harness::RunResult& result, const WrittenRun& written) {
        sweep.add(spec.workload[parameter], result, written.json);
      });
  if (!runs.ended_early.empty()) sweep.end_early(runs.ended_early);
  write_summary(runs, "sweep", report::sweep_table(sweep), report::sweep_json(sweep));
  return runs.code;
}

// --find-peak: the steps' progress on stderr; the peak found is written as a run.
int run_peak_search(const harness::BenchmarkSpec& spec, const RunArgs& a, harness::RunOptions o) {
  if (a.mode == "grey") throw std::invalid_argument("--find-peak runs black-box only");
  if (a.repeat > 1) throw std::invalid_argument("--find-peak is one search: not with --repeat");
  harness::PeakSearchOptions search = peak_search_options(a);
  o.load.duration_s.reset();
  o.progress = nullptr;
  std::size_t steps = 0;
  auto found = harness::find_peak(spec, o, search, [&](const harness::PeakStep& s) {
    char rate[32];
    std::snprintf(rate, sizeof rate, "%.1f", s.rate_hz);
    progress_line(a, "[" + spec.id + "] peak search step " + std::to_string(++steps) + ": " + rate +
                         " Hz: " + (s.passed ? "sustained" : "failed: " + s.reason));
  });
  if (!found.peak) {
    std::cout << report::peak_search_table(found.record);
    std::cout << "result: no rate met the bounds; nothing written\n";
    return g_interrupted.load() ? interrupted_exit_code() : kExitInvalidResult;
  }
  const int code = write_run(spec, a, *found.peak).code;
  // An interrupted search still writes the peak it had found; the exit status says it stopped.
  return g_interrupted.load() != 0 ? interrupted_exit_code() : code;
}

}  // namespace robotperf::cli
