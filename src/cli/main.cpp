// robotperf: the command-line front end.
#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <charconv>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <thread>

#include "bag_commands.hpp"
#include "graph_command.hpp"
#include "registry_commands.hpp"
#include "robotperf/bag/bag.hpp"
#include "robotperf/build_info.hpp"
#include "robotperf/categories/builtin.hpp"
#include "robotperf/git_revision.hpp"
#include "robotperf/harness/backend_check.hpp"
#include "robotperf/harness/benchmark_spec.hpp"
#include "robotperf/harness/dataset.hpp"
#include "robotperf/harness/peak_search.hpp"
#include "robotperf/harness/run.hpp"
#include "robotperf/msgs/cdr.hpp"
#include "robotperf/msgs/dynamic.hpp"
#include "robotperf/report/atomic_file.hpp"
#include "robotperf/report/benchmark_yaml.hpp"
#include "robotperf/report/readme.hpp"
#include "robotperf/report/report.hpp"
#include "robotperf/report/results.hpp"
#include "robotperf/report/run_store.hpp"
#include "robotperf/report/series.hpp"
#include "robotperf/report/sweep.hpp"
#include "robotperf/rmw/security.hpp"
#include "robotperf/sysinfo/machine.hpp"
#include "robotperf/tracing/analysis.hpp"
#include "robotperf/tracing/ctf.hpp"
#include "robotperf/tracing/session.hpp"

namespace fs = std::filesystem;
using namespace robotperf;

namespace {

// Exit codes, documented in the README.
constexpr int kExitOk = 0;
constexpr int kExitError = 1;
constexpr int kExitUsage = 2;
constexpr int kExitInvalidResult = 3;
constexpr int kExitRefused = 4;

// All of `text` as std::from_chars reads a T in decimal, or nothing: a double's digits, point and
// exponent (also inf and nan, which the callers bound), an unsigned's digits alone (no sign,
// space or 0x); nullopt for anything else and beyond T's range.
template <class T>
std::optional<T> decimal(const std::string& text) {
  T value{};
  const char* end = text.data() + text.size();
  const auto [stop, error] = std::from_chars(text.data(), end, value);
  if (error != std::errc() || stop != end) return std::nullopt;
  return value;
}

// A number option's bound in words: CLI11's PositiveNumber and NonNegativeNumber print the range
// up to DBL_MAX, three hundred digits long.
CLI::Validator number_check(bool zero_allowed) {
  const char* wanted = zero_allowed ? "a number, 0 or more" : "a number greater than 0";
  return CLI::Validator(
      [zero_allowed, wanted](std::string& text) -> std::string {
        const auto value = decimal<double>(text);
        if (value && (zero_allowed ? *value >= 0 : *value > 0)) return "";
        return std::string("must be ") + wanted + " (got " + text + ")";
      },
      zero_allowed ? "NONNEGATIVE" : "POSITIVE");
}
const CLI::Validator kPositive = number_check(false);
const CLI::Validator kNonNegative = number_check(true);

// A number option bounded on both sides. CLI11's Range lets "nan" through (every comparison with
// it is false).
CLI::Validator number_between(double low, double high) {
  std::ostringstream wanted;
  wanted << "a number from " << low << " to " << high;
  return CLI::Validator(
      [low, high, wanted = wanted.str()](std::string& text) -> std::string {
        const auto value = decimal<double>(text);
        if (value && *value >= low && *value <= high) return "";
        return "must be " + wanted + " (got " + text + ")";
      },
      "NUMBER");
}

// A whole-number option's check. CLI11 2.1.2 converts integers with strtoll/strtoull in base 0
// (0x10 is 16, 010 is 8, and -1 an unsigned 2^64-1), so only decimal digits pass, and they are
// rewritten without leading zeros, which that conversion then reads as decimal: options take it
// with transform(), as check() would discard the rewrite.
CLI::Validator whole_number(std::uint64_t min,
                            std::uint64_t max = std::numeric_limits<std::uint64_t>::max()) {
  const bool unbounded = max == std::numeric_limits<std::uint64_t>::max();
  const std::string range = unbounded ? std::to_string(min) + " or more"
                                      : std::to_string(min) + " to " + std::to_string(max);
  const std::string wanted = unbounded ? ", " + range : " from " + range;
  return CLI::Validator(
      [min, max, wanted](std::string& text) -> std::string {
        const auto value = decimal<std::uint64_t>(text);
        if (!value || *value < min || *value > max)
          return "must be a whole number" + wanted + " (got " + text + ")";
        text = std::to_string(*value);
        return "";
      },
      range);
}

// A --domain option's check, rewritten and taken with transform() as whole_number's is.
CLI::Validator domain_id_check(bool auto_allowed) {
  const std::string range = "0 to " + std::to_string(rmw::kMaxDomainId);
  const std::string wanted = "a DDS domain id from " + range + (auto_allowed ? ", or auto" : "");
  return CLI::Validator(
      [auto_allowed, wanted](std::string& text) -> std::string {
        if (auto_allowed && text == "auto") return "";
        const auto id = rmw::parse_domain_id(text);
        if (!id) return "must be " + wanted + " (got " + text + ")";
        text = std::to_string(*id);
        return "";
      },
      auto_allowed ? range + ", or auto" : range);
}

// Power and scheduling options shared by `run`, `sysinfo` and `node`.
struct PowerArgs {
  double period_s = 0.1;
  std::string meter;
  std::string sysfs_root = "/";
  std::string nvml_library = "libnvidia-ml.so.1";
  std::vector<std::string> types;

  metrics::PowerOptions options() const {
    metrics::PowerOptions o;
    o.period = std::chrono::duration_cast<std::chrono::nanoseconds>(
        std::chrono::duration<double>(period_s));
    o.meter_command = meter;
    o.sysfs_root = sysfs_root;
    o.nvml_library = nvml_library;
    o.types.insert(types.begin(), types.end());
    return o;
  }
};

void add_power_options(CLI::App* command, PowerArgs& a, bool with_period) {
  if (with_period) {
    command
        ->add_option("--power-period", a.period_s,
                     "seconds between power readings in the measured window (default 0.1)")
        ->check(number_between(0.0005, 60.0));
  }
  command->add_option("--power-meter", a.meter,
                      "external power meter: a shell command that prints watts, run once per "
                      "reading");
  command
      ->add_option("--power-sources", a.types,
                   "use only these source types: rapl, hwmon, nvml, jetson, external "
                   "(default: all found)")
      ->delimiter(',')
      ->check(CLI::IsMember({"rapl", "hwmon", "nvml", "jetson", "external"}));
  command->add_option("--sysfs-root", a.sysfs_root,
                      "root under which sys/ holds the power sensors (default /; for testing)");
  command->add_option("--nvml-library", a.nvml_library,
                      "NVML library to load (default libnvidia-ml.so.1)");
}

struct SchedulingArgs {
  std::string cpus;
  int rt_priority = 0;
  bool lock_memory = false;

  harness::SchedulingOptions options() const {
    harness::SchedulingOptions o;
    if (!cpus.empty()) {
      o.cpus = harness::parse_cpu_list(cpus);
      harness::check_cpus_allowed(o.cpus);
    }
    o.rt_priority = rt_priority;
    o.lock_memory = lock_memory;
    return o;
  }
};

void add_scheduling_options(CLI::App* command, SchedulingArgs& a) {
  command->add_option("--cpus", a.cpus, "pin the graph to these CPUs, e.g. 2-3 or 0,2");
  command
      ->add_option("--rt-priority", a.rt_priority,
                   "run the graph with SCHED_FIFO at this priority (1-99)")
      ->transform(whole_number(1, 99));
  command->add_flag("--mlock", a.lock_memory, "lock the graph's memory (mlockall)");
}

fs::path self_executable() {
  std::error_code ec;
  fs::path p = fs::read_symlink("/proc/self/exe", ec);
  if (ec) throw std::runtime_error("cannot locate the robotperf executable: " + ec.message());
  return p;
}

// The built-in benchmarks (installed beside the executable, else the source tree's), then the
// folders of ROBOTPERF_BENCHMARKS (':'-separated) and of --benchmarks.
std::vector<fs::path> benchmark_roots(const std::vector<std::string>& flags) {
  std::vector<fs::path> roots;
  const fs::path installed =
      self_executable().parent_path().parent_path() / build_info::kInstalledBenchmarksDir;
  std::error_code ec;
  roots.push_back(fs::is_directory(installed, ec) ? installed
                                                  : fs::path(build_info::kBenchmarksDir));
  if (const char* env = std::getenv("ROBOTPERF_BENCHMARKS"); env && *env) {
    std::stringstream entries(env);
    std::string entry;
    while (std::getline(entries, entry, ':')) {
      if (!entry.empty()) roots.emplace_back(entry);
    }
  }
  for (const auto& f : flags) roots.emplace_back(f);
  // A folder given twice (or the built-in one again) is read once.
  std::vector<fs::path> unique;
  for (const auto& r : roots) {
    const fs::path canonical = fs::weakly_canonical(r, ec);
    if (std::ranges::none_of(unique, [&](const fs::path& u) { return u == canonical; }))
      unique.push_back(ec ? r : canonical);
  }
  return unique;
}

using Roots = std::vector<fs::path>;

// Creates `folder` if needed and checks that a file can be written in it; throws
// std::invalid_argument naming `option` and the reason.
void require_writable_folder(const fs::path& folder, const std::string& option) {
  std::error_code ec;
  fs::create_directories(folder, ec);
  const fs::path probe = folder / (".robotperf-write-check-" + std::to_string(getpid()));
  if (!ec) {
    const int fd = open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
    if (fd < 0) {
      ec.assign(errno, std::generic_category());
    } else {
      close(fd);
      fs::remove(probe, ec);
    }
  }
  if (ec) {
    throw std::invalid_argument(option + " " + folder.string() + ": cannot write there (" +
                                ec.message() + "); give a folder you can write to");
  }
}

int list_benchmarks(const Roots& roots) {
  std::vector<std::string> broken;
  const auto specs = harness::discover_benchmarks(roots, &broken);
  // Columns as wide as their longest entry.
  int id_width = 2, name_width = 4, category_width = 8;
  for (const auto& s : specs) {
    id_width = std::max(id_width, static_cast<int>(s.id.size()));
    name_width = std::max(name_width, static_cast<int>(s.name.size()));
    category_width = std::max(category_width, static_cast<int>(s.category.size()));
  }
  std::printf("%-*s  %-*s  %-*s  %s\n", id_width, "id", name_width, "name", category_width,
              "category", "description");
  for (const auto& s : specs) {
    std::printf("%-*s  %-*s  %-*s  %s\n", id_width, s.id.c_str(), name_width, s.name.c_str(),
                category_width, s.category.c_str(), s.short_description.c_str());
  }
  for (const auto& b : broken)
    std::fprintf(stderr, "robotperf: skipped broken package: %s\n", b.c_str());
  return kExitOk;
}

int describe_benchmark(const Roots& roots, const std::string& id) {
  const auto s = harness::find_benchmark(roots, id);
  std::cout << s.id << " — " << s.name << " (" << s.category << ")\n";
  if (!s.short_description.empty()) std::cout << s.short_description << "\n";
  std::cout << "\n" << s.description << "\n";
  std::cout << "package:   " << s.dir.string() << "\n";
  std::cout << "dataset:   " << s.dataset;
  if (const auto* d = plugin::registry().find_dataset(s.dataset)) {
    std::cout << " — " << d->info.description << " (from " << d->origin << ")";
  }
  if (!s.workload.empty()) {
    std::cout << "\nworkload: ";
    const char* separator = " ";
    for (const auto& [key, value] : s.workload) {
      std::cout << separator << key << " = " << value;
      separator = ", ";
    }
  }
  std::cout << "\nrate:      " << s.rate_hz << " Hz, "
            << (s.count ? std::to_string(s.count) : "dataset-length") << " messages, warm-up "
            << s.warmup << ", drain " << s.drain_s << " s\n";
  std::cout << "validity:  at least " << s.min_samples << " samples, loss <= " << s.max_loss_percent
            << " %\n";
  std::cout << "inputs:\n";
  for (const auto& in : s.inputs)
    std::cout << "  " << in.topic << "  [" << in.type << "] <- stream " << in.stream << "\n";
  for (const auto& p : s.plugins) std::cout << "plug-in:   " << p.string() << "\n";
  std::cout << "processes: " << s.processes
            << (s.security_required ? ", DDS Security required" : "") << "\n";
  if (!s.nodes.empty()) std::cout << "nodes:\n";
  for (const auto& n : s.nodes) cli::describe_node(std::cout, n);
  if (!s.launch.empty()) std::cout << "launch (an external graph):\n";
  for (const auto& l : s.launch) {
    std::cout << "  " << l.name << ":";
    for (const auto& word : l.command) std::cout << " " << word;
    std::cout << "  (in " << l.cwd.string() << ")\n";
  }
  if (s.attach) std::cout << "attach: an external graph already running on the domain\n";
  std::cout << "output:\n  " << s.output.topic << "  [" << s.output.type << "] -> monitor\n";
  if (s.functional) {
    const auto& f = *s.functional;
    std::cout << "functional: evaluator " << f.evaluator << ", "
              << (f.sample ? std::to_string(f.sample) + " sampled outputs\n"
                           : std::string("every measured output\n"));
    for (const auto& [role, stream] : f.truth)
      std::cout << "  truth " << role << " <- stream " << stream << "\n";
    for (const auto& [name, value] : f.parameters)
      std::cout << "  param " << name << " = " << value << "\n";
    for (const auto& [metric, t] : f.thresholds) {
      std::cout << "  threshold " << metric;
      if (t.min) std::cout << " >= " << *t.min;
      if (t.max) std::cout << " <= " << *t.max;
      std::cout << "\n";
    }
  }
  return kExitOk;
}

struct RunArgs {
  std::string id;
  std::optional<std::string> rate;     // Hz, or "bag"
  std::optional<double> update_rate;   // Hz: the controller managers' loop rate
  std::optional<std::string> backend;  // --backend: nodes whose kernel has it run on it
  bool device_resident = false;        // --device-resident
  std::optional<double> duration, drain;
  std::optional<std::string> dataset, window;
  std::vector<std::string> remaps;
  double rate_scale = 1.0;
  std::string arrival = "fixed";
  std::optional<uint64_t> arrival_seed;
  std::string monitor_wait = "sleep";
  // --find-peak and its bounds.
  bool find_peak = false;
  std::optional<double> loss_bound, latency_bound;
  double latency_percentile = 99;
  std::optional<std::string> rate_range;
  double peak_resolution = 5;
  // --repeat N [--repeat-pause S]
  std::size_t repeat = 1;
  double repeat_pause = 0;
  std::optional<std::size_t> count, warmup;
  // Default: the benchmark's process layout; fastdds for per-node, else intra.
  std::optional<std::string> rmw, processes;
  // --workload KEY=VALUE (over benchmark.yaml's workload), --sweep KEY=V1,V2,...
  std::vector<std::string> workload;
  std::optional<std::string> sweep;
  std::string output = "results";
  bool csv = false;
  bool quiet = false;
  bool report = false;
  bool strict = false;
  std::optional<std::string> domain;  // a number, or "auto"
  PowerArgs power;
  SchedulingArgs scheduling;
  std::string mode = "black";
  std::size_t trace_subbuf = 0;
  std::vector<std::string> plugins;  // --plugin: loaded by per-node children too
  double callback_timeout_s = 30.0;
  // Several hosts: --host NAME=COMMAND (a launcher), or --netns with its link's shaping.
  std::vector<std::string> hosts;
  bool netns = false;
  std::string link_rate = "1gbit";
  std::string netem;
  std::string security;  // a keystore: DDS Security for every participant of the run
  double connect_timeout_s = 15.0;
  std::string ros_distro = "jazzy";
};

// JSON as text for a file or the terminal: bytes that are not UTF-8 (names from a trace or a bag)
// are replaced, not refused, so that what was measured is always written.
std::string json_text(const nlohmann::json& j, int indent) {
  return j.dump(indent, ' ', false, nlohmann::json::error_handler_t::replace);
}

// The first SIGINT or SIGTERM ends the run cleanly (the harness polls this); a second one ends
// the process at once.
std::atomic<int> g_interrupted{0};

void on_interrupt(int signal_number) {
  if (g_interrupted.exchange(signal_number) != 0) {
    constexpr char kMessage[] = "\nrobotperf: interrupted again: stopping now\n";
    (void)!write(STDERR_FILENO, kMessage, sizeof kMessage - 1);
    harness::kill_node_processes();
    _exit(128 + signal_number);
  }
  constexpr char kMessage[] =
      "\nrobotperf: interrupted: ending the run, keeping what it measured (again to force)\n";
  (void)!write(STDERR_FILENO, kMessage, sizeof kMessage - 1);
}

// Handles SIGINT and SIGTERM while it lives.
class InterruptHandling {
 public:
  InterruptHandling() {
    struct sigaction action {};
    action.sa_handler = on_interrupt;
    sigemptyset(&action.sa_mask);
    sigaction(SIGINT, &action, &previous_int_);
    sigaction(SIGTERM, &action, &previous_term_);
  }
  ~InterruptHandling() {
    sigaction(SIGINT, &previous_int_, nullptr);
    sigaction(SIGTERM, &previous_term_, nullptr);
  }

 private:
  struct sigaction previous_int_ {};
  struct sigaction previous_term_ {};
};

// Writes a run's files (<base><suffix> for each) atomically, never over another run's: a base
// taken (two runs started in the same millisecond) becomes <base>-2, ... (report::write_new_files).
// When the output folder refuses them (a full disk, say), they go to a folder of their own under
// the temporary directory instead and stderr says where: a measured run is not thrown away.
// Returns the base the files were written under, or nothing when they could be written nowhere
// (stderr says why).
std::optional<fs::path> write_result_files(const fs::path& base,
                                           const std::map<std::string, std::string>& files) {
  try {
    return report::write_new_files(base, files);
  } catch (const std::exception& e) {
    std::cerr << "robotperf: " << e.what() << "\n";
  }
  const fs::path elsewhere = fs::temp_directory_path() /
                             ("robotperf-unsaved-" + std::to_string(getpid())) / base.filename();
  try {
    fs::create_directories(elsewhere.parent_path());
    const fs::path kept = report::write_new_files(elsewhere, files);
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

// "--remap from:=to" and "--window START:END" (seconds, either may be empty).
harness::BagSelection bag_selection(const RunArgs& a) {
  harness::BagSelection bag;
  bag.path = *a.dataset;
  for (const auto& r : a.remaps) {
    const auto sep = r.find(":=");
    if (sep == std::string::npos || sep == 0 || sep + 2 == r.size())
      throw std::invalid_argument("--remap " + r + ": expected <bag topic>:=<benchmark topic>");
    bag.remaps[r.substr(0, sep)] = r.substr(sep + 2);
  }
  if (a.window) {
    const auto sep = a.window->find(':');
    auto seconds = [&](const std::string& text) -> std::optional<double> {
      if (text.empty()) return std::nullopt;
      const std::optional<double> v = decimal<double>(text);
      if (!v || !(*v >= 0))
        throw std::invalid_argument("--window " + *a.window + ": expected START:END in seconds");
      return v;
    };
    if (sep == std::string::npos)
      throw std::invalid_argument("--window " + *a.window + ": expected START:END in seconds");
    bag.start_s = seconds(a.window->substr(0, sep));
    bag.end_s = seconds(a.window->substr(sep + 1));
  }
  return bag;
}

// One run of `spec`; a grey run's trace folder is removed when the run does not happen.
harness::RunResult measure(const harness::BenchmarkSpec& spec, const harness::RunOptions& o) {
  const InterruptHandling interrupts;
  try {
    return harness::run_benchmark(spec, o);
  } catch (...) {
    std::error_code ec;
    if (!o.trace_dir.empty()) fs::remove_all(o.trace_dir, ec);
    throw;
  }
}

struct WrittenRun {
  int code = kExitOk;            // the exit status this run alone would give
  std::optional<fs::path> json;  // where its results file went, when it was written
};

// Prints the run's summary, then writes its results (and report, trace, CSV as asked).
WrittenRun write_run(const harness::BenchmarkSpec& spec, const RunArgs& a,
                     harness::RunResult& result) {
  fs::path base = fs::path(a.output) / report::result_basename(result);
  if (result.grey) {
    // The trace folder takes the first name no other run has; the files follow it.
    for (int n = 2; fs::exists(base.string() + ".trace") || fs::exists(base.string() + ".json");
         ++n)
      base = fs::path(a.output) / (report::result_basename(result) + "-" + std::to_string(n));
    const fs::path trace = base.string() + ".trace";
    fs::rename(result.trace_dir, trace);
    result.trace_dir = trace;
  }
  const auto machine = sysinfo::collect_machine_info();
  // The summary first: whatever happens to the files, what was measured is on the screen.
  std::cout << report::summary_table(result);
  std::cout << "machine: " << sysinfo::summary_line(machine) << "\n";
  std::map<std::string, std::string> files = {
      {".json", json_text(report::result_to_json(result, machine), 2) + "\n"}};
  if (a.csv) files[".latencies.csv"] = report::latencies_csv(result);
  const auto kept = write_result_files(base, files);
  const bool moved = kept && kept->parent_path() != base.parent_path();
  if (kept) base = *kept;
  if (kept)
    std::cout << "results: " << base.string() << ".json" << (a.csv ? " (+ .latencies.csv)" : "")
              << (result.grey ? " (+ .trace)" : "") << "\n";
  if (a.report && kept && !moved) {
    report::ReportInput input;
    input.runs.push_back(report::load_run(base.string() + ".json"));
    // The package's accepted results, for context, when it has any.
    const auto accepted = report::import_benchmark_yaml(spec.dir / "benchmark.yaml");
    if (!accepted.results.empty()) input.published.push_back(accepted);
    report::ReportOptions options;
    options.title = "robotperf " + spec.id + " — " + report::result_basename(result);
    report::write_file_atomically(base.string() + ".report.html",
                                  report::render_html(input, options));
    std::cout << "report: " << base.string() << ".report.html\n";
  }
  WrittenRun out;
  const bool functional_ok = !result.functional || result.functional->valid;
  out.code = result.valid && functional_ok ? kExitOk : kExitInvalidResult;
  if (result.interrupted) out.code = 128 + g_interrupted.load();
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

// Several runs of one benchmark (--repeat, --sweep), each with a fresh graph and written as usual.
// Before run i, `prepare(i)` sets it up (it may change `spec`, which run i then measures) and
// names it for the progress line; after it, `record` keeps its figures. Ends early on an interrupt
// (during a run or a preparation) or when a result cannot be written. The exit status is the
// first failing run's, or 128 + the signal when interrupted; `first` is the first results file
// written.
struct SeveralRuns {
  int code = kExitOk;
  std::optional<fs::path> first;
};
SeveralRuns run_several(
    const harness::BenchmarkSpec& spec, const RunArgs& a, const harness::RunOptions& o,
    std::size_t runs, const std::function<std::string(std::size_t)>& prepare,
    const std::function<void(const harness::RunResult&, const WrittenRun&)>& record) {
  const InterruptHandling interrupts;  // also over the preparations (--repeat-pause)
  SeveralRuns out;
  for (std::size_t i = 0; i < runs; ++i) {
    const std::string label = prepare(i);
    if (g_interrupted.load() != 0) break;
    if (!a.quiet) std::fprintf(stderr, "[%s] %s\n", spec.id.c_str(), label.c_str());
    harness::RunResult result = measure(spec, o);
    const WrittenRun written = write_run(spec, a, result);
    record(result, written);
    if (!out.first) out.first = written.json;
    if (written.code != kExitOk && out.code == kExitOk) out.code = written.code;
    if (result.interrupted || written.code == kExitError) break;
  }
  if (g_interrupted.load() != 0 && out.code == kExitOk) out.code = 128 + g_interrupted.load();
  return out;
}

// The summary of several runs: printed, and written beside the first of them as
// <first>.<kind>.json ("series", "sweep").
void write_summary(const SeveralRuns& runs, const std::string& kind, const std::string& table,
                   const nlohmann::json& summary) {
  std::cout << "\n" << table;
  if (!runs.first) return;
  const fs::path path = fs::path(*runs.first).replace_extension("." + kind + ".json");
  report::write_file_atomically(path, json_text(summary, 2) + "\n");
  std::cout << kind << ": " << path.string() << "\n";
}

// --repeat N: N runs; then the run-to-run view of the headline figures (report::series_summary).
int run_series(const harness::BenchmarkSpec& spec, const RunArgs& a, const harness::RunOptions& o) {
  report::Series series(spec.id);
  const SeveralRuns runs = run_several(
      spec, a, o, a.repeat,
      [&](std::size_t i) {
        if (i > 0 && a.repeat_pause > 0) {
          // Interruptible: a Ctrl-C during the pause ends the series like one during a run.
          const auto until =
              std::chrono::steady_clock::now() + std::chrono::duration<double>(a.repeat_pause);
          while (std::chrono::steady_clock::now() < until && g_interrupted.load() == 0)
            std::this_thread::sleep_for(std::chrono::milliseconds(50));
        }
        return "run " + std::to_string(i + 1) + " of " + std::to_string(a.repeat);
      },
      [&](const harness::RunResult& result, const WrittenRun& written) {
        series.add(result, written.json);
      });
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
  report::Sweep sweep(spec.id, parameter);
  const SeveralRuns runs = run_several(
      spec, a, o, values.size(),
      [&](std::size_t i) {
        spec.workload[parameter] = values[i];
        return parameter + " = " + values[i];
      },
      [&](const harness::RunResult& result, const WrittenRun& written) {
        sweep.add(spec.workload[parameter], result, written.json);
      });
  write_summary(runs, "sweep", report::sweep_table(sweep), report::sweep_json(sweep));
  return runs.code;
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

// --host NAME=COMMAND for the hosts the graph names, checked; --netns replaces them.
std::map<std::string, std::vector<std::string>> host_launchers(const harness::BenchmarkSpec& spec,
                                                               const RunArgs& a) {
  const auto hosts = spec.hosts();
  if (a.netns && hosts.empty()) {
    throw std::invalid_argument("--netns puts the graph's hosts in network namespaces, but " +
                                spec.id + " places no node on a host (graph.yaml host:)");
  }
  if (a.netns && !a.hosts.empty())
    throw std::invalid_argument("--netns makes the hosts' launchers itself: not with --host");
  if (a.netns && hosts.size() > 1) {
    throw std::invalid_argument("--netns makes one other host, and " + spec.id + " names " +
                                std::to_string(hosts.size()) + "; give each a --host launcher");
  }
  if (!a.netns && (a.link_rate != "1gbit" || !a.netem.empty()))
    throw std::invalid_argument(
        "--link-rate and --netem shape the link --netns makes: add --netns");
  std::map<std::string, std::vector<std::string>> out;
  for (const auto& entry : a.hosts) {
    const auto equals = entry.find('=');
    const std::string name = entry.substr(0, equals);
    if (equals == std::string::npos || !harness::valid_host_name(name))
      throw std::invalid_argument("--host " + entry + ": expected NAME=COMMAND");
    if (std::ranges::find(hosts, name) == hosts.end()) {
      throw std::invalid_argument("--host " + name + ": " + spec.id +
                                  " places no node on that host (graph.yaml host:)");
    }
    std::istringstream words(entry.substr(equals + 1));
    for (std::string w; words >> w;) out[name].push_back(w);
    if (out[name].empty()) throw std::invalid_argument("--host " + entry + ": no command");
  }
  return out;
}

// A list of devices as results record them.
nlohmann::json devices_json(const std::vector<plugin::DeviceInfo>& devices) {
  nlohmann::json list = nlohmann::json::array();
  for (const auto& d : devices) list.push_back(harness::device_to_json(d));
  return list;
}

int run(const Roots& roots, const RunArgs& a) {
  auto spec = harness::find_benchmark(roots, a.id);
  for (const std::string& assignment : a.workload) {
    const auto equals = assignment.find('=');
    if (equals == std::string::npos || equals == 0)
      throw std::invalid_argument("--workload " + assignment + ": expected KEY=VALUE");
    spec.workload[assignment.substr(0, equals)] = assignment.substr(equals + 1);
  }
  harness::RunOptions o;
  if (a.dataset) {
    // A bag replaces the generated dataset, so its workload parameters would change nothing.
    if (!a.workload.empty() || a.sweep)
      throw std::invalid_argument(std::string(a.sweep ? "--sweep" : "--workload") +
                                  " sets the generated dataset's parameters: not with --dataset");
    o.bag = bag_selection(a);
  }
  if (a.rate_scale != 1.0 && a.rate != "bag")
    throw std::invalid_argument("--rate-scale only applies with --rate bag");
  if (a.rate == "bag") {
    o.bag_timeline = true;
    o.rate_scale = a.rate_scale;
  } else if (a.rate) {
    o.rate_hz = decimal<double>(*a.rate);
    if (!o.rate_hz)
      throw std::invalid_argument("--rate " + *a.rate + ": expected a rate in Hz or 'bag'");
  }
  o.arrival = harness::ArrivalPattern::parse(a.arrival);
  if (a.arrival_seed && o.arrival.kind != harness::ArrivalPattern::Kind::kPoisson)
    throw std::invalid_argument("--arrival-seed only applies with --arrival poisson");
  if (a.arrival_seed) o.arrival.seed = *a.arrival_seed;
  o.monitor_wait = a.monitor_wait == "spin" ? graph::WaitMode::kSpin : graph::WaitMode::kSleep;
  o.update_rate_hz = a.update_rate;
  // Said before anything else of the run: a backend this build lacks is named by no kernel.
  if (a.backend) harness::check_backend_available(*a.backend);
  o.backend = a.backend;
  o.device_resident = a.device_resident;
  o.count = a.count;
  o.duration_s = a.duration;
  o.warmup = a.warmup;
  o.drain_s = a.drain;
  const std::string processes = a.processes.value_or(spec.processes);
  // An external graph's nodes are reached through DDS, as per-node children are.
  o.rmw = a.rmw.value_or(processes == "per-node" || spec.external() ? "fastdds" : "intra");
  o.log_dir = a.output;
  o.host_launchers = host_launchers(spec, a);
  o.keystore = a.security;
  o.ros_distro = rmw::ros_distro_from_name(a.ros_distro);
  // Made before any participant, so that all of this process's sockets are on the runner's side.
  std::optional<harness::NetworkLink> link;
  if (a.netns) {
    link.emplace(harness::LinkShaping{a.link_rate == "none" ? "" : a.link_rate, a.netem});
    link->enter_runner_side();
    for (const auto& host : spec.hosts()) o.host_launchers[host] = link->launcher();
    o.network_link = &*link;
  }
  if (!a.domain) {
    o.domain_id = rmw::domain_id_from_environment();
  } else if (*a.domain == "auto") {
    o.domain_id = rmw::find_quiet_domain(o.rmw);
    if (!a.quiet) std::fprintf(stderr, "robotperf: --domain auto: domain %d\n", o.domain_id);
  } else {
    o.domain_id = rmw::parse_domain_id(*a.domain).value();  // checked when parsed
  }
  o.processes =
      processes == "per-node" ? harness::ProcessLayout::kPerNode : harness::ProcessLayout::kSingle;
  // Every child loads the plug-ins this process was given (the package's own `plugins:` it
  // loads with the package, ROBOTPERF_PLUGIN_PATH it inherits).
  o.node_command = {self_executable().string()};
  for (const auto& p : a.plugins) o.node_command.insert(o.node_command.end(), {"--plugin", p});
  o.node_command.push_back("node");
  o.power = a.power.options();
  o.scheduling = a.scheduling.options();
  o.strict = a.strict;
  o.callback_timeout_s = a.callback_timeout_s;
  o.connect_timeout_s = a.connect_timeout_s;
  o.interrupted = &g_interrupted;
  if (!a.quiet && isatty(STDERR_FILENO)) {
    o.progress = [&](std::size_t sent, std::size_t total, std::size_t received) {
      std::fprintf(stderr, "\r[%s] sent %zu/%zu  received %zu ", spec.id.c_str(), sent, total,
                   received);
      if (sent == total) std::fputc('\n', stderr);
    };
  }
  // Fail on an unwritable output folder, or a sub-buffer size LTTng refuses, before spending time
  // on the run.
  require_writable_folder(a.output, "--output");
  if (a.mode == "grey" && a.trace_subbuf != 0) tracing::check_subbuffer_bytes(a.trace_subbuf);
  if (a.mode == "grey") {
    o.mode = harness::RunMode::kGrey;
    // Recorded under a temporary name, renamed after the results file once the run is named.
    o.trace_dir = fs::path(a.output) / (".trace-" + std::to_string(getpid()));
    o.trace_subbuf_bytes = a.trace_subbuf;
  }

  if (a.find_peak) {
    if (a.mode == "grey") throw std::invalid_argument("--find-peak runs black-box only");
    if (a.repeat > 1) throw std::invalid_argument("--find-peak is one search: not with --repeat");
    harness::PeakSearchOptions search = peak_search_options(a);
    o.duration_s.reset();
    o.progress = nullptr;
    const InterruptHandling interrupts;
    std::size_t steps = 0;
    auto found = harness::find_peak(spec, o, search, [&](const harness::PeakStep& s) {
      if (a.quiet) return;
      std::fprintf(stderr, "[%s] peak search step %zu: %.1f Hz: %s\n", spec.id.c_str(), ++steps,
                   s.rate_hz, s.passed ? "sustained" : ("failed: " + s.reason).c_str());
    });
    if (!found.peak) {
      std::cout << report::peak_search_table(found.record);
      std::cout << "result: no rate met the bounds; nothing written\n";
      return g_interrupted.load() ? 128 + g_interrupted.load() : kExitInvalidResult;
    }
    const int code = write_run(spec, a, *found.peak).code;
    // An interrupted search still writes the peak it had found; the exit status says it stopped.
    return g_interrupted.load() != 0 ? 128 + g_interrupted.load() : code;
  }
  if (a.sweep) {
    if (a.repeat > 1) throw std::invalid_argument("--sweep runs once per value: not with --repeat");
    return run_sweep(spec, a, o);
  }
  if (a.repeat > 1) return run_series(spec, a, o);
  harness::RunResult result = measure(spec, o);
  return write_run(spec, a, result).code;
}

struct TraceArgs {
  std::string dir;
  std::string json;
  int pid = 0;
};

// `trace analyze`: the grey-box analysis of any CTF trace folder.
int analyze(const TraceArgs& a) {
  const auto analysis = tracing::analyze_trace(a.dir, {.run_pid = a.pid, .extra_processes = {}});
  // A process the trace has no run of is a wrong --pid, not an invalid run.
  if (a.pid != 0 && !analysis.run) {
    throw std::invalid_argument(tracing::missing_run(analysis, a.pid) +
                                (analysis.run_pids.empty()
                                     ? ": leave --pid out to analyse the trace's other events"
                                     : ": give --pid one of those, or leave it out for the first"));
  }
  std::cout << tracing::analysis_summary(analysis);
  if (!a.json.empty()) {
    nlohmann::json j = tracing::to_json(analysis);
    j["valid"] = analysis.valid;
    j["reasons"] = analysis.invalid_reasons;
    if (analysis.run) {
      j["run"] = {
          {"benchmark", analysis.run->benchmark},
          {"rmw", analysis.run->rmw},
          {"pid", analysis.run->pid},
          {"sent", analysis.sent},
          {"measured", analysis.measured},
          {"matched", analysis.matched},
          {"lost", analysis.lost},
          {"unobserved", analysis.unobserved},
          {"duplicates", analysis.duplicates},
          {"repeats", analysis.repeats},
          {"unknown", analysis.unknown},
          {"latency_ms",
           {{"from_scheduled", metrics::to_json(analysis.latency_from_scheduled, 1e-6, "ms")},
            {"from_sent", metrics::to_json(analysis.latency_from_sent, 1e-6, "ms")}}},
          {"throughput_hz", analysis.throughput_hz}};
    }
    report::write_output(a.json, json_text(j, 2) + "\n");
  }
  return analysis.valid ? kExitOk : kExitInvalidResult;
}

// Results files named on the command line: files, or folders whose results files are taken.
std::vector<report::StoredRun> collect_runs(const std::vector<std::string>& paths) {
  std::vector<report::StoredRun> runs;
  for (const auto& p : paths.empty() ? std::vector<std::string>{"results"} : paths) {
    if (fs::is_directory(p)) {
      auto scan = report::scan_results(p);
      for (const auto& s : scan.skipped) std::fprintf(stderr, "robotperf: skipped %s\n", s.c_str());
      for (auto& r : scan.runs) runs.push_back(std::move(r));
    } else {
      runs.push_back(report::load_run(p));
    }
  }
  return runs;
}

struct ExportArgs {
  std::vector<std::string> results;
  std::string format = "benchmark-yaml";
  std::string merge, output = "-";
  bool merge_package = false;
  bool include_invalid = false;
  std::string hardware, category;
};

int export_results(const Roots& roots, const ExportArgs& a) {
  const auto runs = collect_runs(a.results);
  report::ExportOptions options{a.hardware, a.category};
  // Entries per target file ("" = standard output), in run order.
  std::vector<std::pair<fs::path, std::vector<report::PublishedResult>>> targets;
  auto target = [&](const fs::path& file) -> std::vector<report::PublishedResult>& {
    for (auto& [f, entries] : targets) {
      if (f == file) return entries;
    }
    return targets.emplace_back(file, std::vector<report::PublishedResult>{}).second;
  };
  std::size_t skipped_invalid = 0;
  // Entries merged into one benchmark's file must be that benchmark's.
  std::string merge_id;
  if (!a.merge.empty()) merge_id = report::import_benchmark_yaml(a.merge).id;
  for (const auto& run : runs) {
    if (!run.valid && !a.include_invalid) {
      ++skipped_invalid;
      continue;
    }
    if (!a.merge.empty() && run.benchmark_id != merge_id) {
      throw std::invalid_argument(run.path.string() + " is a run of " + run.benchmark_id +
                                  ", not of " + merge_id + " (the id of " + a.merge +
                                  "): nothing merged; give only " + merge_id +
                                  " runs, or use --merge-package");
    }
    fs::path file = a.merge;
    if (a.merge_package)
      file = harness::find_benchmark(roots, run.benchmark_id).dir / "benchmark.yaml";
    auto& entries = target(file);
    for (auto& e : report::export_entries(run, options)) entries.push_back(std::move(e));
  }
  if (skipped_invalid)
    std::fprintf(stderr,
                 "robotperf: left out %zu invalid run(s) (--include-invalid exports them)\n",
                 skipped_invalid);
  if (targets.empty()) {
    std::fprintf(stderr, "robotperf: no valid runs to export\n");
    return kExitUsage;
  }
  for (const auto& [file, entries] : targets) {
    if (file.empty()) {
      report::write_output(a.output, report::entries_yaml(entries));
      if (!report::is_standard_output(a.output)) std::cout << a.output << "\n";
      continue;
    }
    std::ifstream in(file, std::ios::binary);
    if (!in)
      throw report::ReportError(file.string() + ": cannot read the benchmark.yaml to merge into");
    const std::string original{std::istreambuf_iterator<char>(in), {}};
    const auto merged = report::merge_entries(original, file.string(), entries);
    if (merged.added) report::write_file_atomically(file, merged.text);
    std::cout << file.string() << ": added " << merged.added << " result(s)";
    if (merged.already_present) std::cout << ", " << merged.already_present << " already there";
    std::cout << "\n";
  }
  return kExitOk;
}

int import_published(const std::vector<std::string>& paths, const std::string& into) {
  std::vector<fs::path> files;
  for (const auto& p : paths) {
    if (fs::is_directory(p) && !fs::exists(fs::path(p) / "benchmark.yaml")) {
      for (const auto& e : fs::recursive_directory_iterator(p)) {
        if (e.path().filename() == "benchmark.yaml") files.push_back(e.path());
      }
    } else {
      files.emplace_back(p);
    }
  }
  std::sort(files.begin(), files.end());
  if (files.empty()) throw report::ReportError("no benchmark.yaml found in the given paths");
  // Read everything before printing anything: a bad file gives one line and nothing else.
  std::vector<report::PublishedBenchmark> benchmarks;
  for (const auto& f : files) benchmarks.push_back(report::import_benchmark_yaml(f));
  std::printf("%-8s %-44s %6s %8s %8s %6s %8s\n", "id", "name", "rows", "latency", "through.",
              "power", "flagged");
  std::string flagged;
  for (const auto& b : benchmarks) {
    std::size_t lat = 0, thr = 0, pow = 0;
    for (const auto& r : b.results) {
      lat += r.metric == "latency";
      thr += r.metric == "throughput";
      pow += r.metric == "power";
    }
    std::printf("%-8s %-44s %6zu %8zu %8zu %6zu %8zu\n", b.id.c_str(), b.name.c_str(),
                b.results.size(), lat, thr, pow, b.flagged());
    flagged += report::flagged_rows_report(b);
    if (!into.empty()) {
      const fs::path out = fs::path(into) / ("published-" + b.category + "-" + b.name + ".json");
      report::write_file_atomically(out, json_text(report::to_json(b), 1) + "\n");
    }
  }
  if (!flagged.empty()) std::cout << "\nrows that break the measurement rules:\n" << flagged;
  if (!into.empty())
    std::cout << "\nimported into " << into << " (robotperf report " << into << " plots them)\n";
  return kExitOk;
}

int readme(const Roots& roots, const std::vector<std::string>& ids, bool check) {
  int status = kExitOk;
  for (const auto& id : ids) {
    const auto spec = harness::find_benchmark(roots, id);
    const fs::path file = spec.dir / "README.md";
    const std::string text = report::render_package_readme(spec.dir);
    if (check) {
      std::ifstream in(file, std::ios::binary);
      const std::string current{std::istreambuf_iterator<char>(in), {}};
      if (current != text) {
        std::fprintf(stderr, "robotperf: %s is out of date; run: robotperf readme %s\n",
                     file.c_str(), spec.id.c_str());
        status = kExitError;
      }
      continue;
    }
    report::write_file_atomically(file, text);
    std::cout << file.string() << "\n";
  }
  return status;
}

struct ReportArgs {
  std::vector<std::string> inputs;
  std::string html, md, title = "robotperf report";
  std::vector<std::string> compare;
};

int make_report(const ReportArgs& a) {
  if (a.html.empty() && a.md.empty())
    throw std::invalid_argument("report: say where to write it: --html FILE and/or --md FILE");
  if (!a.compare.empty() && a.compare.size() != 2)
    throw std::invalid_argument(
        "report: --compare takes exactly two selectors (--compare A --compare B)");
  std::vector<fs::path> paths;
  for (const auto& p : a.inputs.empty() ? std::vector<std::string>{"results"} : a.inputs)
    paths.emplace_back(p);
  const auto input = report::load_report_inputs(paths);
  for (const auto& s : input.skipped) std::fprintf(stderr, "robotperf: skipped %s\n", s.c_str());
  if (input.runs.empty() && input.published.empty())
    throw report::ReportError(
        "nothing to report: no results files or benchmark.yaml in the given paths");
  report::ReportOptions options;
  options.title = a.title;
  if (a.compare.size() == 2) options.compare = std::pair{a.compare[0], a.compare[1]};
  if (!a.html.empty() && !a.md.empty() && report::is_standard_output(a.html) &&
      report::is_standard_output(a.md)) {
    throw std::invalid_argument("report: only one of --html and --md can be - (standard output)");
  }
  // Standard output carries the report alone; where a file went is said on stderr then.
  std::ostream& said = report::is_standard_output(a.html) || report::is_standard_output(a.md)
                           ? std::cerr
                           : std::cout;
  if (!a.html.empty()) {
    report::write_output(a.html, report::render_html(input, options));
    if (!report::is_standard_output(a.html)) said << "report: " << a.html << "\n";
  }
  if (!a.md.empty()) {
    report::write_output(a.md, report::render_markdown(input, options));
    if (!report::is_standard_output(a.md)) said << "report: " << a.md << "\n";
  }
  return kExitOk;
}

// `compare A B`: the report's comparison in the terminal. A side that is a results file is read
// even when it is not in the results folders.
int compare_in_terminal(const std::string& a, const std::string& b,
                        const std::vector<std::string>& results) {
  std::vector<fs::path> paths;
  for (const auto& p : results) paths.emplace_back(p);
  if (results.empty()) {
    std::error_code ec;
    if (fs::is_directory("results", ec)) paths.emplace_back("results");
    for (const auto& side : {a, b}) {
      if (side.ends_with(".json") && fs::is_regular_file(side, ec)) paths.emplace_back(side);
    }
  }
  if (paths.empty())
    throw report::ReportError(
        "compare: no ./results folder here; name the results with --results DIR");
  const auto input = report::load_report_inputs(paths);
  for (const auto& s : input.skipped) std::fprintf(stderr, "robotperf: skipped %s\n", s.c_str());
  std::cout << report::render_comparison_text(input, a, b);
  return kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "robotperf — benchmarking suite for robotics computing (ROS 2 graphs, black-box and "
      "grey-box)"};
  app.set_version_flag("--version",
                       std::string(build_info::kVersion) + " (" + build_info::kGitRevision + ")");
  app.require_subcommand(1);
  // Global options may also follow the subcommand (robotperf run a1 --plugin lib.so).
  app.fallthrough();
  std::vector<std::string> benchmarks_flags, plugin_flags;
  app.add_option("--benchmarks", benchmarks_flags,
                 "also use the benchmark packages of this folder (<category>/<package>/; "
                 "repeatable)");
  app.add_option("--plugin", plugin_flags,
                 "load this plug-in (a shared library built against robotperf; repeatable)");

  std::string list_what = "benchmarks";
  auto* list_cmd = app.add_subcommand(
      "list", "list the benchmarks, or the registered kernels, datasets or evaluators");
  list_cmd->add_option("what", list_what, "benchmarks (default), kernels, datasets or evaluators")
      ->check(CLI::IsMember({"benchmarks", "kernels", "datasets", "evaluators"}));

  std::string describe_id;
  auto* describe_cmd =
      app.add_subcommand("describe", "show a benchmark's graph, dataset and settings");
  describe_cmd->add_option("id", describe_id, "benchmark id or name, e.g. a1")->required();

  RunArgs ra;
  auto* run_cmd = app.add_subcommand("run", "run a benchmark and print its summary");
  run_cmd->add_option("id", ra.id, "benchmark id or name, e.g. a1")->required();
  run_cmd->add_option("--rate", ra.rate,
                      "input rate in Hz (default: the benchmark's), or 'bag': the bag's own "
                      "timeline");
  run_cmd->add_option("--update-rate", ra.update_rate,
                      "control benchmarks: the controller manager's loop rate in Hz (default: "
                      "the graph's update_rate), e.g. 1000 to stress the loop");
  run_cmd
      ->add_option("--callback-timeout", ra.callback_timeout_s,
                   "seconds a node's callback may run before the run ends with the node named "
                   "as hung (default 30)")
      ->check(kPositive);
  run_cmd->add_option("--rate-scale", ra.rate_scale, "with --rate bag: play this many times faster")
      ->check(kPositive);
  auto* dataset_opt = run_cmd->add_option(
      "--dataset", ra.dataset, "replay this rosbag2 bag (directory, .db3 or .mcap) as the input");
  run_cmd
      ->add_option("--remap", ra.remaps, "bag topic onto a benchmark input: from:=to (repeatable)")
      ->needs(dataset_opt);
  run_cmd->add_option("--window", ra.window, "only the bag's messages in START:END seconds")
      ->needs(dataset_opt);
  auto* find_peak_flag = run_cmd->add_flag(
      "--find-peak", ra.find_peak,
      "search for the highest input rate the graph sustains (each step a full run of --duration "
      "seconds, default 5, from --rate or the benchmark's rate upwards)");
  run_cmd
      ->add_option("--loss-bound", ra.loss_bound,
                   "with --find-peak: the most loss (%) a sustained rate may have (default: the "
                   "benchmark's max_loss_percent)")
      ->needs(find_peak_flag);
  run_cmd
      ->add_option("--latency-bound", ra.latency_bound,
                   "with --find-peak: the latency (ms) the --latency-percentile must stay within")
      ->needs(find_peak_flag);
  run_cmd
      ->add_option("--latency-percentile", ra.latency_percentile,
                   "with --latency-bound: which percentile of the latency (default 99)")
      ->needs(find_peak_flag);
  run_cmd
      ->add_option("--rate-range", ra.rate_range,
                   "with --find-peak: LO:HI, the rates searched (default: from the start rate to "
                   "1 MHz)")
      ->needs(find_peak_flag);
  run_cmd
      ->add_option("--peak-resolution", ra.peak_resolution,
                   "with --find-peak: stop bisecting when the failing rate is within this many "
                   "percent of the sustained one (default 5)")
      ->needs(find_peak_flag);
  run_cmd
      ->add_option("--repeat", ra.repeat,
                   "run N times, each with a fresh graph, and summarise the series: the median of "
                   "each headline figure with its 95 % interval and the run-to-run spread")
      ->transform(whole_number(1, 10000));
  run_cmd->add_option("--repeat-pause", ra.repeat_pause, "with --repeat: seconds between runs")
      ->check(number_between(0.0, 3600.0));
  run_cmd->add_option("--workload", ra.workload,
                      "KEY=VALUE: a workload parameter of the benchmark's dataset, over "
                      "benchmark.yaml's (repeatable; `list datasets` names them)");
  auto* sweep_opt = run_cmd->add_option(
      "--sweep", ra.sweep,
      "KEY=V1,V2,...: one run per value of a workload parameter, then the values side by side "
      "(e.g. payload_bytes=64,1024,65536,1048576,4194304 for n1 and n2)");
  find_peak_flag->excludes(sweep_opt);
  run_cmd->add_option("--arrival", ra.arrival,
                      "when messages are sent at the rate: fixed (default), poisson (random "
                      "intervals of mean 1/rate) or burst:N (N back to back every N/rate)");
  run_cmd
      ->add_option("--arrival-seed", ra.arrival_seed,
                   "with --arrival poisson: the schedule's seed (default 1)")
      ->transform(whole_number(0));
  run_cmd
      ->add_option("--monitor-wait", ra.monitor_wait,
                   "how the Monitor waits for outputs: sleep (default; each latency includes a "
                   "thread wake-up) or spin (no wake-up; keeps one core busy during the run)")
      ->check(CLI::IsMember({"sleep", "spin"}));
  auto* count_opt = run_cmd->add_option("--count", ra.count, "messages to send, warm-up included")
                        ->transform(whole_number(1));
  find_peak_flag->excludes(count_opt);
  run_cmd->add_option("--duration", ra.duration, "seconds to send for (count = rate x duration)")
      ->excludes(count_opt);
  run_cmd
      ->add_option("--warmup", ra.warmup, "first messages not counted (default: the benchmark's)")
      ->transform(whole_number(0));
  run_cmd->add_option("--drain", ra.drain, "seconds to wait for outputs after the last send");
  run_cmd
      ->add_option("--rmw", ra.rmw,
                   "transport: intra, fastdds or cyclonedds (default: intra; fastdds for a "
                   "per-node layout)")
      ->check(CLI::IsMember({"intra", "fastdds", "cyclonedds"}));
  run_cmd->add_option("--backend", ra.backend,
                      "run every node whose kernel has this backend on it (cpu, opencl, cuda in a "
                      "build with the CUDA toolkit, or a plug-in's); the others stay on theirs "
                      "(see robotperf list kernels)");
  run_cmd->add_flag("--device-resident", ra.device_resident,
                    "keep images on the device between nodes that can hand them over there "
                    "(type adaptation, as NITROS; e.g. a1 with --backend cuda): a configuration "
                    "of its own, not the host-memory baseline");
  run_cmd
      ->add_option("--processes", ra.processes,
                   "single (all nodes in one process) or per-node (default: the benchmark's)")
      ->check(CLI::IsMember({"single", "per-node"}));
  run_cmd
      ->add_option("--domain", ra.domain,
                   "DDS domain id, or 'auto': one no other participant uses (default: "
                   "ROS_DOMAIN_ID or 0)")
      ->transform(domain_id_check(true));
  run_cmd
      ->add_option("--host", ra.hosts,
                   "NAME=COMMAND: how to start a process on a host graph.yaml names (default: "
                   "ssh NAME --); repeatable")
      ->type_name("NAME=COMMAND");
  run_cmd->add_flag("--netns", ra.netns,
                    "run the graph's other host in a network namespace of its own, joined to "
                    "the runner's by a veth pair (needs root)");
  run_cmd->add_option("--link-rate", ra.link_rate,
                      "--netns: the link's rate limit, as tc writes it (default: 1gbit; none: "
                      "unshaped)");
  run_cmd->add_option("--netem", ra.netem,
                      "--netns: netem's delay, jitter and loss on the link, e.g. "
                      "\"delay 1ms 0.1ms loss 0.1%\"");
  run_cmd
      ->add_option("--connect-timeout", ra.connect_timeout_s,
                   "seconds the graph may take to start and connect before the run is refused "
                   "(default 15)")
      ->check(number_between(0.1, 3600.0));
  run_cmd
      ->add_option("--security", ra.security,
                   "DDS Security: every participant presents the /robotperf enclave of this "
                   "keystore (robotperf security init DIR makes one)")
      ->type_name("DIR");
  run_cmd
      ->add_option("--ros-distro", ra.ros_distro,
                   "ROS 2 release the DDS participants announce themselves as to the graph's "
                   "nodes: humble (24-byte GIDs, no type hashes), iron or jazzy (default)")
      ->check(CLI::IsMember({"humble", "iron", "jazzy"}));
  run_cmd->add_option("--output", ra.output, "folder for the results files (default: ./results)");
  run_cmd->add_flag("--csv", ra.csv, "also write the per-message latencies as CSV");
  run_cmd->add_flag("--quiet", ra.quiet, "no progress line");
  run_cmd->add_flag("--report", ra.report,
                    "also write the HTML report of the run next to its results");

  auto* results_cmd = app.add_subcommand("results", "the results folder: list, export, import");
  results_cmd->require_subcommand(1);
  std::string list_dir = "results";
  auto* results_list_cmd = results_cmd->add_subcommand("list", "show the runs of a results folder");
  results_list_cmd->add_option("dir", list_dir, "results folder (default: ./results)");
  std::string list_format = "table";
  results_list_cmd
      ->add_option("--format", list_format,
                   "table (default), json (an array of objects) or csv (a header line, then one "
                   "line per run)")
      ->check(CLI::IsMember({"table", "json", "csv"}));
  ExportArgs ea;
  auto* export_cmd = results_cmd->add_subcommand(
      "export", "turn runs into RobotPerf benchmark.yaml result entries");
  export_cmd->add_option("results", ea.results, "results files or folders (default: ./results)");
  export_cmd->add_option("--format", ea.format, "output format")
      ->check(CLI::IsMember({"benchmark-yaml"}));
  auto* output_opt = export_cmd->add_option(
      "--output,-o", ea.output, "write the entries to this file (default -: standard output)");
  auto* merge_opt = export_cmd->add_option(
      "--merge", ea.merge,
      "append the entries to this benchmark.yaml (existing entries untouched; runs of another "
      "benchmark are refused)");
  merge_opt->excludes(output_opt);
  export_cmd
      ->add_flag("--merge-package", ea.merge_package,
                 "append each run's entries to its benchmark package's benchmark.yaml")
      ->excludes(merge_opt)
      ->excludes(output_opt);
  export_cmd->add_option("--hardware", ea.hardware,
                         "hardware name to record (default: from the machine description)");
  export_cmd->add_option("--category", ea.category, "RobotPerf category (default: guessed)")
      ->check(CLI::IsMember({"edge", "workstation", "datacenter", "cloud"}));
  export_cmd->add_flag("--include-invalid", ea.include_invalid, "also export invalid runs");
  std::vector<std::string> import_paths;
  std::string import_into;
  auto* import_cmd = results_cmd->add_subcommand(
      "import", "read published RobotPerf benchmark.yaml files and flag rows that break the rules");
  import_cmd->add_option("files", import_paths, "benchmark.yaml files or folders holding them")
      ->required();
  import_cmd->add_option("--into", import_into,
                         "also store them in this results folder, for robotperf report");

  std::vector<std::string> readme_ids;
  bool readme_check = false;
  auto* readme_cmd = app.add_subcommand(
      "readme", "regenerate benchmark packages' README.md from their benchmark.yaml");
  readme_cmd->add_option("ids", readme_ids, "benchmark ids, e.g. a1 a2 a5")->required();
  readme_cmd->add_flag("--check", readme_check, "only check that README.md is up to date");

  ReportArgs rpa;
  auto* report_cmd = app.add_subcommand(
      "report", "HTML and Markdown report: radar plots across hardware, runs, distributions");
  report_cmd->add_option("results", rpa.inputs,
                         "results files, imported files, benchmark.yaml files or folders "
                         "(default: ./results)");
  report_cmd->add_option("--html", rpa.html, "write the HTML report here (- : standard output)");
  report_cmd->add_option("--md", rpa.md, "write the Markdown report here (- : standard output)");
  report_cmd->add_option("--title", rpa.title, "report title");
  report_cmd->add_option("--compare", rpa.compare,
                         "compare two sides (give it twice): a results file or name prefix, "
                         "or a hardware name");
  run_cmd->add_flag("--strict", ra.strict,
                    "refuse to run when a run rule is broken (see the warnings of a normal run)");
  add_power_options(run_cmd, ra.power, true);
  add_scheduling_options(run_cmd, ra.scheduling);
  run_cmd
      ->add_option("--mode", ra.mode,
                   "black (Playback/Monitor) or grey (also record an LTTng trace and take the "
                   "results from it)")
      ->check(CLI::IsMember({"black", "grey"}));
  run_cmd
      ->add_option("--trace-subbuf-size", ra.trace_subbuf,
                   "grey: per-CPU LTTng sub-buffer bytes (default: sized for the workload)")
      ->transform(whole_number(0));

  std::string compare_a, compare_b;
  std::vector<std::string> compare_results;
  auto* compare_cmd = app.add_subcommand(
      "compare",
      "compare two runs or configurations in the terminal: medians, ratio B/A, significance");
  compare_cmd
      ->add_option("A", compare_a,
                   "a results file, a file-name prefix (a1-intra), a hardware or series name, or "
                   "fields: hardware=,rmw=,processes=,backend=,mode=,arrivals=,monitor=,rate=")
      ->required();
  compare_cmd->add_option("B", compare_b, "the other side, as A")->required();
  compare_cmd->add_option("--results", compare_results,
                          "results files or folders, imported published rows included (default: "
                          "./results, and A and B where they are files)");

  TraceArgs ta;
  auto* trace_cmd = app.add_subcommand("trace", "work with LTTng traces");
  trace_cmd->require_subcommand(1);
  auto* analyze_cmd = trace_cmd->add_subcommand(
      "analyze", "grey-box analysis of a CTF trace (robotperf or ros2_tracing)");
  analyze_cmd->add_option("dir", ta.dir, "the trace folder (searched for CTF metadata)")
      ->required();
  analyze_cmd->add_option("--json", ta.json, "also write the analysis as JSON to this file");
  analyze_cmd
      ->add_option("--pid", ta.pid,
                   "analyse the robotperf run of this process (default: the first)")
      ->transform(whole_number(0, std::numeric_limits<int>::max()));

  auto* bag_cmd = app.add_subcommand("bag", "inspect, print and convert rosbag2 bags");
  bag_cmd->require_subcommand(1);
  std::string bag_path;
  auto* bag_info_cmd = bag_cmd->add_subcommand("info", "storage, duration, topics, counts, QoS");
  bag_info_cmd->add_option("bag", bag_path, "bag directory, .db3 or .mcap file")->required();
  cli::EchoOptions echo;
  auto* bag_echo_cmd = bag_cmd->add_subcommand("echo", "print messages as YAML");
  bag_echo_cmd->add_option("bag", bag_path, "bag directory, .db3 or .mcap file")->required();
  bag_echo_cmd->add_option("--topic", echo.topics, "only this topic (repeatable)");
  bag_echo_cmd->add_option("--limit", echo.limit, "print at most N messages")
      ->transform(whole_number(0));
  bag_echo_cmd->add_option("--msg-dir", echo.msg_dirs,
                           "folder of .msg files (<pkg>/msg/*.msg, or flat) for types the bag "
                           "has no definition of");
  bag_echo_cmd
      ->add_option("--max-array", echo.max_array, "summarise arrays longer than this (default 64)")
      ->transform(whole_number(0));
  cli::ConvertOptions convert;
  std::string convert_out;
  auto* bag_convert_cmd = bag_cmd->add_subcommand("convert", "write a bag in another storage");
  bag_convert_cmd->add_option("in", bag_path, "bag directory, .db3 or .mcap file")->required();
  bag_convert_cmd->add_option("out", convert_out, "new bag directory")->required();
  bag_convert_cmd->add_option("--storage", convert.storage, "sqlite3 or mcap (default mcap)")
      ->check(CLI::IsMember({"sqlite3", "mcap"}));
  bag_convert_cmd
      ->add_option("--compression", convert.compression, "MCAP chunks: zstd, lz4 or none")
      ->check(CLI::IsMember({"zstd", "lz4", "none"}));
  bag_convert_cmd->add_option("--chunk-size", convert.chunk_size, "MCAP chunk size in bytes")
      ->transform(whole_number(0));
  bag_convert_cmd->add_option("--max-file-size", convert.max_file_mib,
                              "split into files of about this many MiB (0 = one file)");
  bag_convert_cmd->add_option(
      "--msg-dir", convert.msg_dirs,
      "folder of .msg files giving the definitions the bag lacks, written into the new bag");

  std::string reindex_dir;
  auto* bag_reindex_cmd = bag_cmd->add_subcommand(
      "reindex", "write metadata.yaml for a bag directory that lost it, from its storage files");
  bag_reindex_cmd->add_option("dir", reindex_dir, "bag directory with .db3 or .mcap files")
      ->required();

  auto* dataset_cmd = app.add_subcommand("dataset", "the built-in datasets");
  dataset_cmd->require_subcommand(1);
  std::string dataset_name;
  cli::GenerateOptions generate;
  auto* generate_cmd = dataset_cmd->add_subcommand("generate", "write a built-in dataset as a bag");
  generate_cmd->add_option("name", dataset_name, "a registered dataset (robotperf list datasets)")
      ->required();
  generate_cmd->add_option("--out", generate.out, "bag directory (default: the name, / as _)");
  generate_cmd->add_option("--storage", generate.storage, "sqlite3 or mcap (default mcap)")
      ->check(CLI::IsMember({"sqlite3", "mcap"}));
  generate_cmd->add_option("--compression", generate.compression, "MCAP chunks: zstd, lz4 or none")
      ->check(CLI::IsMember({"zstd", "lz4", "none"}));

  PowerArgs sysinfo_power;
  auto* sysinfo_cmd = app.add_subcommand(
      "sysinfo",
      "describe this machine, this robotperf and the power sources found, as results "
      "record them");
  add_power_options(sysinfo_cmd, sysinfo_power, false);

  std::string node_package, node_name, node_rmw = "fastdds";
  int node_domain = 0;
  auto* node_cmd =
      app.add_subcommand("node", "run one node of a benchmark (used by --processes per-node)");
  node_cmd->group("");  // internal: not listed in --help
  node_cmd->add_option("package", node_package)->required();
  node_cmd->add_option("--node", node_name)->required();
  node_cmd->add_option("--rmw", node_rmw);
  node_cmd->add_option("--domain", node_domain)->transform(domain_id_check(false));
  std::optional<double> node_update_rate;
  node_cmd->add_option("--update-rate", node_update_rate);
  std::optional<std::string> node_backend;
  node_cmd->add_option("--backend", node_backend);
  double node_callback_timeout_s = 30.0;
  node_cmd->add_option("--callback-timeout", node_callback_timeout_s);
  std::string node_run_token;
  node_cmd->add_option("--run-token", node_run_token);
  std::string node_keystore;
  node_cmd->add_option("--security", node_keystore);
  std::string node_ros_distro = "jazzy";
  node_cmd->add_option("--ros-distro", node_ros_distro);

  cli::GraphOptions graph_options;
  auto* graph_cmd = app.add_subcommand(
      "graph", "list the ROS 2 nodes, topics, types and QoS visible on a DDS domain");
  graph_cmd->add_option("--rmw", graph_options.rmw, "fastdds (default) or cyclonedds")
      ->check(CLI::IsMember({"fastdds", "cyclonedds"}));
  graph_cmd->add_option("--domain", graph_options.domain, "DDS domain (default: ROS_DOMAIN_ID)")
      ->transform(domain_id_check(false));
  graph_cmd
      ->add_option("--listen", graph_options.listen_s,
                   "seconds to listen to discovery before listing (default 3)")
      ->check(number_between(0.1, 600.0));
  graph_cmd->add_flag("--json", graph_options.json, "print JSON");

  std::string keystore_dir;
  std::vector<std::string> keystore_enclaves;
  auto* security_cmd = app.add_subcommand("security", "DDS Security keystores (SROS2 layout)");
  security_cmd->require_subcommand(1);
  auto* security_init_cmd = security_cmd->add_subcommand(
      "init",
      "make a keystore: a CA, and per enclave a certificate, key, and signed governance and "
      "permissions (adds missing enclaves to an existing keystore)");
  security_init_cmd->add_option("dir", keystore_dir, "the keystore folder")->required();
  security_init_cmd
      ->add_option("--enclave", keystore_enclaves,
                   "an enclave to make, e.g. /my_robot/camera (default: /robotperf); repeatable")
      ->type_name("NAME");
  SchedulingArgs node_scheduling;
  add_scheduling_options(node_cmd, node_scheduling);

  // Without a command: what the commands are, not only that one is missing.
  if (argc == 1) {
    std::cerr << app.help()
              << "robotperf: give a command (robotperf list, robotperf run a1, ...)\n";
    return kExitUsage;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::Success& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "robotperf: %s (see robotperf --help)\n", e.what());
    return kExitUsage;
  }

  try {
    categories::register_builtin_categories();
    cli::load_plugins(plugin_flags);
    ra.plugins = plugin_flags;
    const Roots roots = benchmark_roots(benchmarks_flags);
    if (*list_cmd) {
      if (list_what == "kernels") return cli::list_kernels(std::cout);
      if (list_what == "datasets") return cli::list_datasets(std::cout);
      if (list_what == "evaluators") return cli::list_evaluators(std::cout);
      return list_benchmarks(roots);
    }
    if (*describe_cmd) return describe_benchmark(roots, describe_id);
    if (*run_cmd) return run(roots, ra);
    if (*results_list_cmd) {
      const auto scan = report::scan_results(list_dir);
      for (const auto& sk : scan.skipped)
        std::fprintf(stderr, "robotperf: skipped %s\n", sk.c_str());
      if (list_format == "json") {
        std::cout << json_text(report::runs_json(scan.runs), 1) << "\n";
      } else {
        std::cout << (list_format == "csv" ? report::runs_csv(scan.runs)
                                           : report::runs_table(scan.runs));
      }
      return kExitOk;
    }
    if (*export_cmd) return export_results(roots, ea);
    if (*import_cmd) return import_published(import_paths, import_into);
    if (*readme_cmd) return readme(roots, readme_ids, readme_check);
    if (*report_cmd) return make_report(rpa);
    if (*compare_cmd) return compare_in_terminal(compare_a, compare_b, compare_results);
    if (*bag_info_cmd) return cli::bag_info(bag_path);
    if (*bag_echo_cmd) return cli::bag_echo(bag_path, echo);
    if (*bag_convert_cmd) return cli::bag_convert(bag_path, convert_out, convert);
    if (*bag_reindex_cmd) return cli::bag_reindex(reindex_dir);
    if (*generate_cmd) return cli::dataset_generate(dataset_name, generate);
    if (*analyze_cmd) return analyze(ta);
    if (*graph_cmd) return cli::ros_graph(graph_options, std::cout);
    if (*sysinfo_cmd) {
      nlohmann::json description = {
          {"machine", sysinfo::to_json(sysinfo::collect_machine_info())},
          {"software", report::software_json()},
          {"power",
           metrics::sources_to_json(metrics::discover_power_sources(sysinfo_power.options()))}};
      // Every registered backend's devices; the host's cpu is the machine above.
      for (const auto* backend : plugin::registry().backends()) {
        description[backend->info.name + "_devices"] = devices_json(
            backend->hooks.devices ? backend->hooks.devices() : std::vector<plugin::DeviceInfo>{});
      }
      std::cout << json_text(description, 2) << "\n";
      return kExitOk;
    }
    if (*node_cmd) {
      harness::BenchmarkSpec spec = harness::load_benchmark(node_package);
      if (node_update_rate) harness::override_update_rate(spec, *node_update_rate);
      if (node_backend) harness::override_backend(spec, *node_backend);
      return harness::run_node_process(spec, node_name, node_rmw, node_domain,
                                       node_scheduling.options(), node_callback_timeout_s,
                                       node_run_token, node_keystore,
                                       rmw::ros_distro_from_name(node_ros_distro));
    }
    if (*security_init_cmd) {
      if (keystore_enclaves.empty()) keystore_enclaves.push_back(rmw::kDefaultEnclave);
      // Named absolutely before it is made, whatever becomes of the current folder.
      const fs::path keystore = fs::absolute(keystore_dir);
      rmw::create_keystore(keystore, keystore_enclaves);
      fs::path shown = keystore.lexically_normal();
      if (!shown.has_filename()) shown = shown.parent_path();  // "dir/." is "dir/"
      std::cout << "keystore: " << shown.string() << "\n";
      for (const auto& enclave : keystore_enclaves) {
        std::cout << "  enclave " << enclave << ": "
                  << rmw::describe(rmw::enclave_files(keystore, enclave)) << "\n";
      }
      std::cout << "use it with: robotperf run n4 --netns --security " << keystore_dir << "\n";
      return kExitOk;
    }
  } catch (const plugin::PluginError& e) {
    std::fprintf(stderr, "robotperf: %s\n", e.what());
    return kExitUsage;
  } catch (const harness::RunInterrupted& e) {
    std::fprintf(stderr, "robotperf: %s\n", e.what());
    return 128 + g_interrupted.load();
  } catch (const harness::RunRefused& e) {
    std::fprintf(stderr, "robotperf: %s\n", e.what());
    return kExitRefused;
  } catch (const bag::BagError& e) {
    std::fprintf(stderr, "robotperf: %s\n", e.what());
    return kExitUsage;
  } catch (const msgs::dynamic::DefinitionError& e) {
    std::fprintf(stderr, "robotperf: %s\n", e.what());
    return kExitUsage;
  } catch (const tracing::TracingUnavailable& e) {
    std::fprintf(stderr, "robotperf: %s\n", e.what());
    return kExitUsage;
  } catch (const tracing::ctf::CtfError& e) {
    std::fprintf(stderr, "robotperf: unreadable trace: %s\n", e.what());
    return kExitUsage;
  } catch (const harness::BenchmarkError& e) {
    std::fprintf(stderr, "robotperf: %s\n", e.what());
    return kExitUsage;
  } catch (const harness::GraphNotConnected& e) {
    std::fprintf(stderr, "robotperf: %s\n", e.what());
    return kExitUsage;
  } catch (const rmw::SecurityError& e) {
    std::fprintf(stderr, "robotperf: %s\n", e.what());
    return kExitUsage;
  } catch (const harness::NetworkSetupError& e) {
    std::fprintf(stderr, "robotperf: %s\n", e.what());
    return kExitUsage;
  } catch (const report::ReportError& e) {
    std::fprintf(stderr, "robotperf: %s\n", e.what());
    return kExitUsage;
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "robotperf: %s\n", e.what());
    return kExitUsage;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "robotperf: %s\n", e.what());
    return kExitError;
  }
  return kExitUsage;
}
