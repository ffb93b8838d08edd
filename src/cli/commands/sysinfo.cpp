// `robotperf sysinfo`: this machine, this robotperf, its power sources and devices, as results
// record them.
#include <iostream>

#include "commands.hpp"
#include "robotperf/cli/exit_codes.hpp"
#include "robotperf/harness/run.hpp"
#include "robotperf/metrics/power.hpp"
#include "robotperf/report/results.hpp"
#include "robotperf/sysinfo/machine.hpp"

namespace robotperf::cli {

namespace {

// Each backend's devices under "<backend>_devices", as results record a device.
void add_device_lists(nlohmann::json& description, const Backends& backends) {
  if (!backends.devices) return;
  for (const auto& [backend, devices] : backends.devices()) {
    nlohmann::json list = nlohmann::json::array();
    for (const auto& d : devices) list.push_back(harness::device_to_json(d));
    description[backend + "_devices"] = std::move(list);
  }
}

class SysinfoCommand : public Command {
 public:
  CLI::App* declare(CLI::App& app) override {
    auto* command = app.add_subcommand(
        "sysinfo",
        "describe this machine, this robotperf and the power sources found, as results "
        "record them");
    add_power_options(command, power_, false);
    command->footer("Example: robotperf sysinfo --power-sources rapl,nvml");
    return command;
  }

  int run(const Context& context) override {
    nlohmann::json description = {
        {"machine", sysinfo::to_json(sysinfo::collect_machine_info())},
        {"software", report::software_json()},
        {"power", metrics::sources_to_json(metrics::discover_power_sources(power_.options()))}};
    add_device_lists(description, context.backends);
    std::cout << json_text(description, 2) << "\n";
    return kExitOk;
  }

 private:
  PowerArgs power_;
};

}  // namespace

std::unique_ptr<Command> sysinfo_command() {
  return std::make_unique<SysinfoCommand>();
}

}  // namespace robotperf::cli
