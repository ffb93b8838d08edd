// `robotperf dataset generate NAME`: a built-in dataset written as a bag (bag_commands.cpp).
#include "../bag_commands.hpp"
#include "commands.hpp"

namespace robotperf::cli {

namespace {

class DatasetCommand : public Command {
 public:
  CLI::App* declare(CLI::App& app) override {
    auto* command = app.add_subcommand("dataset", "the built-in datasets");
    command->require_subcommand(1);
    command->footer(
        "Example: robotperf list datasets && robotperf dataset generate NAME --out my_bag");
    auto* generate = command->add_subcommand("generate", "write a built-in dataset as a bag");
    generate->add_option("name", name_, "a registered dataset (robotperf list datasets)")
        ->required();
    generate->add_option("--out", options_.out, "bag directory (default: the name, / as _)");
    generate->add_option("--storage", options_.storage, "sqlite3 or mcap (default mcap)")
        ->check(CLI::IsMember({"sqlite3", "mcap"}));
    generate->add_option("--compression", options_.compression, "MCAP chunks: zstd, lz4 or none")
        ->check(CLI::IsMember({"zstd", "lz4", "none"}));
    generate->footer(
        "Example: robotperf dataset generate <name> --out my_bag (names: robotperf list "
        "datasets)");
    return command;
  }

  int run(const Context&) override { return dataset_generate(name_, options_); }

 private:
  std::string name_;
  GenerateOptions options_;
};

}  // namespace

std::unique_ptr<Command> dataset_command() {
  return std::make_unique<DatasetCommand>();
}

}  // namespace robotperf::cli
