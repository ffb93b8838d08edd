#include "commands.hpp"

namespace robotperf::cli {

std::vector<std::unique_ptr<Command>> all_commands() {
  std::vector<std::unique_ptr<Command>> commands;
  for (auto make : {list_command, describe_command, run_command, results_command, readme_command,
                    report_command, compare_command, history_command, trace_command, bag_command,
                    dataset_command, sysinfo_command, node_command, graph_command, security_command,
                    help_command, completion_command})
    commands.push_back(make());
  return commands;
}

}  // namespace robotperf::cli
