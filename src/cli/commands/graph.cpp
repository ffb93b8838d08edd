// `robotperf graph`: the ROS 2 graph visible on a DDS domain (graph_command.cpp does the work).
#include <iostream>

#include "../graph_command.hpp"
#include "commands.hpp"

namespace robotperf::cli {

namespace {

class GraphCommand : public Command {
 public:
  CLI::App* declare(CLI::App& app) override {
    auto* command = app.add_subcommand(
        "graph", "list the ROS 2 nodes, topics, types and QoS visible on a DDS domain");
    command->add_option("--rmw", options_.rmw, "fastdds (default) or cyclonedds")
        ->check(CLI::IsMember({"fastdds", "cyclonedds"}));
    command->add_option("--domain", options_.domain, "DDS domain (default: ROS_DOMAIN_ID)")
        ->transform(domain_id_check(false));
    command
        ->add_option("--listen", options_.listen_s,
                     "seconds to listen to discovery before listing (default 3)")
        ->transform(seconds_with_unit())
        ->check(number_between(0.1, 600.0));
    command->add_flag("--json", options_.json, "print JSON");
    command->footer("Example: robotperf graph --domain 7 --listen 5");
    return command;
  }

  int run(const Context&) override { return ros_graph(options_, std::cout); }

 private:
  GraphOptions options_;
};

}  // namespace

std::unique_ptr<Command> graph_command() {
  return std::make_unique<GraphCommand>();
}

}  // namespace robotperf::cli
