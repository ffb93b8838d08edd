// `robotperf compare A B`: the report's comparison of two sides, in the terminal.
#include <algorithm>
#include <cstdio>
#include <iostream>
#include <optional>
#include <stdexcept>

#include "../options.hpp"
#include "commands.hpp"
#include "results_source.hpp"
#include "robotperf/cli/exit_codes.hpp"
#include "robotperf/files/atomic_file.hpp"
#include "robotperf/report/gate.hpp"
#include "robotperf/report/report.hpp"
#include "robotperf/report/run_store.hpp"

namespace robotperf::cli {

namespace {

// The results to read: --results, else ./results and the sides that are results files.
std::vector<fs::path> results_paths(const std::vector<std::string>& results,
                                    const std::vector<std::string>& sides) {
  std::vector<fs::path> paths;
  for (const auto& p : results) paths.emplace_back(p);
  if (results.empty()) {
    std::error_code ec;
    if (fs::is_directory("results", ec)) paths.emplace_back("results");
    for (const auto& side : sides) {
      if (side.ends_with(".json") && fs::is_regular_file(side, ec)) paths.emplace_back(side);
    }
  }
  if (paths.empty())
    throw report::ReportError(
        "compare: no ./results folder here; name the results with --results DIR");
  return paths;
}

// A folder of many runs read through its database (docs/reference/results-database.md): the
// runs are listed from it, and only those the sides choose are read whole from their files, with
// the folder's published rows. nullopt when the folder has subfolders (compare reads them too) or
// no database it can use: then every file is read.
std::optional<report::ReportInput> sides_through_database(const fs::path& folder,
                                                          const std::vector<std::string>& sides) {
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) return std::nullopt;
  std::vector<fs::path> published;
  for (const auto& entry : fs::directory_iterator(folder)) {
    if (entry.is_directory(ec)) return std::nullopt;
    if (report::may_be_imported_file(entry.path()) || entry.path().filename() == "benchmark.yaml")
      published.push_back(entry.path());
  }
  auto synced = results_db::open_synced(folder);
  if (!synced) return std::nullopt;
  report::ReportInput out;
  out.skipped = std::move(synced->skipped);
  std::ranges::sort(published);
  for (const auto& file : published) {
    try {
      auto read = report::load_report_inputs({file});
      for (auto& p : read.published) out.published.push_back(std::move(p));
    } catch (const report::ReportError& e) {
      out.skipped.push_back(e.what());
    }
  }
  const report::ReportInput listed{synced->database.listed_runs(), out.published, {}};
  for (const auto& file : report::files_of_runs_chosen(listed, sides)) {
    try {
      out.runs.push_back(report::load_run(file));
    } catch (const report::ReportError& e) {
      out.skipped.push_back(e.what());
    }
  }
  report::sort_by_start(out.runs);
  return out;
}

struct GateArgs {
  std::optional<double> fail_on_regression;  // percent
  std::string junit, markdown;               // files to write, when named
};

// The regression gate: exit 1 on a regression, 0 without; its JUnit and Markdown written
// atomically where asked.
int gate(const report::ReportInput& input, const std::string& baseline,
         const std::string& candidate, const GateArgs& g) {
  const report::GateResult result =
      report::run_gate(input, baseline, candidate, g.fail_on_regression.value_or(0));
  std::cout << report::gate_text(result);
  if (!g.junit.empty()) files::write_file_atomically(g.junit, report::gate_junit(result));
  if (!g.markdown.empty()) files::write_file_atomically(g.markdown, report::gate_markdown(result));
  if (result.judged() == 0)
    throw report::ReportError("the gate judged nothing: each side needs at least " +
                              std::to_string(report::kGateMinRuns) +
                              " valid runs of a benchmark (run with --repeat)");
  return result.regressions() > 0 ? kExitRegression : kExitOk;
}

class CompareCommand : public Command {
 public:
  CLI::App* declare(CLI::App& app) override {
    auto* command =
        app.add_subcommand("compare",
                           "compare two runs or configurations: medians, ratio, significance; with "
                           "--fail-on-regression a CI gate");
    command->add_option("A", a_,
                        "a results file, a file-name prefix (a1-intra), a hardware or series "
                        "name, or fields: hardware= (or system=),rmw=,processes=,backend=,mode=,"
                        "arrivals=,monitor=,rate=,label.KEY=");
    command->add_option("B", b_, "the other side, as A");
    command->add_option("--baseline", baseline_, "the gate's baseline, as A")
        ->excludes(command->get_option("A"));
    command->add_option("--candidate", candidate_, "the gate's candidate, as A")
        ->excludes(command->get_option("B"));
    command
        ->add_option("--fail-on-regression", gate_.fail_on_regression,
                     "PCT: exit 1 when a figure of the candidate is worse than the baseline's, "
                     "beyond the run-to-run noise and by more than PCT percent")
        ->check(number_between(0, 1000));
    command->add_option("--junit", gate_.junit, "with the gate: also write JUnit XML to FILE");
    command->add_option("--markdown", gate_.markdown,
                        "with the gate: also write a Markdown summary to FILE (a CI job summary)");
    command->add_option(
        "--results", results_,
        "results files or folders, imported published rows included (default: "
        "the database --from or ROBOTPERF_RESULTS_URL names, else ./results and the "
        "sides where they are files)");
    command->add_option("--from", from_,
                        "read the runs from this PostgreSQL database (postgresql://...; "
                        "credentials from PGPASSWORD, ~/.pgpass or PGPASSFILE)");
    command->footer(
        "Examples:\n  robotperf compare rmw=intra rmw=fastdds --results results\n"
        "  robotperf compare --baseline label.rev=main --candidate label.rev=pr42 "
        "--fail-on-regression 10 --junit gate.xml\n"
        "  robotperf compare rmw=intra rmw=fastdds --from "
        "postgresql://ci@db.lab.example/robotperf");
    return command;
  }

  int run(const Context&) override {
    const std::string a = baseline_.empty() ? a_ : baseline_;
    const std::string b = candidate_.empty() ? b_ : candidate_;
    if (a.empty() || b.empty())
      throw std::invalid_argument(
          "compare needs two sides: A and B, or --baseline and --candidate");
    const bool gating = gate_.fail_on_regression.has_value();
    if (!gating && (!gate_.junit.empty() || !gate_.markdown.empty()))
      throw std::invalid_argument("--junit and --markdown go with --fail-on-regression");
    const auto url = database_to_read(from_, !results_.empty());
    const auto paths = url ? std::vector<fs::path>{} : results_paths(results_, {a, b});
    std::optional<report::ReportInput> through_database;
    if (paths.size() == 1) through_database = sides_through_database(paths[0], {a, b});
    const auto input = url                ? report_input_from_database(*url)
                       : through_database ? std::move(*through_database)
                                          : report::load_report_inputs(paths);
    for (const auto& s : input.skipped) std::fprintf(stderr, "robotperf: skipped %s\n", s.c_str());
    if (gating) return gate(input, a, b, gate_);
    std::cout << report::render_comparison_text(input, a, b);
    return kExitOk;
  }

 private:
  std::string a_, b_, baseline_, candidate_;
  GateArgs gate_;
  std::vector<std::string> results_;
  std::string from_;
};

}  // namespace

std::unique_ptr<Command> compare_command() {
  return std::make_unique<CompareCommand>();
}

}  // namespace robotperf::cli
