// util/relay: republishes what it receives. With delay_ms it holds each
// message for a known time, with drop_every = k it drops every k-th message,
// and with fail_after = n its callback throws on message n + 1, so the harness
// can be checked against a graph whose behaviour is known exactly.
#include <chrono>
#include <stdexcept>
#include <string>
#include <thread>

#include "builtin_kernels.hpp"
#include "robotperf/msgs/known_types.hpp"

namespace robotperf::kernels {
namespace {

class RelayNode final : public graph::Node {
 public:
  RelayNode(graph::Context& context, const KernelConfig& config) : Node(context, config.node_name) {
    const std::string type = config.parameters.get_string("type", "sensor_msgs/msg/Image");
    delay_ = std::chrono::microseconds(
        static_cast<int64_t>(config.parameters.get_double("delay_ms", 0.0) * 1000.0));
    drop_every_ = config.parameters.get_int("drop_every", 0);
    fail_after_ = config.parameters.get_int("fail_after", 0);
    if (delay_.count() < 0)
      throw std::invalid_argument("node '" + name() + "': delay_ms must be >= 0");
    if (drop_every_ < 0)
      throw std::invalid_argument("node '" + name() + "': drop_every must be >= 0");

    bool known = msgs::with_message_type(type, [&]<class T>() {
      const auto& ts = msgs::type_support<T>();
      output_ = create_generic_publisher(config.topic("output"), ts, config.qos);
      input_ = create_generic_subscription(
          config.topic("input"), ts, config.qos,
          [this](rmw::MessagePtr m, const graph::MessageInfo&) { relay(std::move(m)); });
    });
    if (!known)
      throw std::invalid_argument("node '" + name() + "': unsupported message type " + type);
  }

 private:
  void relay(rmw::MessagePtr msg) {
    ++received_;
    if (fail_after_ > 0 && received_ > fail_after_) {
      throw std::runtime_error("failing on purpose after " + std::to_string(fail_after_) +
                               " messages (fail_after)");
    }
    if (drop_every_ > 0 && received_ % drop_every_ == 0) return;
    if (delay_.count() > 0) std::this_thread::sleep_for(delay_);
    output_->publish(std::move(msg));
  }

  std::chrono::microseconds delay_{0};
  int64_t drop_every_ = 0;
  int64_t fail_after_ = 0;
  int64_t received_ = 0;
  std::shared_ptr<graph::GenericPublisher> output_;
  std::shared_ptr<graph::GenericSubscription> input_;
};

}  // namespace

std::shared_ptr<graph::Node> make_relay_node(graph::Context& context, const KernelConfig& config) {
  return std::make_shared<RelayNode>(context, config);
}

}  // namespace robotperf::kernels
