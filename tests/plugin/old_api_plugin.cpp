// A plug-in built against an older plug-in API, as its ROBOTPERF_PLUGIN would have written it: it
// calls a function this robotperf no longer has and runs code at load. robotperf must refuse it
// with the version line, from the version recorded in the file, before loading it.
#include <cstdlib>

#include "robotperf/plugin.hpp"

namespace robotperf::plugin {
int removed_before_this_version(int);
}

extern "C" __attribute__((used, section(ROBOTPERF_PLUGIN_API_SECTION)))
const int robotperf_plugin_api_version_recorded = ROBOTPERF_PLUGIN_API_VERSION - 1;

extern "C" __attribute__((visibility("default"))) int robotperf_plugin_api_version() {
  return ROBOTPERF_PLUGIN_API_VERSION - 1;
}

extern "C" __attribute__((visibility("default"))) void robotperf_plugin_register(
    robotperf::plugin::Registrar&) {
  robotperf::plugin::removed_before_this_version(1);
}

namespace {
// Loading it would end the test.
const bool ran_at_load = [] {
  std::abort();
  return true;
}();
}  // namespace
