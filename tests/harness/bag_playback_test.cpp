// Replaying rosbag2 bags: any-type playback with IDs written into the header bytes.
#include <gtest/gtest.h>

#include <filesystem>
#include <set>

#include "../fixture_root.hpp"
#include "../sanitized_build.hpp"
#include "black_box.hpp"
#include "robotperf/bag/bag.hpp"
#include "robotperf/harness/dataset.hpp"
#include "robotperf/harness/run.hpp"
#include "robotperf/msgs/definitions.hpp"
#include "robotperf/msgs/serialized_message.hpp"
#include "robotperf/rmw/transport.hpp"
#include "test_package.hpp"

namespace robotperf::harness {
namespace {

namespace fs = std::filesystem;

using robotperf::testing::FixtureRoot;

bag::TopicInfo topic_info(const std::string& name, const std::string& type) {
  bag::TopicInfo t;
  t.name = name;
  t.type = type;
  t.definition_encoding = "ros2msg";
  t.definition = msgs::ros2msg_schema(type).value_or("");
  return t;
}

// perception/image as a bag, like `dataset generate` writes it, with the
// topics renamed by `rename` and frame k recorded at `time_of(k)`.
// Frames in `corrupt_images` get an image whose payload is cut in half (its header still reads).
// Frame k is recorded `record_delay_of(k)` after its stamp.
void write_camera_bag(const fs::path& dir, bag::Storage storage,
                      const std::map<std::string, std::string>& rename = {},
                      const std::function<int64_t(std::size_t)>& time_of = {},
                      const std::set<std::size_t>& corrupt_images = {},
                      const std::function<int64_t(std::size_t)>& record_delay_of = {}) {
  const Dataset d = load_dataset("perception/image");
  bag::WriteOptions w;
  w.storage = storage;
  bag::Writer writer(dir, w);
  std::vector<std::size_t> ids;
  for (const auto& s : d.streams) {
    auto it = rename.find(s.topic);
    ids.push_back(
        writer.add_topic(topic_info(it == rename.end() ? s.topic : it->second, s.type->ros_type)));
  }
  std::vector<uint8_t> buffer;
  for (std::size_t k = 0; k < d.frames; ++k) {
    const int64_t t = time_of ? time_of(k) : 1'700'000'000'000'000'000 + int64_t(k) * 33'333'333;
    // The camera_info is recorded slightly later than its image, as on a robot.
    for (std::size_t i = 0; i < d.streams.size(); ++i) {
      const auto& s = d.streams[i];
      auto msg = s.type->copy_with_stamp_ns(s.messages[k].get(), t);
      buffer.resize(s.type->serialized_size(msg.get()));
      s.type->serialize(msg.get(), buffer);
      if (s.type->ros_type == "sensor_msgs/msg/Image" && corrupt_images.contains(k))
        buffer.resize(buffer.size() / 2);
      const int64_t delay = record_delay_of ? record_delay_of(k) : 0;
      writer.write(ids[i], t + delay + int64_t(i) * 100'000, buffer);
    }
  }
  writer.close();
}

BenchmarkSpec a1() {
  return find_benchmark(fs::path(ROBOTPERF_SOURCE_DIR) / "benchmarks", "a1");
}

void expect_all_matched(const RunResult& r, std::size_t count) {
  EXPECT_EQ(r.sent, count);
  EXPECT_EQ(r.matched, r.measured);
  EXPECT_EQ(r.lost, 0u);
  EXPECT_EQ(r.duplicates, 0u);
  EXPECT_EQ(r.unknown, 0u);
  std::set<uint64_t> ids;
  for (const auto& rec : r.records) {
    EXPECT_TRUE(ids.insert(rec.id).second) << "id " << rec.id << " sent twice";
    EXPECT_GE(rec.received_ns, rec.sent_ns) << "id " << rec.id;
  }
}

RunOptions bag_run(const fs::path& bag, const std::string& rmw, std::size_t count) {
  RunOptions o;
  o.load.bag = BagSelection{bag, {}, {}, {}};
  o.transport.rmw = rmw;
  o.load.count = count;
  o.load.warmup = 0;
  o.load.rate_hz = test_rate(30, 10);
  o.load.drain_s = 5;
  return o;
}

TEST(SerializedMessage, StampIsReadAndWrittenInPlace) {
  std::vector<uint8_t> le{0, 1, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0, 0xAA};
  EXPECT_EQ(msgs::read_header_stamp_ns(le), 1'000'000'002);
  msgs::write_header_stamp_ns(le, 5'000'000'007);
  EXPECT_EQ(le, (std::vector<uint8_t>{0, 1, 0, 0, 5, 0, 0, 0, 7, 0, 0, 0, 0xAA}));
  std::vector<uint8_t> be{0, 0, 0, 0, 0, 0, 0, 3, 0, 0, 0, 4};
  EXPECT_EQ(msgs::read_header_stamp_ns(be), 3'000'000'004);
  EXPECT_THROW(msgs::read_header_stamp_ns(std::vector<uint8_t>{0, 1, 0, 0, 1}), msgs::CdrError);
  const auto& ts = msgs::serialized_type_support("sensor_msgs/msg/Image");
  EXPECT_EQ(ts.dds_type, "sensor_msgs::msg::dds_::Image_");
  EXPECT_TRUE(msgs::is_serialized_type_support(ts));
  EXPECT_EQ(&ts, &msgs::serialized_type_support("sensor_msgs/msg/Image"));
}

TEST(BagPlayback, LoaderGroupsImageAndCameraInfoIntoFrames) {
  FixtureRoot tmp;
  write_camera_bag(tmp.path() / "bag", bag::Storage::kMcap);
  const Dataset d = load_bag_dataset({tmp.path() / "bag", {}, {}, {}}, a1().inputs);
  EXPECT_EQ(d.frames, 68u);
  ASSERT_EQ(d.streams.size(), 2u);
  EXPECT_EQ(d.streams[0].name, "camera_info");
  EXPECT_EQ(d.frame_times_ns.size(), 68u);
  EXPECT_NEAR(d.rate_hz, 30.0, 0.01);
  for (std::size_t k = 0; k < d.frames; ++k) {
    auto stamp = [&](std::size_t s) {
      return msgs::read_header_stamp_ns(
          static_cast<const msgs::SerializedMessage*>(d.streams[s].messages[k].get())->cdr);
    };
    EXPECT_EQ(stamp(0), stamp(1)) << "frame " << k;
  }
  // A window of the first second: frames at 0 .. 0.99 s.
  const Dataset w = load_bag_dataset({tmp.path() / "bag", {}, 0.0, 0.99}, a1().inputs);
  EXPECT_EQ(w.frames, 30u);
}

TEST(BagPlayback, DatasetHashCoversTheRecordedTimeline) {
  FixtureRoot tmp;
  write_camera_bag(tmp.path() / "even", bag::Storage::kSqlite3);
  write_camera_bag(tmp.path() / "even-again", bag::Storage::kSqlite3);
  // The same messages, the second half recorded 50 ms late: --rate bag replays another workload.
  write_camera_bag(tmp.path() / "late", bag::Storage::kSqlite3, {}, {}, {},
                   [](std::size_t k) { return k >= 34 ? 50'000'000 : 0; });
  const auto hash = [&](const char* name) {
    return load_bag_dataset({tmp.path() / name, {}, {}, {}}, a1().inputs).hash;
  };
  EXPECT_EQ(hash("even"), hash("even-again"));
  EXPECT_NE(hash("even"), hash("late"));
}

TEST(BagPlayback, A1OnIntraLoopsWithUniqueIdsAndNoLoss) {
  FixtureRoot tmp;
  write_camera_bag(tmp.path() / "bag", bag::Storage::kSqlite3);
  const RunResult r = run_benchmark(a1(), bag_run(tmp.path() / "bag", "intra", 80));
  expect_all_matched(r, 80);  // 80 > 68 frames: the bag loops
  EXPECT_EQ(r.dataset_frames, 68u);
  EXPECT_TRUE(r.dataset_hash.starts_with("fnv1a64:"));
}

TEST(BagPlayback, A1OnFastddsPublishesRecordedBytesWithRemapping) {
  FixtureRoot tmp;
  write_camera_bag(tmp.path() / "bag", bag::Storage::kMcap,
                   {{"/camera/image_raw", "/front/image"}, {"/camera/camera_info", "/front/info"}});
  RunOptions o = bag_run(tmp.path() / "bag", "fastdds", 80);
  // A busy 2-core machine does not rectify and upscale 30 frames a second through Fast DDS in
  // every build: frames would queue and drop, which is not what this test is about.
  o.load.rate_hz = test_rate(15, 5);
  o.transport.domain_id = rmw::reserved_domain();
  // Without remapping, the bag has nothing for a1's inputs.
  try {
    run_benchmark(a1(), o);
    ADD_FAILURE() << "a bag without a1's topics was accepted";
  } catch (const BenchmarkError& e) {
    EXPECT_NE(std::string(e.what()).find("--remap"), std::string::npos) << e.what();
  }
  o.load.bag->remaps = {{"/front/image", "/camera/image_raw"},
                        {"/front/info", "/camera/camera_info"}};
  const RunResult r = run_benchmark(a1(), o);
  expect_all_matched(r, 80);
}

// A corrupt message in a bag is found when the bag is loaded and left out, with a warning: it is
// never sent, so the graph is never blamed for dropping it.
TEST(BagPlayback, CorruptMessagesAreReportedNotCountedAsLost) {
  FixtureRoot tmp;
  write_camera_bag(tmp.path() / "bag", bag::Storage::kMcap, {}, {}, {5, 17});
  const RunResult r = run_benchmark(a1(), bag_run(tmp.path() / "bag", "intra", 40));
  expect_all_matched(r, 40);
  EXPECT_EQ(r.dataset_frames, 66u);  // 68 frames, two without a usable image
  std::string warnings;
  for (const auto& w : r.warnings) {
    if (w.rule == "corrupt_messages") warnings += w.message + "\n";
  }
  EXPECT_NE(warnings.find("2 messages on /camera/image_raw do not decode as sensor_msgs/msg/Image"),
            std::string::npos)
      << warnings;
  EXPECT_NE(warnings.find("neither sent nor counted as lost"), std::string::npos) << warnings;
}

TEST(BagPlayback, TypesWithoutHeaderAreRefused) {
  FixtureRoot tmp;
  {
    bag::Writer writer(tmp.path() / "bag", {});
    const auto t = writer.add_topic(topic_info("/in", "std_msgs/msg/String"));
    const std::vector<uint8_t> hello{0, 1, 0, 0, 6, 0, 0, 0, 'h', 'e', 'l', 'l', 'o', 0};
    writer.write(t, 1, hello);
    writer.close();
  }
  testing::TestPackage p("unstamped", testing::relay_graph("none"));
  RunOptions o = bag_run(tmp.path() / "bag", "intra", 10);
  try {
    run_benchmark(load_benchmark(p.dir()), o);
    ADD_FAILURE() << "std_msgs/String was accepted as a playback input";
  } catch (const BenchmarkError& e) {
    EXPECT_NE(std::string(e.what()).find("std_msgs/Header"), std::string::npos) << e.what();
  }
}

TEST(BagPlayback, TimelineScheduleFollowsRecordedIntervalsAndLoops) {
  const std::vector<int64_t> times{1000, 1000 + 10'000'000, 1000 + 40'000'000};
  const auto s = timeline_schedule(times, 2.0, 7);
  // Recorded offsets 0, 10, 40 ms; one loop = 40 + 20 (mean interval) ms; halved by scale 2.
  EXPECT_EQ(s, (std::vector<int64_t>{0, 5'000'000, 20'000'000, 30'000'000, 35'000'000, 50'000'000,
                                     60'000'000}));
  EXPECT_THROW(timeline_schedule({5}, 1.0, 3), BenchmarkError);
}

TEST(BagPlayback, BagTimelinePacesSendsLikeTheRecording) {
  FixtureRoot tmp;
  // Intervals of 10, 20, 30, ... ms: clearly not a fixed rate.
  const auto time_of = [](std::size_t k) {
    return 1'700'000'000'000'000'000 + int64_t(k * (k + 1) / 2) * 10'000'000;
  };
  write_camera_bag(tmp.path() / "bag", bag::Storage::kMcap, {{"/camera/image_raw", "/in"}},
                   time_of);
  testing::TestPackage p("timeline", testing::relay_graph("none"));
  RunOptions o = bag_run(tmp.path() / "bag", "intra", 12);
  o.load.rate_hz.reset();
  o.load.bag_timeline = true;
  o.load.rate_scale = 2.0;
  const RunResult r = run_benchmark(load_benchmark(p.dir()), o);
  expect_all_matched(r, 12);
  ASSERT_EQ(r.records.size(), 12u);
  for (std::size_t k = 1; k < r.records.size(); ++k) {
    const int64_t planned = (time_of(k) - time_of(0)) / 2;
    EXPECT_EQ(r.records[k].scheduled_ns - r.records[0].scheduled_ns, planned);
    // Sends keep to the plan within a generous bound for a busy machine.
    EXPECT_NEAR(double(r.records[k].sent_ns - r.records[0].sent_ns), double(planned), 20e6);
  }
}

}  // namespace
}  // namespace robotperf::harness
