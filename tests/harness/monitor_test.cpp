// The Monitor around the graph: what it keeps for the functional evaluation; and the Playback's
// warm-up held until the graph delivers.
#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <future>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "black_box.hpp"
#include "robotperf/graph/executor.hpp"
#include "robotperf/harness/dataset.hpp"
#include "robotperf/harness/run.hpp"
#include "robotperf/msgs/geometry_msgs.hpp"
#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/msgs/type_support.hpp"
#include "robotperf/plugin/evaluator.hpp"
#include "test_package.hpp"

namespace robotperf::harness {
namespace {

// A node that reuses its output once released (stereo_depth_nodes.cpp) must get it back even when
// the Monitor keeps that output: over intra, the Monitor keeps a copy.
TEST(Monitor, KeepsACopyOfAnOutputSharedWithTheGraphOverIntra) {
  graph::Context context(rmw::make_transport("intra", {}));
  const BoundaryTopic output{"/out", "sensor_msgs/msg/Image", "", rmw::QoS{}};
  const MessageIds ids{1'000'000'000, 100'000'000, 3};
  Monitor monitor(context, output, ids, 0);
  monitor.keep_outputs({1});
  graph::Executor executor(1);
  executor.add_node(monitor.node());
  graph::Node graph_node(context, "graph");
  auto publisher = graph_node.create_publisher<msgs::Image>("/out");
  executor.start();

  auto published = std::make_shared<msgs::Image>();
  published->header.stamp = msgs::Time::from_ns(ids.stamp_ns(1));
  published->encoding = "mono8";
  published->width = published->height = published->step = 4;
  published->data.assign(16, 7);
  publisher->publish(std::shared_ptr<const msgs::Image>(published));
  ASSERT_TRUE(monitor.wait_for(1, rmw::steady_now_ns() + 10'000'000'000));
  executor.stop();

  const Monitor::Tally tally = monitor.tally();
  ASSERT_EQ(tally.kept.size(), 1u);
  EXPECT_EQ(tally.kept[0].first, 1u);
  const auto* kept = static_cast<const msgs::Image*>(tally.kept[0].second.get());
  EXPECT_NE(kept, published.get());
  EXPECT_EQ(kept->header.stamp.to_ns(), ids.stamp_ns(1));
  EXPECT_EQ(kept->data, published->data);
  EXPECT_EQ(published.use_count(), 1) << "the Monitor still holds the graph's message";
}

// A node's second output (b3's poses) follows its first: the wait for the outputs is not over
// while a kept output's observed truth is still on its way, or the evaluation would find it
// missing.
TEST(Monitor, WaitsForTheObservedTruthOfTheOutputsItKeeps) {
  graph::Context context(rmw::make_transport("intra", {}));
  const BoundaryTopic output{"/out", "sensor_msgs/msg/Image", "", rmw::QoS{}};
  const MessageIds ids{1'000'000'000, 100'000'000, 3};
  Monitor monitor(context, output, ids, 0);
  monitor.keep_outputs({1});
  monitor.keep_observed_truth("/poses", msgs::type_support<msgs::PoseArray>());
  graph::Executor executor(1);
  executor.add_node(monitor.node());
  graph::Node graph_node(context, "graph");
  auto images = graph_node.create_publisher<msgs::Image>("/out");
  auto poses = graph_node.create_publisher<msgs::PoseArray>("/poses");
  executor.start();

  auto image = std::make_shared<msgs::Image>();
  image->header.stamp = msgs::Time::from_ns(ids.stamp_ns(1));
  images->publish(std::shared_ptr<const msgs::Image>(image));
  EXPECT_FALSE(monitor.wait_for(1, rmw::steady_now_ns() + 200'000'000))
      << "the output's poses have not been published";
  auto pose = std::make_shared<msgs::PoseArray>();
  pose->header.stamp = msgs::Time::from_ns(ids.stamp_ns(1));
  pose->poses.resize(2);
  poses->publish(std::shared_ptr<const msgs::PoseArray>(pose));
  EXPECT_TRUE(monitor.wait_for(1, rmw::steady_now_ns() + 10'000'000'000));
  executor.stop();

  const Monitor::Tally tally = monitor.tally();
  ASSERT_EQ(tally.observed_truth.count(1), 1u);
  EXPECT_EQ(static_cast<const msgs::PoseArray*>(tally.observed_truth.at(1).get())->poses.size(),
            2u);
}

// An evaluator that records what it was given.
class RecordingEvaluator final : public plugin::FunctionalEvaluator {
 public:
  void add(const void* output, std::size_t frame) override {
    frames.push_back(frame);
    bytes.push_back(static_cast<const msgs::Image*>(output)->data.at(0));
  }
  std::map<std::string, double> metrics() const override { return {}; }
  std::vector<std::size_t> frames;
  std::vector<uint8_t> bytes;
};

// Checked on arrival: each chosen output once, as its frame, and nothing held.
TEST(Monitor, GivesChosenOutputsToAnOnArrivalEvaluatorOnceEach) {
  graph::Context context(rmw::make_transport("intra", {}));
  const BoundaryTopic output{"/out", "sensor_msgs/msg/Image", "", rmw::QoS{}};
  const MessageIds ids{1'000'000'000, 100'000'000, 5};
  Monitor monitor(context, output, ids, 1);
  monitor.keep_outputs({1, 2, 4});
  RecordingEvaluator evaluator;
  monitor.evaluate_on_arrival(evaluator, 3);
  graph::Executor executor(1);
  executor.add_node(monitor.node());
  graph::Node graph_node(context, "graph");
  auto publisher = graph_node.create_publisher<msgs::Image>("/out");
  executor.start();
  for (uint64_t id : {0, 1, 2, 2, 3, 4}) {  // 2 twice: a duplicate is not checked again
    auto m = std::make_shared<msgs::Image>();
    m->header.stamp = msgs::Time::from_ns(ids.stamp_ns(id));
    m->data.assign(4, static_cast<uint8_t>(id));
    publisher->publish(std::shared_ptr<const msgs::Image>(m));
  }
  ASSERT_TRUE(monitor.wait_for(4, rmw::steady_now_ns() + 10'000'000'000));
  // Read while the Monitor still runs: an output whose check is under way is waited for.
  const Monitor::Tally tally = monitor.tally();
  executor.stop();
  EXPECT_TRUE(tally.kept.empty());
  EXPECT_EQ(tally.evaluated_on_arrival, 3u);
  EXPECT_EQ(tally.duplicates, 1u);
  EXPECT_EQ(evaluator.frames, (std::vector<std::size_t>{1, 2, 1}));  // id 4 is frame 4 mod 3
  EXPECT_EQ(evaluator.bytes, (std::vector<uint8_t>{1, 2, 4}));
}

// An evaluator (a plug-in's code) that throws on an output.
class ThrowingEvaluator final : public plugin::FunctionalEvaluator {
 public:
  void add(const void*, std::size_t) override { throw std::runtime_error("evaluator bug"); }
  std::map<std::string, double> metrics() const override { return {}; }
};

// An on-arrival check that throws is a failure of the check, said in the tally; the tally, which
// waits for the checks under way, still comes.
TEST(Monitor, AnOnArrivalEvaluatorThatThrowsIsReportedAndTheTallyStillComes) {
  // Held by the thread that waits for the tally: if it never comes, the test fails and the
  // thread keeps what it waits on.
  struct Setup {
    graph::Context context{rmw::make_transport("intra", {})};
    MessageIds ids{1'000'000'000, 100'000'000, 3};
    Monitor monitor{context, BoundaryTopic{"/out", "sensor_msgs/msg/Image", "", rmw::QoS{}}, ids,
                    0};
    ThrowingEvaluator evaluator;
    graph::Executor executor{1};
    graph::Node graph_node{context, "graph"};
  };
  auto setup = std::make_shared<Setup>();
  setup->monitor.keep_outputs({1});
  setup->monitor.evaluate_on_arrival(setup->evaluator, 3);
  setup->executor.add_node(setup->monitor.node());
  auto publisher = setup->graph_node.create_publisher<msgs::Image>("/out");
  setup->executor.start();
  auto m = std::make_shared<msgs::Image>();
  m->header.stamp = msgs::Time::from_ns(setup->ids.stamp_ns(1));
  publisher->publish(std::shared_ptr<const msgs::Image>(m));
  ASSERT_TRUE(setup->monitor.wait_for(1, rmw::steady_now_ns() + 10'000'000'000));

  auto tallied = std::make_shared<std::promise<Monitor::Tally>>();
  std::future<Monitor::Tally> tally = tallied->get_future();
  std::thread([setup, tallied] { tallied->set_value(setup->monitor.tally()); }).detach();
  ASSERT_EQ(tally.wait_for(std::chrono::seconds(20)), std::future_status::ready)
      << "the tally waits for a check that threw";
  const Monitor::Tally t = tally.get();
  EXPECT_EQ(t.received_measured, 1u);
  EXPECT_EQ(t.evaluated_on_arrival, 0u);
  EXPECT_EQ(t.evaluation_error, "evaluator bug");
  EXPECT_FALSE(setup->executor.error()) << "the Monitor's own callback did not fail";
  setup->executor.stop();
}

// The end of the drain: what arrives after it is not counted, however long the run then takes to
// finish (an external power meter's last reading takes seconds).
TEST(Monitor, IgnoresWhatArrivesAfterItWasClosed) {
  graph::Context context(rmw::make_transport("intra", {}));
  const BoundaryTopic output{"/out", "sensor_msgs/msg/Image", "", rmw::QoS{}};
  const MessageIds ids{1'000'000'000, 100'000'000, 3};
  Monitor monitor(context, output, ids, 0);
  graph::Executor executor(1);
  executor.add_node(monitor.node());
  graph::Node graph_node(context, "graph");
  auto publisher = graph_node.create_publisher<msgs::Image>("/out");
  executor.start();
  auto publish = [&](uint64_t id) {
    auto m = std::make_shared<msgs::Image>();
    m->header.stamp = msgs::Time::from_ns(ids.stamp_ns(id));
    publisher->publish(std::shared_ptr<const msgs::Image>(m));
  };
  publish(0);
  ASSERT_TRUE(monitor.wait_for(1, rmw::steady_now_ns() + 10'000'000'000));
  monitor.close();
  publish(1);
  publish(1'000);  // an unknown ID, were it counted
  // Counted, the later message would be there well within this (it is, before the close).
  EXPECT_FALSE(monitor.wait_for(2, rmw::steady_now_ns() + 1'000'000'000));
  executor.stop();
  const Monitor::Tally tally = monitor.tally();
  EXPECT_EQ(tally.received_measured, 1u);
  EXPECT_GE(tally.received_ns[0], 0);
  EXPECT_EQ(tally.received_ns[1], -1);
  EXPECT_EQ(tally.unknown, 0u);
}

// The warm-up is sent again while the gate says the graph does not deliver yet; measured messages
// are sent once, after it, and the records and counts hold each message once.
TEST(Playback, RepeatsTheWarmupUntilTheGraphDelivers) {
  testing::TestPackage package("gate", testing::relay_graph("none"));
  const BenchmarkSpec spec = load_benchmark(package.dir());
  graph::Context context(rmw::make_transport("intra", {}));
  const MessageIds ids{1'000'000'000, 1'000'000, 12};  // 12 messages at 1 kHz
  Playback playback(context, spec, load_dataset(spec.dataset), ids);
  std::mutex mutex;
  std::condition_variable arrived;
  int published = 0;
  auto counter = std::make_shared<graph::Node>(context, "counter");
  auto sub = counter->create_subscription<msgs::Image>(
      "/in",
      rmw::QoS{rmw::History::kKeepAll, 0, rmw::Reliability::kReliable, rmw::Durability::kVolatile},
      [&](std::shared_ptr<const msgs::Image>) {
        std::lock_guard lock(mutex);
        ++published;
        arrived.notify_all();
      });
  graph::Executor executor(1);
  executor.add_node(counter);
  executor.start();

  int checks = 0;
  const Playback::DeliveryGate gate{4, [&] { return ++checks == 3; },
                                    rmw::steady_now_ns() + 10'000'000'000,
                                    [] { return std::string("never reached"); }};
  std::vector<MessageRecord> records;
  std::vector<std::size_t> counted;
  int64_t repeated_ns = 0;
  const std::size_t sent = playback.run(
      records, [] { return false; }, [&](std::size_t n) { counted.push_back(n); }, &gate,
      &repeated_ns);
  EXPECT_EQ(sent, 12u);
  EXPECT_EQ(checks, 3);
  EXPECT_EQ(repeated_ns, 2 * 4'000'000) << "two more passes over the 4 ms warm-up";
  ASSERT_EQ(records.size(), 12u);
  for (std::size_t k = 0; k < records.size(); ++k) EXPECT_EQ(records[k].id, k);
  EXPECT_GE(records[4].scheduled_ns - records[3].scheduled_ns, 8'000'000)
      << "the measured messages follow the repetitions";
  EXPECT_EQ(counted.size(), 12u);
  EXPECT_EQ(counted.back(), 12u);
  {
    // Each of the 12 once, and the 4 warm-up messages twice more.
    std::unique_lock lock(mutex);
    EXPECT_TRUE(arrived.wait_for(lock, std::chrono::seconds(10), [&] { return published >= 20; }));
    EXPECT_EQ(published, 20);
  }
  executor.stop();
}

// In bursts of 4, a warm-up of 5 ends inside the second burst: the gate is still asked before the
// first measured message, which goes out at that burst's deadline after it.
TEST(Playback, AsksTheGateInsideABurst) {
  testing::TestPackage package("gate_burst", testing::relay_graph("none"));
  const BenchmarkSpec spec = load_benchmark(package.dir());
  graph::Context context(rmw::make_transport("intra", {}));
  const MessageIds ids{1'000'000'000, 1'000'000, 12};
  std::vector<int64_t> schedule;
  for (int64_t k = 0; k < 12; ++k) schedule.push_back(k / 4 * 4'000'000);
  Playback playback(context, spec, load_dataset(spec.dataset), ids, false, schedule);
  std::vector<std::size_t> sent_when_asked;
  std::size_t sent = 0;
  const Playback::DeliveryGate gate{5,
                                    [&] {
                                      sent_when_asked.push_back(sent);
                                      return true;
                                    },
                                    rmw::steady_now_ns() + 10'000'000'000,
                                    [] { return std::string("never reached"); }};
  std::vector<MessageRecord> records;
  EXPECT_EQ(playback.run(
                records, [] { return false; }, [&](std::size_t n) { sent = n; }, &gate),
            12u);
  EXPECT_EQ(sent_when_asked, std::vector<std::size_t>{5}) << "asked once, after the warm-up";
  ASSERT_EQ(records.size(), 12u);
  EXPECT_EQ(records[5].scheduled_ns, records[4].scheduled_ns) << "one burst, in two parts";
  EXPECT_EQ(records[7].scheduled_ns, records[5].scheduled_ns);
  EXPECT_EQ(records[8].scheduled_ns - records[5].scheduled_ns, 4'000'000);
}

// A device graph's warm-up, 5 messages a round: its answers so far at the end of each round.
TEST(DeviceWarmup, ReadyOnceTheGraphAnswersAtItsSteadyPace) {
  // Compiling for three rounds, then the backlog and the round's own answers: ready at once.
  {
    DeviceWarmup w(5);
    EXPECT_FALSE(w.ready_after_round(0));
    EXPECT_FALSE(w.ready_after_round(0));
    EXPECT_FALSE(w.ready_after_round(0));
    EXPECT_TRUE(w.ready_after_round(9));
  }
  // A graph that keeps up from the start.
  EXPECT_TRUE(DeviceWarmup(5).ready_after_round(5));
  // Slower than the rate: its answers per round rise while the build ends, then hold (2, 2).
  {
    DeviceWarmup w(5);
    EXPECT_FALSE(w.ready_after_round(0));
    EXPECT_FALSE(w.ready_after_round(1));
    EXPECT_FALSE(w.ready_after_round(3));
    EXPECT_TRUE(w.ready_after_round(5));
  }
  // Answers that still rise from round to round are a backlog being worked off, not a pace.
  {
    DeviceWarmup w(5);
    EXPECT_FALSE(w.ready_after_round(1));
    EXPECT_FALSE(w.ready_after_round(3));
    EXPECT_FALSE(w.ready_after_round(7));
    EXPECT_TRUE(w.ready_after_round(11));
  }
  // A graph that pairs by exact time drops the repeated warm-up (stamps older than its last set):
  // the first round's answers come in over two rounds, rising, then none. Silent after answering,
  // it is idle and warm (on pocl, a3 at 3 Hz waited here for its whole --connect-timeout).
  {
    DeviceWarmup w(5);
    EXPECT_FALSE(w.ready_after_round(0));
    EXPECT_FALSE(w.ready_after_round(2));
    EXPECT_FALSE(w.ready_after_round(5));
    EXPECT_TRUE(w.ready_after_round(5));
  }
}

TEST(Playback, AGraphThatNeverDeliversIsRefusedAtTheDeadline) {
  testing::TestPackage package("gate_never", testing::relay_graph("none"));
  const BenchmarkSpec spec = load_benchmark(package.dir());
  graph::Context context(rmw::make_transport("intra", {}));
  const MessageIds ids{1'000'000'000, 1'000'000, 12};
  Playback playback(context, spec, load_dataset(spec.dataset), ids);
  // The message is asked for at the deadline: it can say what happened by then.
  int rounds = 0;
  const Playback::DeliveryGate gate{
      4, [&] { return ++rounds < 0; }, rmw::steady_now_ns() + 50'000'000,
      [&] { return "no answer in " + std::to_string(rounds) + " rounds"; }};
  std::vector<MessageRecord> records;
  try {
    playback.run(
        records, [] { return false; }, nullptr, &gate);
    ADD_FAILURE() << "a graph that never delivers was not refused";
  } catch (const GraphNotConnected& e) {
    EXPECT_GE(rounds, 2) << "50 ms of 4 ms warm-ups";
    EXPECT_EQ(std::string(e.what()), "no answer in " + std::to_string(rounds) + " rounds");
  }
}

}  // namespace
}  // namespace robotperf::harness
