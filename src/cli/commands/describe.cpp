// `robotperf describe ID`: a benchmark's graph, dataset and settings.
#include <iostream>

#include "../registry_commands.hpp"
#include "commands.hpp"
#include "robotperf/cli/exit_codes.hpp"
#include "robotperf/harness/benchmark_spec.hpp"
#include "robotperf/plugin/registry.hpp"

namespace robotperf::cli {

namespace {

void describe_functional(const harness::FunctionalSpec& f) {
  std::cout << "functional: evaluator " << f.evaluator << ", "
            << (f.sample ? std::to_string(f.sample) + " sampled outputs\n"
                         : std::string("every measured output\n"));
  for (const auto& [role, stream] : f.truth)
    std::cout << "  truth " << role << " <- stream " << stream << "\n";
  for (const auto& [name, value] : f.parameters)
    std::cout << "  param " << name << " = " << value << "\n";
  for (const auto& [metric, t] : f.thresholds) {
    std::cout << "  threshold " << metric;
    if (t.min) std::cout << " >= " << *t.min;
    if (t.max) std::cout << " <= " << *t.max;
    std::cout << "\n";
  }
}

// From the package line to the run settings.
void describe_inputs(const harness::BenchmarkSpec& s) {
  std::cout << "package:   " << s.dir.string() << "\n";
  std::cout << "dataset:   " << s.dataset;
  if (const auto* d = plugin::registry().find_dataset(s.dataset)) {
    std::cout << " — " << d->info.description << " (from " << d->origin << ")";
  }
  if (!s.workload.empty()) {
    std::cout << "\nworkload: ";
    const char* separator = " ";
    for (const auto& [key, value] : s.workload) {
      std::cout << separator << key << " = " << value;
      separator = ", ";
    }
  }
  std::cout << "\nrate:      " << s.rate_hz << " Hz, "
            << (s.count ? std::to_string(s.count) : "dataset-length") << " messages, warm-up "
            << s.warmup << ", drain " << s.drain_s << " s\n";
  std::cout << "validity:  at least " << s.min_samples << " samples, loss <= " << s.max_loss_percent
            << " %\n";
  std::cout << "inputs:\n";
  for (const auto& in : s.inputs)
    std::cout << "  " << in.topic << "  [" << in.type << "] <- stream " << in.stream << "\n";
}

// The graph: plug-ins, processes, nodes or the external graph, and the measured output.
void describe_graph(const harness::BenchmarkSpec& s) {
  for (const auto& p : s.plugins) std::cout << "plug-in:   " << p.string() << "\n";
  std::cout << "processes: " << s.processes
            << (s.security_required ? ", DDS Security required" : "") << "\n";
  if (!s.nodes.empty()) std::cout << "nodes:\n";
  for (const auto& n : s.nodes) describe_node(std::cout, n);
  if (!s.launch.empty()) std::cout << "launch (an external graph):\n";
  for (const auto& l : s.launch) {
    std::cout << "  " << l.name << ":";
    for (const auto& word : l.command) std::cout << " " << word;
    std::cout << "  (in " << l.cwd.string() << ")\n";
  }
  if (s.attach) std::cout << "attach: an external graph already running on the domain\n";
  std::cout << "output:\n  " << s.output.topic << "  [" << s.output.type << "] -> monitor\n";
}

class DescribeCommand : public Command {
 public:
  CLI::App* declare(CLI::App& app) override {
    auto* command =
        app.add_subcommand("describe", "show a benchmark's graph, dataset and settings");
    command->add_option("id", id_, "benchmark id or name, e.g. a1")->required();
    command->footer("Example: robotperf describe a1");
    return command;
  }

  int run(const Context& context) override {
    const auto s = harness::find_benchmark(context.roots, id_);
    std::cout << s.id << " — " << s.name << " (" << s.category << ")\n";
    if (!s.short_description.empty()) std::cout << s.short_description << "\n";
    std::cout << "\n" << s.description << "\n";
    describe_inputs(s);
    describe_graph(s);
    if (s.functional) describe_functional(*s.functional);
    return kExitOk;
  }

 private:
  std::string id_;
};

}  // namespace

std::unique_ptr<Command> describe_command() {
  return std::make_unique<DescribeCommand>();
}

}  // namespace robotperf::cli
