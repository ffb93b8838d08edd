// robotperf: the command-line front end. Each verb is a Command of its own (commands/); this
// declares the global options, parses, and runs the verb chosen.
#include "robotperf/cli/command_line.hpp"

#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <iostream>

#include "command.hpp"
#include "parse_errors.hpp"
#include "registry_commands.hpp"
#include "robotperf/build_info.hpp"
#include "robotperf/cli/exit_codes.hpp"
#include "robotperf/git_revision.hpp"

namespace robotperf::cli {

int run_command_line(int argc, char** argv) {
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
  const auto commands = all_commands();
  std::vector<CLI::App*> subcommands;
  for (const auto& command : commands) subcommands.push_back(command->declare(app));

  // Without a command: what the commands are, not only that one is missing.
  if (argc == 1) {
    std::cerr << app.help()
              << "robotperf: give a command (robotperf list, robotperf run a1, ...)\n";
    return kExitUsage;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {  // --help, --help-all, --version
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "robotperf: %s\n",
                 parse_error_line(app, std::vector<std::string>(argv + 1, argv + argc), e).c_str());
    return kExitUsage;
  }

  try {
    load_plugins(plugin_flags);
    const Context context{benchmark_roots(benchmarks_flags), plugin_flags};
    for (std::size_t i = 0; i < commands.size(); ++i) {
      if (*subcommands[i]) return commands[i]->run(context);
    }
  } catch (...) {
    return report_error(std::current_exception());
  }
  return kExitUsage;
}

}  // namespace robotperf::cli
