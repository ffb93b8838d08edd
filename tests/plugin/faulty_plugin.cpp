// A plug-in whose kernel fails the way third-party code does: it throws from its callback after
// `throw_after` messages, or from its constructor with `refuse: true`, or crashes the process with
// `abort_after`; on its `opencl` backend it adds `drift` to every byte, as an accelerator that
// computes a slightly different answer would. The fault-injection tests run it.
#include <cstdlib>
#include <stdexcept>

#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/plugin.hpp"

namespace {

using namespace robotperf;

class FaultyNode final : public graph::Node {
 public:
  FaultyNode(graph::Context& context, const plugin::KernelConfig& config)
      : Node(context, config.node_name),
        throw_after_(config.parameters.get_int("throw_after")),
        abort_after_(config.parameters.get_int("abort_after")),
        drift_(config.backend == "cpu" ? 0 : config.parameters.get_int("drift")) {
    if (config.parameters.get_bool("refuse")) {
      throw std::runtime_error("the accelerator this kernel needs is not present");
    }
    output_ = create_publisher<msgs::Image>(config.topic("output"), config.qos);
    input_ = create_subscription<msgs::Image>(
        config.topic("input"), config.qos, [this](std::shared_ptr<const msgs::Image> in) {
          ++seen_;
          if (throw_after_ > 0 && seen_ > throw_after_) {
            throw std::runtime_error("device lost after " + std::to_string(throw_after_) +
                                     " frames");
          }
          if (abort_after_ > 0 && seen_ > abort_after_) std::abort();
          msgs::Image out(*in);
          for (uint8_t& byte : out.data) byte = static_cast<uint8_t>(byte + drift_);
          output_->publish(std::move(out));
        });
  }

 private:
  int64_t throw_after_;
  int64_t abort_after_;
  int64_t drift_;
  int64_t seen_ = 0;
  std::shared_ptr<graph::Publisher<msgs::Image>> output_;
  std::shared_ptr<graph::GenericSubscription> input_;
};

}  // namespace

ROBOTPERF_PLUGIN(registrar) {
  registrar.add_kernel(
      {.name = "faulty_plugin/relay",
       .description = "relays images until it fails as its parameters say",
       .backends = {"cpu", "opencl"},
       .inputs = {{"input", "sensor_msgs/msg/Image"}},
       .outputs = {{"output", "sensor_msgs/msg/Image"}},
       .parameters = {plugin::int_parameter("throw_after", 0, "throw after this many (0: never)"),
                      plugin::int_parameter("abort_after", 0, "abort after this many (0: never)"),
                      plugin::bool_parameter("refuse", false, "throw from the constructor"),
                      plugin::int_parameter("drift", 0,
                                            "added to every byte off the cpu backend")}},
      [](graph::Context& context, const plugin::KernelConfig& config) {
        return std::make_shared<FaultyNode>(context, config);
      });
}
