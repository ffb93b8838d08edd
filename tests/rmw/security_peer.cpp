// The other process of the DDS Security tests (Cyclone DDS delivers between participants of one
// process without authenticating them, so only separate processes show what security admits),
// until its stdin closes:
//
//   echo:    republishes every Image it receives on <in_topic> unchanged on <out_topic>;
//   intrude: publishes an Image with frame "intruder" on <out_topic> every 50 ms, and counts what
//            it receives on <in_topic>.
//
// usage: security_peer <transport> <domain_id> <keystore, or - for none> <in_topic> <out_topic>
//                      echo|intrude
// It writes "ready" on stdout once it runs (the intruder: once its first message reached its own
// subscription, proof that it publishes). Exit status: 0; 3 when the intruder received something;
// 1 on errors.
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <memory>
#include <string>
#include <thread>

#include "fastdds_leak_suppressions.hpp"
#include "inbox.hpp"
#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/rmw/security.hpp"
#include "robotperf/rmw/transport.hpp"

namespace rmw = robotperf::rmw;
namespace msgs = robotperf::msgs;

namespace {

std::atomic<bool> stdin_closed{false};

void say_ready() {
  std::puts("ready");
  std::fflush(stdout);
}

// The parent ends a run by closing our stdin; a parent that died does too.
void watch_stdin() {
  std::thread([] {
    char buffer[64];
    while (read(STDIN_FILENO, buffer, sizeof buffer) > 0) {
    }
    stdin_closed = true;
  }).detach();
}

int echo(rmw::Transport& transport, const std::string& in_topic, const std::string& out_topic) {
  rmw::testing::Inbox inbox;
  const auto& type = msgs::type_support<msgs::Image>();
  auto publisher = transport.create_publisher(out_topic, type, rmw::QoS::ros_default());
  auto subscription =
      transport.create_subscription(in_topic, type, rmw::QoS::ros_default(), inbox.on_ready());
  say_ready();
  watch_stdin();
  while (!stdin_closed) {
    rmw::MessagePtr msg = inbox.take(*subscription, nullptr, std::chrono::milliseconds(100));
    if (!msg) continue;
    // A volatile sample written before the parent's reader matched would be lost.
    if (!rmw::testing::wait_until([&] { return publisher->matched_subscriptions() > 0; })) {
      std::fprintf(stderr, "security_peer: nobody subscribes to %s\n", out_topic.c_str());
      return 1;
    }
    publisher->publish(msg);
  }
  return 0;
}

int intrude(rmw::Transport& transport, const std::string& in_topic, const std::string& out_topic) {
  const auto& type = msgs::type_support<msgs::Image>();
  rmw::testing::Inbox inbox;
  auto subscription =
      transport.create_subscription(in_topic, type, rmw::QoS::ros_default(), inbox.on_ready());
  auto publisher = transport.create_publisher(out_topic, type, rmw::QoS::ros_default());
  // Its own messages, seen by its own participant: proof that it did publish.
  auto own = transport.create_subscription(out_topic, type, rmw::QoS::ros_default(), [] {});
  msgs::Image image;
  image.header.frame_id = "intruder";
  image.encoding = "mono8";
  image.width = image.height = image.step = 4;
  image.data.assign(16, 0x5a);
  const auto message = std::make_shared<const msgs::Image>(image);
  int received = 0;
  bool published = false;
  watch_stdin();
  while (!stdin_closed) {
    publisher->publish(message);
    while (inbox.take(*subscription, nullptr, std::chrono::milliseconds(50))) ++received;
    if (!published && own->take(nullptr)) {
      published = true;
      say_ready();
    }
  }
  if (received > 0) {
    std::fprintf(stderr, "security_peer: the intruder received %d message(s) on %s\n", received,
                 in_topic.c_str());
    return 3;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string role = argc == 7 ? argv[6] : "";
  if (role != "echo" && role != "intrude") {
    std::fprintf(stderr,
                 "usage: %s <transport> <domain_id> <keystore|-> <in_topic> <out_topic> "
                 "echo|intrude\n",
                 argv[0]);
    return 2;
  }
  try {
    rmw::TransportOptions options(std::atoi(argv[2]));
    if (std::string(argv[3]) != "-") options.security = rmw::enclave_files(argv[3]);
    auto transport = rmw::make_transport(argv[1], options);
    return role == "echo" ? echo(*transport, argv[4], argv[5])
                          : intrude(*transport, argv[4], argv[5]);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "security_peer: %s\n", e.what());
    return 1;
  }
}
