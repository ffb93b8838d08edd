// ROS 2 graph conformance of the DDS transports (docs/design.md §2), seen by a plain Fast DDS
// participant and decoded from the ROS 2 .msg files alone: each participant publishes its nodes
// on ros_discovery_info (rmw_dds_common/msg/ParticipantEntitiesInfo, GIDs in the chosen
// distribution's layout) and, from Iron on, each endpoint's REP 2011 type hash in its USER_DATA.
// A second robotperf participant reads both back as `robotperf graph` does.
#include "ros_graph.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/domain/DomainParticipantListener.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "../shared_data.hpp"
#include "fastdds_raw_bytes_type.hpp"
#include "robotperf/msgs/dynamic.hpp"
#include "transport_test_util.hpp"

namespace robotperf::rmw {
namespace {

namespace dds = eprosima::fastdds::dds;
namespace dyn = msgs::dynamic;
using eprosima::fastrtps::types::ReturnCode_t;
using namespace testing;

constexpr const char* kImageHash =
    "RIHS01_d31d41a9a4c4bc8eae9be757b0beed306564f7526c88ea6a4588fb9582527d47";

std::string read_text(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// rmw_dds_common's three types from its .msg files, with Humble's or Iron's Gid.
dyn::TypeRegistry rmw_dds_common_types(RosDistro distro) {
  const std::filesystem::path files = shared_data("msg/rmw_dds_common");
  dyn::TypeRegistry registry;
  registry.add_msg("rmw_dds_common/msg/Gid",
                   read_text(distro == RosDistro::kHumble ? files / "humble" / "Gid.msg"
                                                          : files / "msg" / "Gid.msg"));
  for (const char* type : {"NodeEntitiesInfo", "ParticipantEntitiesInfo"}) {
    registry.add_msg(std::string("rmw_dds_common/msg/") + type,
                     read_text(files / "msg" / (std::string(type) + ".msg")));
  }
  return registry;
}

std::vector<uint8_t> bytes_of(const dyn::Value& gid) {
  return std::get<dyn::Bytes>(gid["data"].data);
}

std::vector<uint8_t> padded(const Gid& gid, std::size_t size) {
  std::vector<uint8_t> out(gid.begin(), gid.end());
  out.resize(size, 0);
  return out;
}

// A plain Fast DDS participant that reads ros_discovery_info as raw bytes and records every
// writer it discovers (GID and USER_DATA by topic).
class Observer final : public dds::DomainParticipantListener {
 public:
  explicit Observer(int domain) {
    auto* factory = dds::DomainParticipantFactory::get_instance();
    participant_ = factory->create_participant(domain, factory->get_default_participant_qos(), this,
                                               dds::StatusMask::none());
    type_ = dds::TypeSupport(
        new FastddsRawBytesType("rmw_dds_common::msg::dds_::ParticipantEntitiesInfo_"));
    type_.register_type(participant_);
    auto* subscriber = participant_->create_subscriber(participant_->get_default_subscriber_qos());
    auto* topic = participant_->create_topic("ros_discovery_info", type_.get_type_name(),
                                             participant_->get_default_topic_qos());
    dds::DataReaderQos qos = subscriber->get_default_datareader_qos();
    qos.reliability().kind = dds::RELIABLE_RELIABILITY_QOS;
    qos.durability().kind = dds::TRANSIENT_LOCAL_DURABILITY_QOS;
    qos.history().kind = dds::KEEP_LAST_HISTORY_QOS;
    qos.history().depth = 100;
    qos.endpoint().history_memory_policy =
        eprosima::fastrtps::rtps::PREALLOCATED_WITH_REALLOC_MEMORY_MODE;
    reader_ = subscriber->create_datareader(topic, qos);
  }
  ~Observer() override {
    participant_->delete_contained_entities();
    dds::DomainParticipantFactory::get_instance()->delete_participant(participant_);
  }

  // The latest ros_discovery_info sample of the participant whose GUID prefix is `prefix`.
  std::optional<std::vector<uint8_t>> latest_from(const ParticipantId& prefix) {
    FastddsRawBytesType::Sample bytes;
    dds::SampleInfo info;
    while (reader_->take_next_sample(&bytes, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) continue;
      ParticipantId sender;
      std::memcpy(sender.data(), info.sample_identity.writer_guid().guidPrefix.value,
                  sender.size());
      latest_[sender] = bytes;
    }
    if (auto it = latest_.find(prefix); it != latest_.end()) return it->second;
    return std::nullopt;
  }

  struct Writer {
    Gid gid{};
    std::string user_data;
  };
  std::optional<Writer> writer_on(const std::string& dds_topic) {
    std::lock_guard lock(mutex_);
    if (auto it = writers_.find(dds_topic); it != writers_.end()) return it->second;
    return std::nullopt;
  }

  void on_publisher_discovery(dds::DomainParticipant*,
                              eprosima::fastrtps::rtps::WriterDiscoveryInfo&& info) override {
    Writer w;
    std::memcpy(w.gid.data(), info.info.guid().guidPrefix.value, 12);
    std::memcpy(w.gid.data() + 12, info.info.guid().entityId.value, 4);
    const auto& data = info.info.m_qos.m_userData.data_vec();
    w.user_data.assign(data.begin(), data.end());
    std::lock_guard lock(mutex_);
    writers_[info.info.topicName().to_string()] = w;
  }

 private:
  dds::DomainParticipant* participant_ = nullptr;
  dds::TypeSupport type_;
  dds::DataReader* reader_ = nullptr;
  std::map<ParticipantId, std::vector<uint8_t>> latest_;
  std::mutex mutex_;
  std::map<std::string, Writer> writers_;
};

class RosGraph : public ::testing::TestWithParam<std::string> {};

// The node of `sample` named /demo/talker, or nullptr.
const dyn::Value* talker_in(const dyn::Value& sample) {
  for (const dyn::Value& node : std::get<dyn::List>(sample["node_entities_info_seq"].data)) {
    if (std::get<std::string>(node["node_namespace"].data) == "/demo" &&
        std::get<std::string>(node["node_name"].data) == "talker") {
      return &node;
    }
  }
  return nullptr;
}

std::size_t count(const dyn::Value& node, const char* field) {
  return std::get<dyn::List>(node[field].data).size();
}

void check_announcements(const std::string& vendor, RosDistro distro) {
  const int domain = reserved_domain();
  Observer observer(domain);
  TransportOptions options(domain);
  options.ros_distro = distro;
  auto transport = make_transport(vendor, options);
  const NodeName talker{"talker", "/demo"};
  const std::string topic = testing::test_topic("chatter");
  auto pub = transport->create_publisher(topic, msgs::type_support<msgs::Image>(), QoS{}, talker);
  auto sub = transport->create_subscription(
      topic + "_in", msgs::type_support<msgs::CameraInfo>(), QoS{}, [] {}, talker);
  const std::size_t gid_size = distro == RosDistro::kHumble ? 24 : 16;
  const dyn::TypeRegistry types = rmw_dds_common_types(distro);

  dyn::Value sample;
  ASSERT_TRUE(testing::wait_until([&] {
    auto bytes = observer.latest_from(transport->participant());
    if (!bytes) return false;
    sample = dyn::decode(types, "rmw_dds_common/msg/ParticipantEntitiesInfo", *bytes);
    const dyn::Value* node = talker_in(sample);
    return node != nullptr && count(*node, "writer_gid_seq") == 1 &&
           count(*node, "reader_gid_seq") == 1;
  })) << "no ros_discovery_info sample with /demo/talker's endpoints";
  const std::vector<uint8_t> participant_gid = bytes_of(sample["gid"]);
  ASSERT_EQ(participant_gid.size(), gid_size);
  const ParticipantId self = transport->participant();
  EXPECT_TRUE(std::equal(self.begin(), self.end(), participant_gid.begin()));

  std::optional<Observer::Writer> writer;
  ASSERT_TRUE(testing::wait_until([&] {
    writer = observer.writer_on("rt" + topic);
    return writer.has_value();
  }));
  const dyn::Value& node = *talker_in(sample);
  EXPECT_EQ(bytes_of(std::get<dyn::List>(node["writer_gid_seq"].data)[0]),
            padded(writer->gid, gid_size))
      << "the node's writer is the writer discovery announces";
  // ros_discovery_info's own writer carries its type's hash too, as rmw does on Iron and later.
  std::optional<Observer::Writer> discovery;
  ASSERT_TRUE(testing::wait_until([&] {
    discovery = observer.writer_on("ros_discovery_info");
    return discovery.has_value();
  }));
  if (distro == RosDistro::kHumble) {
    EXPECT_EQ(writer->user_data.find("typehash="), std::string::npos) << writer->user_data;
    EXPECT_EQ(discovery->user_data.find("typehash="), std::string::npos) << discovery->user_data;
  } else {
    EXPECT_EQ(writer->user_data, std::string("typehash=") + kImageHash + ";");
    EXPECT_EQ(discovery->user_data,
              "typehash=RIHS01_91a0593bacdcc50ea9bdcf849a938b128412cc1ea821245c663bcd26f83c295e;");
  }

  // A writer that goes is withdrawn from its node.
  pub.reset();
  ASSERT_TRUE(testing::wait_until([&] {
    auto bytes = observer.latest_from(transport->participant());
    sample = dyn::decode(types, "rmw_dds_common/msg/ParticipantEntitiesInfo", *bytes);
    const dyn::Value* n = talker_in(sample);
    return n != nullptr && count(*n, "writer_gid_seq") == 0 && count(*n, "reader_gid_seq") == 1;
  }));
}

TEST_P(RosGraph, AnnouncesNodesAndTypeHashesAsJazzy) {
  check_announcements(GetParam(), RosDistro::kJazzy);
}

TEST_P(RosGraph, AnnouncesHumbleGidsWithoutTypeHashes) {
  check_announcements(GetParam(), RosDistro::kHumble);
}

// What `robotperf graph` lists: the other participant's nodes, endpoints, types, QoS and hashes.
TEST_P(RosGraph, PeersReadNodesEndpointsAndHashes) {
  const TransportOptions options = testing::test_options();
  auto talker_side = make_transport(GetParam(), options);
  auto listener_side = make_transport(GetParam() == "fastdds" ? "cyclonedds" : "fastdds", options);
  const std::string topic = testing::test_topic("chatter");
  auto pub = talker_side->create_publisher(topic, msgs::type_support<msgs::Image>(),
                                           QoS::sensor_data(), NodeName{"talker", "/demo"});
  std::optional<PeerParticipant> seen;
  ASSERT_TRUE(testing::wait_until([&] {
    for (const PeerParticipant& p : listener_side->peers()) {
      if (p.id != talker_side->participant()) continue;
      const bool has_node = !p.nodes.empty() && !p.nodes[0].writers.empty();
      const bool has_endpoint =
          std::ranges::any_of(p.endpoints, [&](const PeerEndpoint& e) { return e.topic == topic; });
      if (has_node && has_endpoint) seen = p;
    }
    return seen.has_value();
  }));
  ASSERT_EQ(seen->nodes.size(), 1u);
  EXPECT_EQ(seen->nodes[0].namespace_, "/demo");
  EXPECT_EQ(seen->nodes[0].name, "talker");
  const Gid writer = seen->nodes[0].writers.at(0);
  const auto endpoint =
      std::ranges::find_if(seen->endpoints, [&](const PeerEndpoint& e) { return e.gid == writer; });
  ASSERT_NE(endpoint, seen->endpoints.end());
  EXPECT_EQ(endpoint->topic, topic);
  EXPECT_TRUE(endpoint->writer);
  EXPECT_EQ(endpoint->dds_type, "sensor_msgs::msg::dds_::Image_");
  EXPECT_EQ(endpoint->qos.reliability, Reliability::kBestEffort);
  EXPECT_EQ(endpoint->qos.durability, Durability::kVolatile);
  EXPECT_EQ(endpoint->type_hash, kImageHash);
}

// ros_discovery_info is keyless: all participants' announcements share the reader's history, while
// each writer keeps only its latest. A burst of one participant's announcements that the observer
// had not read yet pushed out a quiet participant's last one, and its nodes were gone for good
// (from 150 endpoints on Cyclone DDS, 400 on Fast DDS).
TEST_P(RosGraph, NodesSurviveABurstOfAnnouncements) {
  constexpr std::size_t kBurst = 500;
  const TransportOptions options = testing::test_options();
  const auto& type = msgs::type_support<msgs::Image>();
  auto observer = make_transport(GetParam(), options);
  auto quiet = make_transport(GetParam(), options);
  auto busy = make_transport(GetParam(), options);
  // The observer discovers both before the burst, without reading its peers (which took the
  // samples waiting in the reader).
  const std::string topic = testing::test_topic("heard");
  auto heard = observer->create_subscription(topic, type, QoS{}, [] {});
  auto quiet_pub = quiet->create_publisher(topic, type, QoS{}, NodeName{"quiet_node", "/"});
  auto busy_pub = busy->create_publisher(topic, type, QoS{}, NodeName{"busy_node", "/"});
  ASSERT_TRUE(testing::wait_until([&] { return heard->matched_publishers() == 2; }));

  std::vector<std::unique_ptr<PublisherHandle>> burst;
  for (std::size_t i = 0; i < kBurst; ++i) {
    burst.push_back(busy->create_publisher(testing::test_topic("burst_" + std::to_string(i)), type,
                                           QoS{}, NodeName{"busy_node", "/"}));
  }
  auto writers_of = [](const std::vector<PeerParticipant>& peers, const ParticipantId& id,
                       const std::string& node) {
    for (const PeerParticipant& p : peers) {
      if (p.id != id) continue;
      for (const PeerNode& n : p.nodes) {
        if (n.name == node) return n.writers.size();
      }
    }
    return std::size_t{0};
  };
  std::vector<PeerParticipant> peers;
  EXPECT_TRUE(testing::wait_until([&] {
    peers = observer->peers();
    return writers_of(peers, busy->participant(), "busy_node") == kBurst + 1 &&
           writers_of(peers, quiet->participant(), "quiet_node") == 1;
  })) << "busy_node: "
      << writers_of(peers, busy->participant(), "busy_node")
      << " writers, quiet_node: " << writers_of(peers, quiet->participant(), "quiet_node");
}

INSTANTIATE_TEST_SUITE_P(Dds, RosGraph, ::testing::Values("fastdds", "cyclonedds"),
                         [](const auto& info) { return info.param; });

// The codec against itself for both layouts, and the .msg-driven codec reading what it wrote.
TEST(ParticipantEntities, EitherLayoutDecodes) {
  Gid participant{};
  participant[0] = 1;
  participant[15] = 0xc1;
  Gid endpoint{};
  endpoint[3] = 7;
  const std::vector<PeerNode> nodes{{"/", "a", {endpoint}, {}}, {"/ns", "b", {}, {endpoint}}};
  for (RosDistro distro : {RosDistro::kHumble, RosDistro::kJazzy}) {
    const auto cdr = encode_participant_entities(participant, nodes, distro);
    const auto back = decode_participant_entities(cdr);
    ASSERT_TRUE(back.has_value()) << to_string(distro);
    EXPECT_EQ(back->participant, participant);
    ASSERT_EQ(back->nodes.size(), 2u);
    EXPECT_EQ(back->nodes[1].namespace_, "/ns");
    EXPECT_EQ(back->nodes[1].writers, std::vector<Gid>{endpoint});
    // The .msg-driven codec reads the same sample with the distribution's Gid.
    const auto value = dyn::decode(rmw_dds_common_types(distro),
                                   "rmw_dds_common/msg/ParticipantEntitiesInfo", cdr);
    EXPECT_EQ(bytes_of(value["gid"]).size(), distro == RosDistro::kHumble ? 24u : 16u);
  }
  EXPECT_FALSE(decode_participant_entities(std::vector<uint8_t>{0, 1, 0, 0, 1, 2, 3}).has_value());
}

TEST(ParticipantEntities, UserDataValuesAreReadByKey) {
  EXPECT_EQ(user_data_value("typehash=RIHS01_ab;", "typehash"), "RIHS01_ab");
  EXPECT_EQ(user_data_value("enclave=/;typehash=RIHS01_cd;x=y;", "typehash"), "RIHS01_cd");
  EXPECT_EQ(user_data_value("enclave=/;typehash=RIHS01_cd", "enclave"), "/");
  EXPECT_EQ(user_data_value("enclave=/;", "typehash"), "");
  EXPECT_EQ(user_data_value("typehashes=x;", "typehash"), "");
  EXPECT_EQ(user_data_value("", "typehash"), "");
}

// Node names as rcl takes them: a namespace before the name, each part a ROS name token.
TEST(NodeNames, SplitAndCheckedAsRclDoes) {
  auto split = [](std::string_view full) {
    const NodeName n = parse_node_name(full);
    return n.namespace_ + " " + n.name;
  };
  EXPECT_EQ(split("relay"), "/ relay");
  EXPECT_EQ(split("ns/relay"), "/ns relay");
  EXPECT_EQ(split("/ns/relay"), "/ns relay");
  EXPECT_EQ(split("a/b_2/_relay"), "/a/b_2 _relay");
  auto error = [](std::string_view full) {
    try {
      parse_node_name(full);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(error("my-relay"),
            "node name 'my-relay' is not a ROS 2 node name: '-' in its name (letters, digits and "
            "'_' only; a namespace before it: 'ns/relay')");
  EXPECT_EQ(error("2relay"),
            "node name '2relay' is not a ROS 2 node name: its name starts with a digit ('2relay')");
  EXPECT_EQ(error("relay node"),
            "node name 'relay node' is not a ROS 2 node name: ' ' in its name (letters, digits "
            "and '_' only; a namespace before it: 'ns/relay')");
  EXPECT_NE(error("ns//relay").find("empty part"), std::string::npos);
  EXPECT_NE(error("relay/").find("empty part"), std::string::npos);
  EXPECT_NE(error("9ns/relay").find("its namespace starts with a digit"), std::string::npos);
  EXPECT_NE(error(std::string(256, 'r')).find("longer than 255"), std::string::npos);
  EXPECT_EQ(error(std::string(255, 'r')), "accepted");
  EXPECT_EQ(error(""), "a node needs a name");
}

}  // namespace
}  // namespace robotperf::rmw
