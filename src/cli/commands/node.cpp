// `robotperf node PACKAGE --node NAME`: one node of a benchmark in a process of its own, started
// by a per-node run (internal: not listed in --help).
#include "commands.hpp"
#include "robotperf/harness/benchmark_spec.hpp"
#include "robotperf/harness/node_spec_wire.hpp"
#include "robotperf/harness/run.hpp"
#include "robotperf/rmw/transport.hpp"

namespace robotperf::cli {

namespace {

class NodeCommand : public Command {
 public:
  CLI::App* declare(CLI::App& app) override {
    auto* command =
        app.add_subcommand("node", "run one node of a benchmark (used by --processes per-node)");
    command->group("");
    command->add_option("package", package_)->required();
    command->add_option("--node", name_)->required();
    command->add_option("--rmw", rmw_);
    command->add_option("--domain", domain_)->transform(domain_id_check(false));
    // The package's nodes as the run resolved them (--backend, --update-rate applied):
    // harness::encode_nodes.
    command->add_option("--nodes", nodes_);
    command->add_option("--callback-timeout", callback_timeout_s_);
    command->add_option("--run-token", run_token_);
    command->add_option("--security", keystore_);
    command->add_option("--ros-distro", ros_distro_);
    add_scheduling_options(command, scheduling_);
    command->footer(
        "Example (as a per-node run starts it): robotperf node PACKAGE_DIR --node NAME --rmw "
        "fastdds --domain 7");
    return command;
  }

  int run(const Context&) override {
    harness::BenchmarkSpec spec = harness::load_benchmark(package_);
    if (!nodes_.empty()) harness::use_encoded_nodes(spec, nodes_);
    return harness::run_node_process(spec, name_, rmw_, domain_, scheduling_.options(),
                                     callback_timeout_s_, run_token_, keystore_,
                                     rmw::ros_distro_from_name(ros_distro_));
  }

 private:
  std::string package_, name_, rmw_ = "fastdds";
  int domain_ = 0;
  std::string nodes_;
  double callback_timeout_s_ = 30.0;
  std::string run_token_;
  std::string keystore_;
  std::string ros_distro_ = "jazzy";
  SchedulingArgs scheduling_;
};

}  // namespace

std::unique_ptr<Command> node_command() {
  return std::make_unique<NodeCommand>();
}

}  // namespace robotperf::cli
