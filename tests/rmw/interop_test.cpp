// Across vendors and processes: our fastdds and cyclonedds transports talk to each other both
// ways, small, VGA colour and 4 MiB images; cyclonedds carries a 30 Hz VGA colour stream between
// two processes without losing a frame.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <string>
#include <thread>
#include <utility>

#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/rmw/transport.hpp"
#include "transport_test_util.hpp"

namespace robotperf::rmw {
namespace {

using msgs::Image;
using namespace testing;

// Image `index` of a stream: rgb8 content of its own, its index in the stamp's seconds.
Image numbered_image(uint32_t width, uint32_t height, int index) {
  Image image = make_image(width, height, static_cast<uint8_t>(index), "rgb8");
  image.header.stamp.sec = index;
  return image;
}

// Publishes images 0 to count - 1 at `rate_hz`, paced to absolute deadlines.
void send_numbered_images(PublisherHandle& pub, uint32_t width, uint32_t height, int count,
                          double rate_hz) {
  const auto period = std::chrono::duration<double>(1.0 / rate_hz);
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < count; ++i) {
    pub.publish(share(numbered_image(width, height, i)));
    std::this_thread::sleep_until(
        start + std::chrono::duration_cast<std::chrono::nanoseconds>((i + 1) * period));
  }
}

// (publishing transport, subscribing transport)
class Interop : public ::testing::TestWithParam<std::pair<std::string, std::string>> {
 protected:
  // Publishes `count` images of `width` x `height` rgb8 at `rate_hz` and returns how many arrived;
  // every one that arrives must be intact and in order.
  int stream(uint32_t width, uint32_t height, int count, double rate_hz) {
    const auto& [from_name, to_name] = GetParam();
    auto from = make_transport(from_name, test_options());
    auto to = make_transport(to_name, test_options());
    Pair<Image> images(*from, *to, test_topic("interop"), QoS::ros_default());
    if (!images.matched()) {
      ADD_FAILURE() << from_name << " and " << to_name << " did not match";
      return 0;
    }
    int received = 0;
    std::thread receiver([&] {
      // Two seconds of silence after the last image ends the stream.
      while (MessagePtr got = images.inbox.take(*images.sub, nullptr, std::chrono::seconds(2))) {
        const Image& image = as<Image>(got);
        const int index = image.header.stamp.sec;
        EXPECT_GE(index, received) << "image " << index << " arrived out of order";
        EXPECT_TRUE(image == numbered_image(width, height, index))
            << width << "x" << height << " image " << index << " arrived changed";
        ++received;
      }
    });
    send_numbered_images(*images.pub, width, height, count, rate_hz);
    receiver.join();
    return received;
  }
};

TEST_P(Interop, SmallImagesArriveIntact) {
  EXPECT_EQ(stream(16, 2, 20, 50.0), 20);
}

// VGA colour at 30 Hz (fragmented samples of 900 KiB).
TEST_P(Interop, VgaColourStreamAt30Hz) {
  const int received = stream(640, 480, 60, 30.0);
  if (GetParam().first == "fastdds" && GetParam().second == "cyclonedds") {
    // Cyclone DDS 0.10.2 readers now and then never deliver a sample Fast DDS 2.9 fragmented,
    // though every fragment arrived (docs/reference/measurement.md, "Choosing a transport"): some loss, but bounded.
    EXPECT_GE(received, 54) << "more than one frame in ten lost";
  } else {
    EXPECT_EQ(received, 60);
  }
}

// 4 MiB images, one at a time.
TEST(CycloneddsToFastdds, FourMebibyteImagesArriveIntact) {
  auto from = make_transport("cyclonedds", test_options());
  auto to = make_transport("fastdds", test_options());
  Pair<Image> images(*from, *to, test_topic("interop_4mib"), QoS::ros_default());
  ASSERT_TRUE(images.matched());
  for (uint8_t seed = 0; seed < 3; ++seed) {
    const Image image = make_image(2048, 2048, seed);
    images.pub->publish(share(image));
    MessagePtr got = images.inbox.take(*images.sub);
    ASSERT_NE(got, nullptr) << "4 MiB image " << int{seed} << " did not arrive";
    EXPECT_TRUE(as<Image>(got) == image) << "4 MiB image " << int{seed} << " arrived changed";
  }
}

INSTANTIATE_TEST_SUITE_P(Vendors, Interop,
                         ::testing::Values(std::pair{"fastdds", "cyclonedds"},
                                           std::pair{"cyclonedds", "fastdds"}),
                         [](const auto& info) {
                           return info.param.first + "_to_" + info.param.second;
                         });

// 640x480 rgb8 at 30 Hz through an echo in a second process: every frame comes back, unchanged
// and in order.
TEST(CycloneddsAcrossProcesses, VgaColourStreamAt30HzLosesNothing) {
  const int domain = reserved_domain();
  const std::string ping = test_topic("vga_ping");
  const std::string pong = test_topic("vga_pong");
  auto transport = make_transport("cyclonedds", {domain});
  auto pub = transport->create_publisher(ping, msgs::type_support<Image>(), QoS::ros_default());
  Inbox inbox;
  auto sub = transport->create_subscription(pong, msgs::type_support<Image>(), QoS::ros_default(),
                                            inbox.on_ready());
  EchoPeer peer("cyclonedds", domain, ping, pong);
  ASSERT_TRUE(wait_until([&] {
    return pub->matched_subscriptions() == 1 && sub->matched_publishers() == 1;
  })) << "the peer process was not discovered";

  constexpr int kFrames = 90;  // three seconds
  std::thread sender([&] { send_numbered_images(*pub, 640, 480, kFrames, 30.0); });
  int received = 0;
  for (; received < kFrames; ++received) {
    MessagePtr echo = inbox.take(*sub);
    if (echo == nullptr) break;
    const Image& image = as<Image>(echo);
    ASSERT_EQ(image.header.stamp.sec, received) << "a frame was lost or reordered";
    ASSERT_TRUE(image == numbered_image(640, 480, received))
        << "frame " << received << " came back changed";
  }
  sender.join();
  EXPECT_EQ(received, kFrames);
  EXPECT_EQ(peer.finish(), 0);
}

}  // namespace
}  // namespace robotperf::rmw
