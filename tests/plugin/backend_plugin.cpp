// A plug-in that brings a backend of its own and judges its answers itself: the kernel
// backend_plugin/offset copies joint states, and its implementation on the test_accelerator
// backend adds `accelerator_error` to every position (an accelerator that computes another
// answer); it also brings an implementation of the built-in util/relay on test_accelerator, for
// joint states. The plug-in registers test_accelerator, with one device, and the comparison of
// sensor_msgs/JointState answers, and test_unbuilt, a backend this robotperf cannot run. The
// backend plug-in tests load it.
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/plugin.hpp"

namespace {

using namespace robotperf;

constexpr const char* kAccelerator = "test_accelerator";

class OffsetNode final : public graph::Node {
 public:
  OffsetNode(graph::Context& context, const plugin::KernelConfig& config, double error)
      : Node(context, config.node_name), error_(error) {
    output_ = create_publisher<msgs::JointState>(config.topic("output"), config.qos);
    input_ = create_subscription<msgs::JointState>(
        config.topic("input"), config.qos, [this](std::shared_ptr<const msgs::JointState> in) {
          msgs::JointState out = *in;
          for (double& p : out.position) p += error_;
          output_->publish(std::move(out));
        });
  }

 private:
  double error_;
  std::shared_ptr<graph::Publisher<msgs::JointState>> output_;
  std::shared_ptr<graph::GenericSubscription> input_;
};

std::vector<plugin::DatasetStream> joint_states(const plugin::Parameters& workload) {
  std::mt19937_64 random(static_cast<uint64_t>(workload.get_int("seed")));
  std::uniform_real_distribution<double> position(-1.0, 1.0);
  auto states = plugin::make_stream<msgs::JointState>("states", "/backend_plugin/states");
  for (int64_t k = 0; k < workload.get_int("frames"); ++k) {
    msgs::JointState s;
    s.name = {"a", "b"};
    s.position = {position(random), position(random)};
    plugin::append(states, std::move(s));
  }
  return {std::move(states)};
}

// The share of positions within 1e-9 of the cpu's; another number of joints agrees nowhere.
plugin::Agreement compare_joint_states(const void* accelerated, const void* cpu) {
  const auto& a = *static_cast<const msgs::JointState*>(accelerated);
  const auto& c = *static_cast<const msgs::JointState*>(cpu);
  plugin::Agreement agreement{0.0, 1.0, "joint positions within 1e-9 (backend_plugin)"};
  if (a.position.size() != c.position.size()) return agreement;
  if (c.position.empty()) {
    agreement.share = 1.0;
    return agreement;
  }
  std::size_t within = 0;
  for (std::size_t i = 0; i < c.position.size(); ++i)
    within += std::abs(a.position[i] - c.position[i]) <= 1e-9 ? 1 : 0;
  agreement.share = static_cast<double>(within) / static_cast<double>(c.position.size());
  return agreement;
}

// util/relay on the accelerator: joint states only, relayed as they came.
std::shared_ptr<graph::Node> accelerated_relay(graph::Context& context,
                                               const plugin::KernelConfig& config) {
  if (config.parameters.get_string("type") != "sensor_msgs/msg/JointState") {
    throw std::invalid_argument("util/relay on " + std::string(kAccelerator) +
                                " relays sensor_msgs/msg/JointState only");
  }
  return std::make_shared<OffsetNode>(context, config, 0.0);
}

}  // namespace

ROBOTPERF_PLUGIN(registrar) {
  registrar.add_kernel(
      {.name = "backend_plugin/offset",
       .description = "copy joint states, off by accelerator_error on test_accelerator",
       .inputs = {{"input", "sensor_msgs/msg/JointState"}},
       .outputs = {{"output", "sensor_msgs/msg/JointState"}},
       .parameters = {plugin::double_parameter("accelerator_error", 0.0,
                                               "added to every position on test_accelerator")}},
      [](graph::Context& context, const plugin::KernelConfig& config) {
        return std::make_shared<OffsetNode>(context, config, 0.0);
      });
  registrar.add_kernel_backend({.kernel = "backend_plugin/offset", .backend = kAccelerator},
                               [](graph::Context& context, const plugin::KernelConfig& config) {
                                 return std::make_shared<OffsetNode>(
                                     context, config,
                                     config.parameters.get_double("accelerator_error"));
                               });
  registrar.add_kernel_backend({.kernel = "util/relay", .backend = kAccelerator},
                               accelerated_relay);
  registrar.add_dataset({.name = "backend_plugin/joints",
                         .description = "seeded joint states",
                         .rate_hz = 50,
                         .frames = 40,
                         .streams = {{"states", "/backend_plugin/states",
                                      "sensor_msgs/msg/JointState", false, "joint states"}},
                         .workload = {plugin::int_parameter("seed", 11, "random seed"),
                                      plugin::int_parameter("frames", 40, "frames")}},
                        joint_states);
  registrar.add_output_comparison(
      {.ros_type = "sensor_msgs/msg/JointState", .description = "joint positions within 1e-9"},
      compare_joint_states);
  registrar.add_backend(
      {.name = kAccelerator, .description = "a device only the tests have"},
      {.devices =
           [] {
             return std::vector<plugin::DeviceInfo>{
                 {"test accelerator 0", "robotperf tests", "1.0", "TestAPI 1.0", 1 << 20}};
           },
       .unavailable_reason = {}});
  registrar.add_backend(
      {.name = "test_unbuilt", .description = "a backend this robotperf was built without"},
      {.devices = {}, .unavailable_reason = [] {
         return std::string("the test_unbuilt backend was not built into this robotperf");
       }});
}
