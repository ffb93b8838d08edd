// `robotperf results list|export|import|rebuild-db|push`: the results folder, RobotPerf's
// benchmark.yaml result entries out of it and into it, its database made again from its files,
// and its runs pushed into a lab's shared PostgreSQL database.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <stdexcept>

#include "commands.hpp"
#include "results_source.hpp"
#include "robotperf/cli/exit_codes.hpp"
#include "robotperf/files/atomic_file.hpp"
#include "robotperf/harness/benchmark_spec.hpp"
#include "robotperf/report/benchmark_yaml.hpp"
#include "robotperf/report/run_store.hpp"
#include "robotperf/results_db/postgres_store.hpp"
#include "robotperf/results_db/results_db.hpp"

namespace robotperf::cli {

namespace {

struct ExportArgs {
  std::vector<std::string> results;
  std::string format = "benchmark-yaml";
  std::string merge, output = "-";
  bool merge_package = false;
  bool include_invalid = false;
  std::string hardware, category;
};

// Entries per target file ("" = standard output), in run order.
using ExportTargets = std::vector<std::pair<fs::path, std::vector<report::PublishedResult>>>;

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

// The runs of the folder `dir`, or of the database --from or ROBOTPERF_RESULTS_URL names when no
// folder is named.
int list_results(const std::string& dir, bool dir_named, const std::string& from,
                 const std::string& format, const std::vector<std::string>& labels) {
  std::vector<report::StoredRun> runs;
  if (const auto url = database_to_read(from, dir_named)) {
    runs = runs_from_database(*url);
  } else {
    runs = folder_runs(dir).runs;
  }
  keep_labelled(runs, labels);
  if (format == "json") {
    std::cout << json_text(report::runs_json(runs), 1) << "\n";
  } else {
    std::cout << (format == "csv" ? report::runs_csv(runs) : report::runs_table(runs));
  }
  return kExitOk;
}

// The valid runs' entries (all runs' with --include-invalid), by the file each goes to.
ExportTargets export_targets(const Roots& roots, const ExportArgs& a) {
  const auto runs = collect_runs(a.results);
  report::ExportOptions options{a.hardware, a.category};
  ExportTargets targets;
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
  return targets;
}

// Appends `entries` to the benchmark.yaml `file`, leaving the entries already there.
void merge_into(const fs::path& file, const std::vector<report::PublishedResult>& entries) {
  std::ifstream in(file, std::ios::binary);
  if (!in)
    throw report::ReportError(file.string() + ": cannot read the benchmark.yaml to merge into");
  const std::string original{std::istreambuf_iterator<char>(in), {}};
  const auto merged = report::merge_entries(original, file.string(), entries);
  if (merged.added) files::write_file_atomically(file, merged.text);
  std::cout << file.string() << ": added " << merged.added << " result(s)";
  if (merged.already_present) std::cout << ", " << merged.already_present << " already there";
  std::cout << "\n";
}

int export_results(const Roots& roots, const ExportArgs& a) {
  const ExportTargets targets = export_targets(roots, a);
  if (targets.empty()) {
    std::fprintf(stderr, "robotperf: no valid runs to export\n");
    return kExitUsage;
  }
  for (const auto& [file, entries] : targets) {
    if (!file.empty()) {
      merge_into(file, entries);
      continue;
    }
    files::write_output(a.output, report::entries_yaml(entries));
    if (!files::is_standard_output(a.output)) std::cout << a.output << "\n";
  }
  return kExitOk;
}

// The benchmark.yaml files of `paths`: files, or folders searched for them.
std::vector<fs::path> published_files(const std::vector<std::string>& paths) {
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
  return files;
}

int import_published(const std::vector<std::string>& paths, const std::string& into) {
  // Read everything before printing anything: a bad file gives one line and nothing else.
  std::vector<report::PublishedBenchmark> benchmarks;
  for (const auto& f : published_files(paths))
    benchmarks.push_back(report::import_benchmark_yaml(f));
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
      files::write_file_atomically(out, json_text(report::to_json(b), 1) + "\n");
    }
  }
  if (!flagged.empty()) std::cout << "\nrows that break the measurement rules:\n" << flagged;
  if (!into.empty())
    std::cout << "\nimported into " << into << " (robotperf report " << into << " plots them)\n";
  return kExitOk;
}

int rebuild_database(const std::string& dir) {
  const auto rebuilt = results_db::rebuild(dir);
  for (const auto& s : rebuilt.skipped) std::fprintf(stderr, "robotperf: skipped %s\n", s.c_str());
  std::cout << rebuilt.database.string() << ": rebuilt from " << dir << ": " << rebuilt.recorded
            << " run(s) recorded";
  if (!rebuilt.skipped.empty()) std::cout << ", " << rebuilt.skipped.size() << " file(s) skipped";
  std::cout << "\n";
  return kExitOk;
}

// The runs of `paths` (folders and results files; ./results when none is named) pushed into the
// database `to` names, else ROBOTPERF_RESULTS_URL. A file that is not a readable run is skipped.
int push_results(const std::string& to, const std::vector<std::string>& paths) {
  const char* environment = std::getenv(results_db::kResultsUrlVariable);
  std::string url;
  if (!to.empty())
    url = results_db::checked_url(to, "--to");
  else if (environment != nullptr && *environment != '\0')
    url = results_db::checked_url(environment, results_db::kResultsUrlVariable);
  else
    throw std::invalid_argument(
        std::string("results push: say where to: --to postgresql://... or ") +
        results_db::kResultsUrlVariable);
  std::vector<report::StoredRun> runs;
  std::vector<std::string> skipped;
  for (const auto& p : paths.empty() ? std::vector<std::string>{"results"} : paths) {
    if (fs::is_directory(p)) {
      auto scan = report::scan_results(p);
      for (auto& r : scan.runs) runs.push_back(std::move(r));
      for (auto& sk : scan.skipped) skipped.push_back(std::move(sk));
    } else if (!fs::exists(p)) {
      throw report::ReportError(p + ": no such file or folder");
    } else {
      try {
        runs.push_back(report::load_run(p));
      } catch (const report::ReportError& e) {
        skipped.emplace_back(e.what());
      }
    }
  }
  auto store = results_db::PostgresStore::connect(url);
  const results_db::Pushed pushed = store.push(runs);
  skipped.insert(skipped.end(), pushed.skipped.begin(), pushed.skipped.end());
  for (const auto& s : skipped) std::fprintf(stderr, "robotperf: skipped %s\n", s.c_str());
  std::cout << store.target() << ": pushed " << pushed.pushed << " run(s)";
  if (!skipped.empty()) std::cout << ", " << skipped.size() << " file(s) skipped";
  std::cout << "\n";
  return kExitOk;
}

class ResultsCommand : public Command {
 public:
  CLI::App* declare(CLI::App& app) override {
    auto* command =
        app.add_subcommand("results", "the results folder: list, export, import, rebuild-db, push");
    command->require_subcommand(1);
    command->footer(
        "Examples: robotperf results list results/\n"
        "          robotperf results export results --merge-package\n"
        "          robotperf results push --to postgresql://ci@db.lab.example/robotperf results");
    declare_list(*command);
    declare_export(*command);
    declare_import(*command);
    declare_rebuild_db(*command);
    declare_push(*command);
    return command;
  }

  int run(const Context& context) override {
    if (*list_)
      return list_results(list_dir_, list_dir_option_->count() > 0, list_from_, list_format_,
                          list_labels_);
    if (*export_) return export_results(context.roots, export_args_);
    if (*rebuild_db_) return rebuild_database(rebuild_dir_);
    if (*push_) return push_results(push_to_, push_paths_);
    return import_published(import_paths_, import_into_);
  }

 private:
  void declare_list(CLI::App& results) {
    list_ = results.add_subcommand("list", "show the runs of a results folder");
    list_dir_option_ = list_->add_option(
        "dir", list_dir_,
        "results folder (default: the database --from or ROBOTPERF_RESULTS_URL names, else "
        "./results)");
    list_->add_option("--from", list_from_,
                      "read the runs from this PostgreSQL database (postgresql://...; credentials "
                      "from PGPASSWORD, ~/.pgpass or PGPASSFILE)");
    list_
        ->add_option("--label", list_labels_,
                     "KEY=VALUE: only the runs with this label (repeatable)")
        ->check(label_check());
    list_
        ->add_option("--format", list_format_,
                     "table (default), json (an array of objects) or csv (a header line, then "
                     "one line per run)")
        ->check(CLI::IsMember({"table", "json", "csv"}));
    list_->footer(
        "Examples: robotperf results list results --format csv\n"
        "          robotperf results list --from postgresql://ci@db.lab.example/robotperf");
  }

  void declare_export(CLI::App& results) {
    ExportArgs& a = export_args_;
    export_ =
        results.add_subcommand("export", "turn runs into RobotPerf benchmark.yaml result entries");
    export_->add_option("results", a.results, "results files or folders (default: ./results)");
    export_->add_option("--format", a.format, "output format")
        ->check(CLI::IsMember({"benchmark-yaml"}));
    auto* output = export_->add_option(
        "--output,-o", a.output, "write the entries to this file (default -: standard output)");
    auto* merge = export_->add_option(
        "--merge", a.merge,
        "append the entries to this benchmark.yaml (existing entries untouched; runs of another "
        "benchmark are refused)");
    merge->excludes(output);
    export_
        ->add_flag("--merge-package", a.merge_package,
                   "append each run's entries to its benchmark package's benchmark.yaml")
        ->excludes(merge)
        ->excludes(output);
    export_->add_option("--hardware", a.hardware,
                        "hardware name to record (default: from the machine description)");
    export_->add_option("--category", a.category, "RobotPerf category (default: guessed)")
        ->check(CLI::IsMember({"edge", "workstation", "datacenter", "cloud"}));
    export_->add_flag("--include-invalid", a.include_invalid, "also export invalid runs");
    export_->footer("Example: robotperf results export results --merge-package");
  }

  void declare_import(CLI::App& results) {
    auto* import = results.add_subcommand(
        "import",
        "read published RobotPerf benchmark.yaml files and flag rows that break the rules");
    import->add_option("files", import_paths_, "benchmark.yaml files or folders holding them")
        ->required();
    import->add_option("--into", import_into_,
                       "also store them in this results folder, for robotperf report");
    import->footer("Example: robotperf results import benchmarks --into published");
  }

  void declare_rebuild_db(CLI::App& results) {
    rebuild_db_ = results.add_subcommand(
        "rebuild-db",
        "make the folder's database (robotperf.db) again from its results files, replacing it "
        "at once");
    rebuild_db_->add_option("dir", rebuild_dir_, "results folder (default: ./results)");
    rebuild_db_->footer("Example: robotperf results rebuild-db results");
  }

  void declare_push(CLI::App& results) {
    push_ = results.add_subcommand(
        "push", "push runs into a shared PostgreSQL database (pushing a run again replaces it)");
    push_->add_option("results", push_paths_, "results folders or files (default: ./results)");
    push_->add_option("--to", push_to_,
                      "the database: postgresql://[user@]host[:port]/db[?sslmode=...] (default: "
                      "ROBOTPERF_RESULTS_URL); credentials from PGPASSWORD, ~/.pgpass or "
                      "PGPASSFILE, never the URL");
    push_->footer("Example: robotperf results push --to postgresql://ci@db.lab.example/robotperf");
  }

  std::string list_dir_ = "results";
  CLI::Option* list_dir_option_ = nullptr;
  std::string list_from_;
  std::string list_format_ = "table";
  std::vector<std::string> list_labels_;
  ExportArgs export_args_;
  std::vector<std::string> import_paths_;
  std::string import_into_;
  CLI::App* list_ = nullptr;
  CLI::App* export_ = nullptr;
  std::string rebuild_dir_ = "results";
  CLI::App* rebuild_db_ = nullptr;
  std::string push_to_;
  std::vector<std::string> push_paths_;
  CLI::App* push_ = nullptr;
};

}  // namespace

std::unique_ptr<Command> results_command() {
  return std::make_unique<ResultsCommand>();
}

}  // namespace robotperf::cli
