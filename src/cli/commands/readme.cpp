// `robotperf readme ID...`: benchmark packages' README.md, regenerated from benchmark.yaml.
#include "robotperf/report/readme.hpp"

#include <cstdio>
#include <fstream>
#include <iostream>

#include "commands.hpp"
#include "robotperf/cli/exit_codes.hpp"
#include "robotperf/files/atomic_file.hpp"
#include "robotperf/harness/benchmark_spec.hpp"

namespace robotperf::cli {

namespace {

class ReadmeCommand : public Command {
 public:
  CLI::App* declare(CLI::App& app) override {
    auto* command = app.add_subcommand(
        "readme", "regenerate benchmark packages' README.md from their benchmark.yaml");
    command->add_option("ids", ids_, "benchmark ids, e.g. a1 a2 a5")->required();
    command->add_flag("--check", check_, "only check that README.md is up to date");
    command->footer("Example: robotperf readme a1 a2 --check");
    return command;
  }

  int run(const Context& context) override {
    int status = kExitOk;
    for (const auto& id : ids_) {
      const auto spec = harness::find_benchmark(context.roots, id);
      const fs::path file = spec.dir / "README.md";
      const std::string text = report::render_package_readme(spec.dir);
      if (check_) {
        std::ifstream in(file, std::ios::binary);
        const std::string current{std::istreambuf_iterator<char>(in), {}};
        if (current != text) {
          std::fprintf(stderr, "robotperf: %s is out of date; run: robotperf readme %s\n",
                       file.c_str(), spec.id.c_str());
          status = kExitError;
        }
        continue;
      }
      files::write_file_atomically(file, text);
      std::cout << file.string() << "\n";
    }
    return status;
  }

 private:
  std::vector<std::string> ids_;
  bool check_ = false;
};

}  // namespace

std::unique_ptr<Command> readme_command() {
  return std::make_unique<ReadmeCommand>();
}

}  // namespace robotperf::cli
