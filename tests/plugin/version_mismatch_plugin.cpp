// A plug-in built against another version of the plug-in API: its entry points are written out
// by hand, as ROBOTPERF_PLUGIN of that version would have written them.
#include "robotperf/plugin.hpp"

extern "C" __attribute__((visibility("default"))) int robotperf_plugin_api_version() {
  return ROBOTPERF_PLUGIN_API_VERSION + 1;
}

extern "C" __attribute__((visibility("default"))) void robotperf_plugin_register(
    robotperf::plugin::Registrar&) {}
