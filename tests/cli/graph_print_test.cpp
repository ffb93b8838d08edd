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

// A node's service endpoints (rq/...Request and rr/...Reply) are shown as the service they make,
// with the server and the client told apart; a request topic without its reply stays an endpoint.
TEST(GraphPrint, ServicesAreFoldedFromTheirRequestAndReplyTopics) {
  rmw::PeerParticipant p;
  p.name = "talker";
  auto add = [&](uint8_t n, bool writer, const std::string& topic, const std::string& type) {
    rmw::PeerEndpoint e;
    e.gid[0] = n;
    e.writer = writer;
    e.topic = topic;
    e.dds_type = type;
    p.endpoints.push_back(e);
    (writer ? p.nodes.back().writers : p.nodes.back().readers).push_back(e.gid);
  };
  p.nodes.push_back({});
  p.nodes.back().namespace_ = "/";
  p.nodes.back().name = "talker";
  const std::string req = "rcl_interfaces::srv::dds_::GetParameters_Request_";
  const std::string rep = "rcl_interfaces::srv::dds_::GetParameters_Response_";
  add(1, false, "rq/talker/get_parametersRequest", req);  // server: reads requests
  add(2, true, "rr/talker/get_parametersReply", rep);
  add(3, true, "rq/other/get_parametersRequest", req);  // client: writes requests
  add(4, false, "rr/other/get_parametersReply", rep);
  add(5, true, "rq/lonely/resetRequest", "std_srvs::srv::dds_::Empty_Request_");
  add(6, true, "/chatter", "std_msgs::msg::dds_::String_");

  std::ostringstream out;
  print_graph({p}, GraphOptions{}, 3, out);
  const std::string text = out.str();
  EXPECT_NE(text.find("1 topic, 2 services"), std::string::npos) << text;
  EXPECT_NE(text.find("serves      /talker/get_parameters  [rcl_interfaces/srv/GetParameters]"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("calls       /other/get_parameters  [rcl_interfaces/srv/GetParameters]"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("publishes   rq/lonely/resetRequest"), std::string::npos) << text;
  EXPECT_EQ(text.find("rq/talker"), std::string::npos) << text;
  EXPECT_NE(text.find("/talker/get_parameters  [rcl_interfaces/srv/GetParameters]  1 server, 0 "
                      "clients"),
            std::string::npos)
      << text;

  GraphOptions json_options;
  json_options.json = true;
  std::ostringstream json_out;
  print_graph({p}, json_options, 3, json_out);
  const auto doc = nlohmann::json::parse(json_out.str());
  const auto& node = doc["participants"][0]["nodes"][0];
  EXPECT_EQ(node["services"].size(), 2u);
  EXPECT_EQ(node["endpoints"].size(), 2u);  // the lonely request and /chatter
}

}  // namespace
}  // namespace robotperf::cli
