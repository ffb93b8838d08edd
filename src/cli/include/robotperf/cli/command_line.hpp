// The robotperf command line, as a library: the executable's composition root (src/app)
// registers the built-in categories and hands in what only it knows of their backends.
#pragma once

#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "robotperf/plugin/kernel.hpp"

namespace robotperf::cli {

// What the command line asks of the backends the categories bring.
struct Backends {
  // Every device of each backend, by backend name ("opencl", "cuda"): what sysinfo lists.
  std::function<std::map<std::string, std::vector<plugin::DeviceInfo>>()> devices;
  // Why `run --backend NAME` cannot run in this build (one line), or nullopt when it can.
  std::function<std::optional<std::string>(const std::string& backend)> not_built;
};

// Parses the command line, runs its verb and returns the process's exit status; errors are said
// in one line on stderr (exit_codes.hpp).
int run_command_line(int argc, char** argv, const Backends& backends);

}  // namespace robotperf::cli
