// `robotperf list [benchmarks|kernels|datasets|evaluators]`.
#include <algorithm>
#include <cstdio>
#include <iostream>

#include "../registry_commands.hpp"
#include "commands.hpp"
#include "robotperf/cli/exit_codes.hpp"
#include "robotperf/harness/benchmark_spec.hpp"

namespace robotperf::cli {

namespace {

int list_benchmarks(const Roots& roots, bool ids_only) {
  std::vector<std::string> broken;
  const auto specs = harness::discover_benchmarks(roots, &broken);
  if (ids_only) {
    for (const auto& s : specs) std::printf("%s\n", s.id.c_str());
    return kExitOk;
  }
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

class ListCommand : public Command {
 public:
  CLI::App* declare(CLI::App& app) override {
    auto* command = app.add_subcommand(
        "list", "list the benchmarks, or the registered kernels, datasets or evaluators");
    command->add_option("what", what_, "benchmarks (default), kernels, datasets or evaluators")
        ->check(CLI::IsMember({"benchmarks", "kernels", "datasets", "evaluators"}));
    command->add_flag("--ids", ids_only_,
                      "benchmarks: their ids alone, one a line (for scripts and shell completion)");
    command->footer("Example: robotperf list kernels");
    return command;
  }

  int run(const Context& context) override {
    if (what_ == "kernels") return list_kernels(std::cout);
    if (what_ == "datasets") return list_datasets(std::cout);
    if (what_ == "evaluators") return list_evaluators(std::cout);
    return list_benchmarks(context.roots, ids_only_);
  }

 private:
  std::string what_ = "benchmarks";
  bool ids_only_ = false;
};

}  // namespace

std::unique_ptr<Command> list_command() {
  return std::make_unique<ListCommand>();
}

}  // namespace robotperf::cli
