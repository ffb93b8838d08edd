// What the readiness check says of an endpoint that found no peer, from what the other
// participants of the domain have.
#include "graph_connection.hpp"

#include <gtest/gtest.h>

namespace robotperf::harness {
namespace {

rmw::PeerParticipant running_graph() {
  rmw::PeerParticipant p;
  p.name = "launched";
  uint8_t n = 0;
  for (const auto& [topic, writer] :
       {std::pair{"/camera/image_rect", true}, std::pair{"/camera/image_raw", false},
        std::pair{"/rosout", true}}) {
    rmw::PeerEndpoint e;
    e.gid[0] = ++n;
    e.writer = writer;
    e.topic = topic;
    e.dds_type = "sensor_msgs::msg::dds_::Image_";
    p.endpoints.push_back(e);
  }
  return p;
}

// A graph that runs with its output named otherwise: the line names what the others publish, and
// the nearest name when ours looks like a typo of it.
TEST(GraphConnection, ATopicNobodyHasListsWhatTheOthersHave) {
  const graph::EndpointStatus ours{"/camera/image_rec", "sensor_msgs/msg/Image", false, 0};
  const std::string line = others_on_topic({running_graph()}, ours, rmw::QoS{}, 41);
  EXPECT_EQ(line,
            "no other participant on domain 41 has an endpoint on it; the others publish "
            "/camera/image_rect [sensor_msgs/msg/Image], /rosout [sensor_msgs/msg/Image]; did "
            "you mean '/camera/image_rect'?");
  // Nothing running at all: the old hint.
  EXPECT_EQ(others_on_topic({}, ours, rmw::QoS{}, 41),
            "no other participant on domain 41 has an endpoint on it (is the graph running, with "
            "this domain and RMW?)");
}

}  // namespace
}  // namespace robotperf::harness
