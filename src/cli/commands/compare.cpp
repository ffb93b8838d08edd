// `robotperf compare A B`: the report's comparison of two sides, in the terminal.
#include <cstdio>
#include <iostream>

#include "commands.hpp"
#include "robotperf/cli/exit_codes.hpp"
#include "robotperf/report/report.hpp"
#include "robotperf/report/run_store.hpp"

namespace robotperf::cli {

namespace {

// A side that is a results file is read even when it is not in the results folders.
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

class CompareCommand : public Command {
 public:
  CLI::App* declare(CLI::App& app) override {
    auto* command = app.add_subcommand(
        "compare",
        "compare two runs or configurations in the terminal: medians, ratio B/A, significance");
    command
        ->add_option("A", a_,
                     "a results file, a file-name prefix (a1-intra), a hardware or series name, "
                     "or fields: hardware=,rmw=,processes=,backend=,mode=,arrivals=,monitor=,"
                     "rate=")
        ->required();
    command->add_option("B", b_, "the other side, as A")->required();
    command->add_option("--results", results_,
                        "results files or folders, imported published rows included (default: "
                        "./results, and A and B where they are files)");
    command->footer("Example: robotperf compare rmw=intra rmw=fastdds --results results");
    return command;
  }

  int run(const Context&) override { return compare_in_terminal(a_, b_, results_); }

 private:
  std::string a_, b_;
  std::vector<std::string> results_;
};

}  // namespace

std::unique_ptr<Command> compare_command() {
  return std::make_unique<CompareCommand>();
}

}  // namespace robotperf::cli
