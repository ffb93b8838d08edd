// A plug-in that registers a kernel under a name the built-in util category already has.
#include "robotperf/plugin.hpp"

ROBOTPERF_PLUGIN(registrar) {
  registrar.add_kernel(
      {.name = "util/relay",
       .description = "a second relay",
       .inputs = {{"input", ""}},
       .outputs = {{"output", ""}}},
      [](robotperf::graph::Context& context, const robotperf::plugin::KernelConfig& c) {
        return std::make_shared<robotperf::graph::Node>(context, c.node_name);
      });
}
