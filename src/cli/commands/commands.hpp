// The verbs of the robotperf command, one file each in this folder.
#pragma once

#include <memory>

#include "../command.hpp"

namespace robotperf::cli {

std::unique_ptr<Command> list_command();
std::unique_ptr<Command> describe_command();
std::unique_ptr<Command> run_command();
std::unique_ptr<Command> results_command();
std::unique_ptr<Command> readme_command();
std::unique_ptr<Command> report_command();
std::unique_ptr<Command> compare_command();
std::unique_ptr<Command> history_command();
std::unique_ptr<Command> trace_command();
std::unique_ptr<Command> bag_command();
std::unique_ptr<Command> dataset_command();
std::unique_ptr<Command> sysinfo_command();
std::unique_ptr<Command> node_command();
std::unique_ptr<Command> graph_command();
std::unique_ptr<Command> security_command();
std::unique_ptr<Command> help_command();
std::unique_ptr<Command> completion_command();

}  // namespace robotperf::cli
