// The robotperf executable: registers the built-in categories and hands the command line what
// only they know, their backends' devices and which backends this build has.
#include <exception>

#include "robotperf/categories/builtin.hpp"
#include "robotperf/cli/command_line.hpp"
#include "robotperf/cli/exit_codes.hpp"
#include "robotperf/perception/cuda_device.hpp"
#include "robotperf/perception/opencl_device.hpp"

int main(int argc, char** argv) {
  using namespace robotperf;
  try {
    categories::register_builtin_categories();
  } catch (...) {
    return cli::report_error(std::current_exception());
  }
  cli::Backends backends;
  backends.devices = [] {
    std::map<std::string, std::vector<plugin::DeviceInfo>> devices;
    devices["opencl"] = perception::opencl_devices();
    devices["cuda"] = perception::cuda_devices();
    return devices;
  };
  backends.not_built = [](const std::string& backend) -> std::optional<std::string> {
    if (backend == "cuda" && !perception::cuda_backend_built()) return perception::kCudaNotBuilt;
    return std::nullopt;
  };
  return cli::run_command_line(argc, argv, backends);
}
