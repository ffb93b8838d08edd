// What `robotperf graph` prints of the participants it found.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <sstream>

#include "graph_command.hpp"

namespace robotperf::cli {
namespace {

rmw::PeerParticipant participant(const std::string& name, const std::string& topic) {
  rmw::PeerParticipant p;
  p.name = name;
  p.id[0] = 7;
  rmw::PeerEndpoint e;
  e.gid[0] = 1;
  e.writer = true;
  e.topic = topic;
  e.dds_type = "std_msgs::msg::dds_::Empty_";
  p.endpoints.push_back(e);
  return p;
}

// Any program on the domain names its participants and topics: bytes that are not UTF-8 must not
// stop the listing (they did: nlohmann's strict dump threw and the verb exited 1).
TEST(GraphPrint, JsonReplacesNamesThatAreNotUtf8) {
  GraphOptions options;
  options.json = true;
  std::ostringstream out;
  ASSERT_NO_THROW(print_graph({participant("bad\xff\xfename", "/bad\xfftopic")}, options, 7, out));
  const auto doc = nlohmann::json::parse(out.str());
  EXPECT_EQ(doc["domain_id"], 7);
  ASSERT_EQ(doc["participants"].size(), 1u);
  EXPECT_EQ(doc["participants"][0]["name"], "bad\xEF\xBF\xBD\xEF\xBF\xBDname");
  EXPECT_EQ(doc["topics"][0]["name"], "/bad\xEF\xBF\xBDtopic");
}

TEST(GraphPrint, TextCountsParticipantsAndTopics) {
  std::ostringstream out;
  print_graph({participant("talker", "/chatter")}, GraphOptions{}, 3, out);
  EXPECT_NE(out.str().find("ROS 2 graph on domain 3 (fastdds, listened 3 s): 1 participant, 0 "
                           "nodes, 1 topic"),
            std::string::npos)
      << out.str();
  EXPECT_NE(out.str().find("/chatter  [std_msgs/msg/Empty]  1 publisher, 0 subscriptions"),
            std::string::npos)
      << out.str();
}

}  // namespace
}  // namespace robotperf::cli
