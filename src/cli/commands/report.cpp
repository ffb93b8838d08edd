// `robotperf report`: the HTML and Markdown report of results and published rows.
#include "robotperf/report/report.hpp"

#include <cstdio>
#include <iostream>
#include <stdexcept>

#include "../options.hpp"
#include "commands.hpp"
#include "results_source.hpp"
#include "robotperf/cli/exit_codes.hpp"
#include "robotperf/files/atomic_file.hpp"
#include "robotperf/report/run_store.hpp"

namespace robotperf::cli {

namespace {

struct ReportArgs {
  std::vector<std::string> inputs;
  std::string from;  // a PostgreSQL database's URL
  std::string html, md, title = "robotperf report";
  std::vector<std::string> compare;
  std::vector<std::string> labels;  // KEY=VALUE: only the runs with these
  bool radar = false;
};

// What the report cannot be asked, before anything is read.
void check_report_args(const ReportArgs& a) {
  if (a.html.empty() && a.md.empty())
    throw std::invalid_argument("report: say where to write it: --html FILE and/or --md FILE");
  if (!a.compare.empty() && a.compare.size() != 2)
    throw std::invalid_argument(
        "report: --compare takes exactly two selectors (--compare A --compare B)");
}

int make_report(const ReportArgs& a) {
  check_report_args(a);
  std::vector<fs::path> paths;
  for (const auto& p : a.inputs.empty() ? std::vector<std::string>{"results"} : a.inputs)
    paths.emplace_back(p);
  const auto url = database_to_read(a.from, !a.inputs.empty());
  auto input = url ? report_input_from_database(*url) : report::load_report_inputs(paths);
  keep_labelled(input.runs, a.labels);
  for (const auto& s : input.skipped) std::fprintf(stderr, "robotperf: skipped %s\n", s.c_str());
  if (input.runs.empty() && input.published.empty())
    throw report::ReportError(
        "nothing to report: no results files or benchmark.yaml in the given paths");
  report::ReportOptions options;
  options.title = a.title;
  options.radar = a.radar;
  if (a.compare.size() == 2) options.compare = std::pair{a.compare[0], a.compare[1]};
  if (!a.html.empty() && !a.md.empty() && files::is_standard_output(a.html) &&
      files::is_standard_output(a.md)) {
    throw std::invalid_argument("report: only one of --html and --md can be - (standard output)");
  }
  // Standard output carries the report alone; where a file went is said on stderr then.
  std::ostream& said =
      files::is_standard_output(a.html) || files::is_standard_output(a.md) ? std::cerr : std::cout;
  if (!a.html.empty()) {
    files::write_output(a.html, report::render_html(input, options));
    if (!files::is_standard_output(a.html)) said << "report: " << a.html << "\n";
  }
  if (!a.md.empty()) {
    files::write_output(a.md, report::render_markdown(input, options));
    if (!files::is_standard_output(a.md)) said << "report: " << a.md << "\n";
  }
  return kExitOk;
}

class ReportCommand : public Command {
 public:
  CLI::App* declare(CLI::App& app) override {
    auto* command = app.add_subcommand(
        "report",
        "HTML and Markdown report: a summary, per benchmark sorted bars beside the published "
        "results, runs, distributions");
    command->add_option("results", args_.inputs,
                        "results files, imported files, benchmark.yaml files or folders "
                        "(default: the database --from or ROBOTPERF_RESULTS_URL names, else "
                        "./results)");
    command->add_option("--from", args_.from,
                        "read the runs from this PostgreSQL database (postgresql://...; "
                        "credentials from PGPASSWORD, ~/.pgpass or PGPASSFILE)");
    command->add_option("--html", args_.html, "write the HTML report here (- : standard output)");
    command->add_option("--md", args_.md, "write the Markdown report here (- : standard output)");
    command->add_option("--title", args_.title, "report title");
    command->add_option("--compare", args_.compare,
                        "compare two sides (give it twice): a results file or name prefix, "
                        "or a hardware name");
    command
        ->add_option("--label", args_.labels,
                     "KEY=VALUE: only the runs with this label (repeatable); published rows stay")
        ->check(label_check());
    command->add_flag("--radar", args_.radar,
                      "add radar plots per category, RobotPerf's presentation (at most 6 series "
                      "each)");
    command->footer(
        "Examples: robotperf report results --html report.html --md report.md\n"
        "          robotperf report --from postgresql://ci@db.lab.example/robotperf --html r.html");
    return command;
  }

  int run(const Context&) override { return make_report(args_); }

 private:
  ReportArgs args_;
};

}  // namespace

std::unique_ptr<Command> report_command() {
  return std::make_unique<ReportCommand>();
}

}  // namespace robotperf::cli
