// The other process of the cross-process tests: republishes every Image it
// receives on <in_topic> unchanged on <out_topic>, until its stdin closes.
//
// usage: echo_peer <transport> <domain_id> <in_topic> <out_topic>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <thread>

#include "inbox.hpp"
#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/rmw/transport.hpp"

namespace rmw = robotperf::rmw;
namespace msgs = robotperf::msgs;

namespace {

std::atomic<bool> stdin_closed{false};

// The parent ends a run by closing our stdin; a parent that died does too.
void wait_for_stdin_eof() {
  char buffer[64];
  while (read(STDIN_FILENO, buffer, sizeof buffer) > 0) {
  }
}

int run(const std::string& transport_name, int domain_id, const std::string& in_topic,
        const std::string& out_topic) {
  auto transport = rmw::make_transport(transport_name, {domain_id});
  rmw::testing::Inbox inbox;
  const auto& type = msgs::type_support<msgs::Image>();
  auto publisher = transport->create_publisher(out_topic, type, rmw::QoS::ros_default());
  auto subscription =
      transport->create_subscription(in_topic, type, rmw::QoS::ros_default(), inbox.on_ready());

  std::thread([] {
    wait_for_stdin_eof();
    stdin_closed = true;
  }).detach();

  while (!stdin_closed) {
    rmw::MessagePtr msg = inbox.take(*subscription, nullptr, std::chrono::milliseconds(100));
    if (!msg) continue;
    // A volatile sample written before the parent's reader matched would be lost.
    if (!rmw::testing::wait_until([&] { return publisher->matched_subscriptions() > 0; })) {
      std::fprintf(stderr, "echo_peer: nobody subscribes to %s\n", out_topic.c_str());
      return 1;
    }
    publisher->publish(msg);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 5) {
    std::fprintf(stderr, "usage: %s <transport> <domain_id> <in_topic> <out_topic>\n", argv[0]);
    return 2;
  }
  try {
    return run(argv[1], std::atoi(argv[2]), argv[3], argv[4]);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "echo_peer: %s\n", e.what());
    return 1;
  }
}
