// The registry verbs of the robotperf command: `list kernels|datasets|evaluators` and what
// `describe` says of a benchmark's kernels, from whatever the built-in categories and the loaded
// plug-ins registered.
#pragma once

#include <filesystem>
#include <ostream>
#include <string>
#include <vector>

#include "robotperf/harness/benchmark_spec.hpp"

namespace robotperf::cli {

int list_kernels(std::ostream& out);
int list_datasets(std::ostream& out);
int list_evaluators(std::ostream& out);

// A node of a benchmark: its kernel (and where it came from), backend, ports with their topics
// and types, and every parameter with the value it takes.
void describe_node(std::ostream& out, const harness::NodeSpec& node);

// Loads the plug-ins named by ROBOTPERF_PLUGIN_PATH (files, or folders whose *.so are loaded;
// ':'-separated) and then `files`; throws plugin::PluginError.
void load_plugins(const std::vector<std::string>& files);

}  // namespace robotperf::cli
