// The categories compiled into robotperf (one folder each under src/categories).
#pragma once

#include <string>
#include <vector>

#include "robotperf/plugin/registry.hpp"

namespace robotperf::categories {

// The built-in categories' names.
const std::vector<std::string>& builtin_categories();

// Registers every built-in category with the process's registry, through the same Registrar as
// a plug-in, once however often it is called.
void register_builtin_categories();

}  // namespace robotperf::categories
