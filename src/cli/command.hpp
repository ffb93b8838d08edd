// One verb of the robotperf command: it declares its CLI11 subcommand with its options, help and
// example, and runs when the command line chose it.
#pragma once

#include <CLI/CLI.hpp>
#include <memory>
#include <string>
#include <vector>

#include "options.hpp"
#include "robotperf/cli/command_line.hpp"

namespace robotperf::cli {

// What every verb may use once the command line is parsed and the plug-ins are loaded.
struct Context {
  Roots roots;                       // the benchmark folders
  std::vector<std::string> plugins;  // --plugin, for the processes a run starts
  const Backends& backends;
};

class Command {
 public:
  virtual ~Command() = default;
  // Adds the verb's subcommand to `app`; returns it, for the dispatcher to see whether it was
  // chosen.
  virtual CLI::App* declare(CLI::App& app) = 0;
  // Runs the chosen verb; returns the exit status, or throws (report_error says it).
  virtual int run(const Context& context) = 0;
};

// Every verb, in the order --help lists them.
std::vector<std::unique_ptr<Command>> all_commands();

}  // namespace robotperf::cli
