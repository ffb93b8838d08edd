// The other process of the cross-process tests: republishes every Image it
// receives on <in_topic> unchanged on <out_topic>, until its stdin closes.
// The external graph tests launch it as a ROS 2 node runs, until SIGINT or
// SIGTERM, with a last argument:
//   until-signal   echoes, as above
//   exit-after=N   exits with status 7 after N echoes (a node that dies mid-run)
//   restamp        echoes with header.stamp set to the time of the echo (a node
//                  that does not copy its input's header)
//
// usage: echo_peer <transport> <domain_id> <in_topic> <out_topic> [MODE]
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <thread>

#include "inbox.hpp"
#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/rmw/transport.hpp"
#include "robotperf/tracing/tracepoints.hpp"

namespace rmw = robotperf::rmw;
namespace msgs = robotperf::msgs;

namespace {

std::atomic<bool> stdin_closed{false};  // or a signal came, with until-signal

void on_signal(int) {
  stdin_closed = true;
}

// The parent ends a run by closing our stdin; a parent that died does too.
void wait_for_stdin_eof() {
  char buffer[64];
  while (read(STDIN_FILENO, buffer, sizeof buffer) > 0) {
  }
}

struct Mode {
  bool until_signal = false;
  long exit_after = -1;  // echoes before exiting; -1: never
  bool restamp = false;
};

int run(const std::string& transport_name, int domain_id, const std::string& in_topic,
        const std::string& out_topic, const Mode& mode) {
  auto transport = rmw::make_transport(transport_name, {domain_id});
  rmw::testing::Inbox inbox;
  const auto& type = msgs::type_support<msgs::Image>();
  // A ROS 2 node as ROS 2 tools would see it.
  const rmw::NodeName node{"echo_peer", "/"};
  auto publisher = transport->create_publisher(out_topic, type, rmw::QoS::ros_default(), node);
  auto subscription = transport->create_subscription(in_topic, type, rmw::QoS::ros_default(),
                                                     inbox.on_ready(), node);
  // As a ROS 2 node with ros2_tracing's tracetools announces itself (its transport's rmw_publish
  // and rmw_take events are robotperf's own): a grey-box run of an external graph names it.
  static const char node_handle = 0, publisher_handle = 0, subscription_handle = 0;
  lttng_ust_tracepoint(ros2, rcl_node_init, &node_handle, transport.get(), node.name.c_str(),
                       node.namespace_.c_str());
  lttng_ust_tracepoint(ros2, rcl_publisher_init, &publisher_handle, &node_handle, publisher.get(),
                       out_topic.c_str(), std::size_t{10});
  lttng_ust_tracepoint(ros2, rcl_subscription_init, &subscription_handle, &node_handle,
                       subscription.get(), in_topic.c_str(), std::size_t{10});

  if (mode.until_signal) {
    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
  } else {
    std::thread([] {
      wait_for_stdin_eof();
      stdin_closed = true;
    }).detach();
  }

  long remaining = mode.exit_after - 1;
  while (!stdin_closed) {
    rmw::MessagePtr msg = inbox.take(*subscription, nullptr, std::chrono::milliseconds(100));
    if (!msg) continue;
    // A volatile sample written before the parent's reader matched would be lost.
    if (!rmw::testing::wait_until([&] { return publisher->matched_subscriptions() > 0; })) {
      std::fprintf(stderr, "echo_peer: nobody subscribes to %s\n", out_topic.c_str());
      return 1;
    }
    if (mode.restamp) {
      auto copy = std::make_shared<msgs::Image>(*static_cast<const msgs::Image*>(msg.get()));
      copy->header.stamp = msgs::Time::from_ns(rmw::wall_now_ns());
      msg = copy;
    }
    publisher->publish(msg);
    if (mode.exit_after >= 0 && --remaining < 0) {
      std::fprintf(stderr, "echo_peer: exiting after %ld echoes, as asked\n", mode.exit_after);
      return 7;
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Mode mode;
  if (argc == 6) {
    const std::string m = argv[5];
    mode.until_signal = true;
    if (m.rfind("exit-after=", 0) == 0) {
      mode.exit_after = std::atol(m.c_str() + 11);
    } else if (m == "restamp") {
      mode.restamp = true;
    } else if (m != "until-signal") {
      argc = 0;  // a usage error
    }
  }
  if (argc != 5 && argc != 6) {
    std::fprintf(stderr,
                 "usage: %s <transport> <domain_id> <in_topic> <out_topic> "
                 "[until-signal|exit-after=N|restamp]\n",
                 argv[0]);
    return 2;
  }
  try {
    return run(argv[1], std::atoi(argv[2]), argv[3], argv[4], mode);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "echo_peer: %s\n", e.what());
    return 1;
  }
}
