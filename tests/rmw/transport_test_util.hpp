// What the transport tests share: test messages, a discovered publisher/subscription pair, and the
// echo peer in a second process.
#pragma once

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "inbox.hpp"
#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/rmw/transport.hpp"

extern char** environ;

namespace robotperf::rmw::testing {

// Tests run in parallel as separate processes: each reserves its own domain, and topic names
// carry the process id, so no two tests can see each other.
inline std::string test_topic(const std::string& name) {
  return "/robotperf_test/" + name + "_" + std::to_string(getpid());
}

inline TransportOptions test_options(std::string user_data = {}) {
  return TransportOptions(reserved_domain(), std::move(user_data));
}

inline msgs::Image make_image(uint32_t width, uint32_t height, uint8_t seed,
                              const std::string& encoding = "mono8") {
  const uint32_t channels = encoding == "rgb8" ? 3 : 1;
  msgs::Image img;
  img.header.stamp = msgs::Time{1700000000, 123456789};
  img.header.frame_id = "camera_optical_frame";
  img.width = width;
  img.height = height;
  img.encoding = encoding;
  img.step = width * channels;
  img.data.resize(std::size_t{img.step} * height);
  for (std::size_t i = 0; i < img.data.size(); ++i) {
    img.data[i] = static_cast<uint8_t>(i * 31 + seed + i / 251);
  }
  return img;
}

inline msgs::CameraInfo make_camera_info() {
  msgs::CameraInfo info;
  info.header.stamp = msgs::Time{42, 999999999};
  info.header.frame_id = "left";
  info.width = 1280;
  info.height = 720;
  info.distortion_model = "plumb_bob";
  info.d = {-0.28, 0.07, 0.0002, -0.0001, 0.0};
  info.k = {700.5, 0, 640.25, 0, 701.0, 360.75, 0, 0, 1};
  info.r = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  info.p = {700.5, 0, 640.25, -42.1, 0, 701.0, 360.75, 0, 0, 0, 1, 0};
  info.binning_x = 2;
  info.binning_y = 3;
  info.roi = {10, 20, 300, 400, true};
  return info;
}

template <class T>
MessagePtr share(T msg) {
  return std::make_shared<const T>(std::move(msg));
}

template <class T>
const T& as(const MessagePtr& msg) {
  return *static_cast<const T*>(msg.get());
}

// A publisher on one transport and a subscription on another (or the same), on one topic.
template <class T>
struct Pair {
  Pair(Transport& from, Transport& to, const std::string& topic, const QoS& qos) {
    pub = from.create_publisher(topic, msgs::type_support<T>(), qos);
    sub = to.create_subscription(topic, msgs::type_support<T>(), qos, inbox.on_ready());
  }
  Pair(Transport& transport, const std::string& topic, const QoS& qos)
      : Pair(transport, transport, topic, qos) {}
  bool matched() {
    return wait_until(
        [&] { return pub->matched_subscriptions() == 1 && sub->matched_publishers() == 1; });
  }
  Inbox inbox;  // outlives `sub`, which notifies it
  std::unique_ptr<PublisherHandle> pub;
  std::unique_ptr<SubscriptionHandle> sub;
};

// A peer program (echo_peer.cpp, security_peer.cpp) in its own process: `args` with argv[0] the
// program, its stdin a pipe from us (closing it ends the peer) and its stdout a pipe to us.
class PeerProcess {
 public:
  explicit PeerProcess(std::vector<std::string> args) {
    int in[2], out[2];
    if (pipe2(in, O_CLOEXEC) != 0) throw std::runtime_error("pipe2 failed");
    if (pipe2(out, O_CLOEXEC) != 0) {
      close(in[0]);
      close(in[1]);
      throw std::runtime_error("pipe2 failed");
    }
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, in[0], STDIN_FILENO);
    posix_spawn_file_actions_adddup2(&actions, out[1], STDOUT_FILENO);
    std::vector<char*> argv;
    for (auto& arg : args) argv.push_back(arg.data());
    argv.push_back(nullptr);
    const int rc = posix_spawn(&pid_, argv[0], &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    close(in[0]);
    close(out[1]);
    stdin_ = in[1];
    stdout_ = out[0];
    if (rc != 0) {
      close(stdin_);
      close(stdout_);
      throw std::runtime_error("cannot start " + args[0]);
    }
  }
  PeerProcess(const PeerProcess&) = delete;
  PeerProcess& operator=(const PeerProcess&) = delete;
  ~PeerProcess() {
    if (pid_ > 0) {
      kill(pid_, SIGKILL);
      finish();
    }
  }

  // Whether the peer printed a line starting with "ready" within `timeout`.
  bool ready(std::chrono::milliseconds timeout) {
    pollfd said{.fd = stdout_, .events = POLLIN, .revents = 0};
    char line[8] = {};
    return poll(&said, 1, static_cast<int>(timeout.count())) == 1 &&
           read(stdout_, line, sizeof line) > 0 && std::string_view(line).starts_with("ready");
  }

  // Closes the peer's stdin and returns its exit status (-1 if it had to be killed after
  // `timeout`).
  int finish(std::chrono::milliseconds timeout = std::chrono::seconds(5)) {
    if (stdin_ >= 0) close(stdin_);
    if (stdout_ >= 0) close(stdout_);
    stdin_ = stdout_ = -1;
    int status = 0;
    const bool exited =
        wait_until([&] { return waitpid(pid_, &status, WNOHANG) == pid_; }, timeout);
    if (!exited) {
      kill(pid_, SIGKILL);
      waitpid(pid_, &status, 0);
    }
    pid_ = -1;
    return exited && WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }

 private:
  pid_t pid_ = -1;
  int stdin_ = -1;
  int stdout_ = -1;
};

#ifdef ROBOTPERF_ECHO_PEER
// The echo peer (echo_peer.cpp): republishes what it receives on `in_topic` on `out_topic`.
class EchoPeer : public PeerProcess {
 public:
  EchoPeer(const std::string& transport, int domain_id, const std::string& in_topic,
           const std::string& out_topic)
      : PeerProcess(
            {ROBOTPERF_ECHO_PEER, transport, std::to_string(domain_id), in_topic, out_topic}) {}
};
#endif

}  // namespace robotperf::rmw::testing
