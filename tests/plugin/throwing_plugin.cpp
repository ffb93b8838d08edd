// A plug-in whose registration throws after registering a kernel: nothing of it may be kept.
#include <stdexcept>

#include "robotperf/plugin.hpp"

ROBOTPERF_PLUGIN(registrar) {
  registrar.add_kernel(
      {.name = "throwing_plugin/kept_nowhere",
       .description = "registered before the throw",
       .inputs = {{"input", "sensor_msgs/msg/Image"}},
       .outputs = {{"output", "sensor_msgs/msg/Image"}}},
      [](robotperf::graph::Context& context, const robotperf::plugin::KernelConfig& c) {
        return std::make_shared<robotperf::graph::Node>(context, c.node_name);
      });
  throw std::runtime_error("no licence for this accelerator");
}
