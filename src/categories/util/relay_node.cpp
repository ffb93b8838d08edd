// util/relay: republishes what it receives. With delay_ms it holds each
// message for a known time, with drop_every = k it drops every k-th message,
// with fail_after = n its callback throws on message n + 1, and with restamp its
// outputs carry the time they were published instead of their input's stamp (as
// a node that writes its own headers), so the harness can be checked against a
// graph whose behaviour is known exactly.
#include <chrono>
#include <stdexcept>
#include <string>
#include <thread>

#include "robotperf/plugin.hpp"

namespace robotperf::util {
namespace {

using plugin::KernelConfig;

struct RelaySettings {
  std::string type;
  double delay_ms = 0;
  int64_t drop_every = 0;
  int64_t fail_after = 0;
  bool restamp = false;
};

const plugin::ParameterStruct<RelaySettings> kRelayParameters{
    plugin::field(&RelaySettings::type, "type", "sensor_msgs/msg/Image",
                  "ROS type of the messages relayed"),
    plugin::field(&RelaySettings::delay_ms, "delay_ms", 0, "hold each message this long, ms"),
    plugin::field(&RelaySettings::drop_every, "drop_every", 0, "drop every k-th message (0: none)"),
    plugin::field(&RelaySettings::fail_after, "fail_after", 0,
                  "throw from the callback on message n + 1 (0: never)"),
    plugin::field(&RelaySettings::restamp, "restamp", false,
                  "stamp each output with the time it is published, not its input's stamp")};

class RelayNode final : public graph::Node {
 public:
  RelayNode(graph::Context& context, const KernelConfig& config) : Node(context, config.node_name) {
    const RelaySettings s = kRelayParameters.read(config.parameters);
    // Bounded before it becomes an integer (an hour: a relay that never answers is fail_after's).
    if (!(s.delay_ms >= 0 && s.delay_ms <= 3.6e6))
      throw std::invalid_argument("node '" + name() + "': delay_ms must be from 0 to 3600000");
    delay_ = std::chrono::microseconds(static_cast<int64_t>(s.delay_ms * 1000.0));
    drop_every_ = s.drop_every;
    fail_after_ = s.fail_after;
    restamp_ = s.restamp;
    if (drop_every_ < 0)
      throw std::invalid_argument("node '" + name() + "': drop_every must be >= 0");
    if (fail_after_ < 0)
      throw std::invalid_argument("node '" + name() + "': fail_after must be >= 0");

    bool known = msgs::with_message_type(s.type, [&]<class T>() {
      const auto& ts = msgs::type_support<T>();
      type_ = &ts;
      output_ = create_generic_publisher(config.topic("output"), ts, config.qos);
      input_ = create_generic_subscription(
          config.topic("input"), ts, config.qos,
          [this](rmw::MessagePtr m, const graph::MessageInfo&) { relay(std::move(m)); });
    });
    if (!known)
      throw std::invalid_argument("node '" + name() + "': unsupported message type " + s.type);
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
    if (restamp_) {
      const auto now = std::chrono::system_clock::now().time_since_epoch();
      msg = type_->copy_with_stamp_ns(
          msg.get(), std::chrono::duration_cast<std::chrono::nanoseconds>(now).count());
    }
    output_->publish(std::move(msg));
  }

  std::chrono::microseconds delay_{0};
  int64_t drop_every_ = 0;
  int64_t fail_after_ = 0;
  int64_t received_ = 0;
  bool restamp_ = false;
  const msgs::TypeSupport* type_ = nullptr;
  std::shared_ptr<graph::GenericPublisher> output_;
  std::shared_ptr<graph::GenericSubscription> input_;
};

}  // namespace

void register_relay_kernel(plugin::Registrar& registrar) {
  registrar.add_kernel(
      {.name = "util/relay",
       .description = "republish each message unchanged; delay_ms, drop_every, fail_after and "
                      "restamp for harness checks",
       .inputs = {{"input", ""}},
       .outputs = {{"output", ""}},
       .parameters = kRelayParameters.declarations()},
      [](graph::Context& context, const KernelConfig& config) {
        return std::make_shared<RelayNode>(context, config);
      });
}

}  // namespace robotperf::util
