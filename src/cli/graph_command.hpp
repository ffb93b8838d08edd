// The `graph` verb: the ROS 2 graph visible on a DDS domain, like `ros2 node list` and
// `ros2 topic list -v`, from DDS discovery and each participant's ros_discovery_info.
#pragma once

#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "robotperf/rmw/transport.hpp"

namespace robotperf::cli {

struct GraphOptions {
  std::string rmw = "fastdds";
  std::optional<int> domain;  // default: ROS_DOMAIN_ID, else 0
  double listen_s = 3.0;      // how long to listen to discovery before listing
  bool json = false;
};

int ros_graph(const GraphOptions& options, std::ostream& out);

// What ros_graph prints of the participants it found on `domain_id`.
void print_graph(const std::vector<rmw::PeerParticipant>& peers, const GraphOptions& options,
                 int domain_id, std::ostream& out);

}  // namespace robotperf::cli
