// Path search and path latency (docs/design.md §3.13) on a simulated graph whose every hop the
// test knows: a restamping node, a fan-out, a two-input synchroniser, a node that drops frames
// and a timer-driven node. The same events are given directly and as a hand-built CTF trace.
#include "robotperf/tracing/paths.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <map>

#include "../fixture_root.hpp"
#include "ctf_writer.hpp"
#include "robotperf/tracing/analysis.hpp"

namespace robotperf::tracing {
namespace {

using testing::CtfWriter;
using V = testing::FieldValue;
using K = PathEvent::Kind;

constexpr int32_t kPid = 77;
constexpr int64_t kStart = 1'000'000;
constexpr int64_t kFrame = 10'000'000;  // the camera's period
constexpr int64_t kTimer = 5'000'000;   // the controller's timer
constexpr int kFrames = 20;
bool dropped(int f) {
  return f % 5 == 4;  // the detector publishes nothing for these
}

// One simulated event: the nodes run on threads of their own (vtid = node number + 1).
struct SimEvent {
  int64_t ts;
  K kind;
  int node;
  std::string topic;  // publish and take
  int64_t stamp = 0;
};

// camera (timer) -> /cam -> rectify (restamps) -> /rect -> detector -> /det -> sync (/rect + /det)
// -> /fused -> controller (timer, 2x the camera's rate) -> /cmd -> actuator; /rect also goes to
// a viewer (fan-out).
const std::vector<std::string> kNodes = {"camera",     "rectify",  "detector", "sync",
                                         "controller", "actuator", "viewer"};
enum { kCamera, kRectify, kDetector, kSync, kController, kActuator, kViewer };

std::vector<SimEvent> simulate() {
  std::vector<SimEvent> ev;
  auto callback = [&](int node, int64_t start, int64_t end, std::vector<SimEvent> inside) {
    ev.push_back({start, K::kCallbackStart, node, "", 0});
    for (auto& e : inside) ev.push_back(std::move(e));
    ev.push_back({end, K::kCallbackEnd, node, "", 0});
  };
  for (int f = 0; f < kFrames; ++f) {
    const int64_t t0 = kStart + f * kFrame;
    const int64_t cam = t0, rect = 7'000'000'000'000 + f, det = 8'000'000'000'000 + f,
                  fused = 9'000'000'000'000 + f;
    callback(kCamera, t0 - 10, t0 + 10, {{t0, K::kPublish, kCamera, "/cam", cam}});
    ev.push_back({t0 + 100, K::kTake, kRectify, "/cam", cam});
    callback(kRectify, t0 + 110, t0 + 600, {{t0 + 500, K::kPublish, kRectify, "/rect", rect}});
    ev.push_back({t0 + 650, K::kTake, kViewer, "/rect", rect});
    callback(kViewer, t0 + 660, t0 + 900, {});
    ev.push_back({t0 + 700, K::kTake, kDetector, "/rect", rect});
    callback(kDetector, t0 + 710, t0 + 3050,
             dropped(f) ? std::vector<SimEvent>{}
                        : std::vector<SimEvent>{{t0 + 3000, K::kPublish, kDetector, "/det", det}});
    ev.push_back({t0 + 800, K::kTake, kSync, "/rect", rect});
    callback(kSync, t0 + 810, t0 + 850, {});
    if (!dropped(f)) {
      ev.push_back({t0 + 3100, K::kTake, kSync, "/det", det});
      callback(kSync, t0 + 3110, t0 + 3350, {{t0 + 3300, K::kPublish, kSync, "/fused", fused}});
      ev.push_back({t0 + 3400, K::kTake, kController, "/fused", fused});
      callback(kController, t0 + 3410, t0 + 3420, {});
    }
  }
  // A first tick before the controller took anything: an output with no input.
  callback(kController, kStart + 1000, kStart + 1100,
           {{kStart + 1050, K::kPublish, kController, "/cmd", 9'999'999'999'999}});
  for (int j = 0; j < 2 * kFrames; ++j) {
    const int64_t t = kStart + j * kTimer + 4000;
    const int64_t cmd = 10'000'000'000'000 + j;
    callback(kController, t, t + 100, {{t + 50, K::kPublish, kController, "/cmd", cmd}});
    ev.push_back({t + 250, K::kTake, kActuator, "/cmd", cmd});
    callback(kActuator, t + 260, t + 300, {});
  }
  std::sort(ev.begin(), ev.end(), [](const SimEvent& a, const SimEvent& b) { return a.ts < b.ts; });
  return ev;
}

PathEvents events_for(const std::vector<std::string>& path) {
  PathEvents pe;
  pe.topics = path;
  pe.nodes = kNodes;
  for (const SimEvent& e : simulate()) {
    PathEvent p{e.ts, e.stamp, kPid, e.node + 1, static_cast<uint32_t>(e.node), 0, e.kind};
    if (e.kind == K::kPublish || e.kind == K::kTake) {
      auto it = std::find(path.begin(), path.end(), e.topic);
      if (it == path.end()) continue;
      p.topic = static_cast<uint32_t>(it - path.begin());
    }
    pe.events.push_back(p);
  }
  return pe;
}

int dropped_frames() {
  int n = 0;
  for (int f = 0; f < kFrames; ++f) n += dropped(f) ? 1 : 0;
  return n;
}

// The whole chain: every hop's time is the simulation's, and the timer's second output for a
// frame (and its outputs after a dropped frame) are not counted again.
void expect_full_chain(const PathLatency& p) {
  const auto reached = static_cast<uint64_t>(kFrames - dropped_frames());
  EXPECT_EQ(p.sources, static_cast<uint64_t>(kFrames));
  EXPECT_EQ(p.reached, reached);
  EXPECT_TRUE(p.ends_at_take);
  ASSERT_EQ(p.stopped_at.size(), 5u);
  EXPECT_EQ(p.stopped_at[1], static_cast<uint64_t>(dropped_frames()));  // at /rect: the detector
  EXPECT_EQ(p.end_to_end.count, reached);
  // First /cmd after the controller took /fused (t0 + 3400): the timer at t0 + 4050, taken 200 ns
  // later.
  EXPECT_DOUBLE_EQ(p.end_to_end.min, 4250.0);
  EXPECT_DOUBLE_EQ(p.end_to_end.max, 4250.0);
  ASSERT_EQ(p.hops.size(), 4u);
  const double transport[] = {100, 200, 100, 100};
  const double in_node[] = {400, 2300, 200, 650};
  const char* nodes[] = {"rectify", "detector", "sync", "controller"};
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_DOUBLE_EQ(p.hops[i].transport.p50, transport[i]) << i;
    EXPECT_DOUBLE_EQ(p.hops[i].in_node.p50, in_node[i]) << i;
    EXPECT_EQ(p.hops[i].node, nodes[i]);
  }
  // Restamping does not matter: each link is by callback.
  EXPECT_EQ(p.hops[0].by_callback, static_cast<uint64_t>(kFrames));
  EXPECT_EQ(p.hops[1].by_callback, reached);
  EXPECT_EQ(p.hops[1].unused, static_cast<uint64_t>(dropped_frames()));
  EXPECT_EQ(p.hops[2].by_callback, reached);
  // The timer's outputs are linked to the latest input, two (or four, after a dropped frame) to
  // each; the first tick comes before any input.
  const PathHop& timer = p.hops[3];
  EXPECT_EQ(timer.outputs, static_cast<uint64_t>(2 * kFrames + 1));
  EXPECT_EQ(timer.by_callback, 0u);
  EXPECT_EQ(timer.unlinked, 1u);
  EXPECT_EQ(timer.by_latest, static_cast<uint64_t>(2 * kFrames));
  EXPECT_EQ(timer.unused, 0u);
  EXPECT_EQ(timer.reused, reached);
}

TEST(PathLatency, ChainOfARestampingDroppingSynchronisingAndTimerDrivenGraph) {
  expect_full_chain(path_latency(events_for({"/cam", "/rect", "/det", "/fused", "/cmd"})));
}

// Past the synchroniser's other input: /fused is published in /det's callback, so its /rect
// input is the latest the synchroniser took.
TEST(PathLatency, ASynchronisersOtherInputIsItsLatest) {
  const PathLatency p = path_latency(events_for({"/cam", "/rect", "/fused"}));
  const auto reached = static_cast<uint64_t>(kFrames - dropped_frames());
  EXPECT_EQ(p.reached, reached);
  EXPECT_DOUBLE_EQ(p.end_to_end.min, 3400.0);  // to the controller's take of /fused
  EXPECT_DOUBLE_EQ(p.end_to_end.max, 3400.0);
  EXPECT_EQ(p.hops[1].by_callback, 0u);
  EXPECT_EQ(p.hops[1].by_latest, reached);
  EXPECT_DOUBLE_EQ(p.hops[1].transport.p50, 300.0);
  EXPECT_EQ(p.hops[1].unused, static_cast<uint64_t>(dropped_frames()));
  EXPECT_EQ(p.stopped_at[1], static_cast<uint64_t>(dropped_frames()));
}

TEST(PathLatency, MessagesBeforeTheStartAreNotMeasured) {
  PathEvents pe = events_for({"/cam", "/rect", "/det"});
  pe.since = kStart + 5 * kFrame;  // frames 5.. measured
  const PathLatency p = path_latency(pe);
  EXPECT_EQ(p.sources, static_cast<uint64_t>(kFrames - 5));
  int reached = 0;
  for (int f = 5; f < kFrames; ++f) reached += dropped(f) ? 0 : 1;
  EXPECT_EQ(p.reached, static_cast<uint64_t>(reached));
  EXPECT_DOUBLE_EQ(p.end_to_end.p50, 3100.0);  // /det taken by the synchroniser
}

// The same graph as a CTF trace, read by analyze_trace: endpoints from the init events, threads
// from the event context.
TEST(PathLatency, FromATraceOfTheGraph) {
  robotperf::testing::FixtureRoot dir;
  CtfWriter w(dir.path(), CtfWriter::Header::kCompact, false, static_cast<int>(kNodes.size()));
  testing::define_robotperf_events(w);
  // Handles: node n: 0x100 + n; its publisher of a topic and subscription: per (node, topic).
  std::map<std::pair<int, std::string>, uint64_t> pub_handle, sub_handle;
  uint64_t next = 0x1000;
  const std::vector<std::pair<int, std::string>> pubs = {{kCamera, "/cam"},
                                                         {kRectify, "/rect"},
                                                         {kDetector, "/det"},
                                                         {kSync, "/fused"},
                                                         {kController, "/cmd"}};
  const std::vector<std::pair<int, std::string>> subs = {
      {kRectify, "/cam"},      {kDetector, "/rect"}, {kSync, "/rect"},  {kSync, "/det"},
      {kController, "/fused"}, {kActuator, "/cmd"},  {kViewer, "/rect"}};
  uint64_t ts = 10;
  for (std::size_t n = 0; n < kNodes.size(); ++n) {
    w.event(0, "ros2:rcl_node_init", ts++, kPid, 1,
            {V(uint64_t{0x100 + n}), V(uint64_t{0}), V(kNodes[n]), V(std::string("/"))});
    // Every node has a /rosout publisher, which must stay out of the graph.
    w.event(
        0, "ros2:rcl_publisher_init", ts++, kPid, 1,
        {V(next++), V(uint64_t{0x100 + n}), V(next++), V(std::string("/rosout")), V(uint64_t{10})});
  }
  for (const auto& [node, topic] : pubs) {
    pub_handle[{node, topic}] = next + 1;
    w.event(0, "ros2:rcl_publisher_init", ts++, kPid, 1,
            {V(next), V(uint64_t{0x100u + static_cast<unsigned>(node)}), V(next + 1), V(topic),
             V(uint64_t{10})});
    next += 2;
  }
  for (const auto& [node, topic] : subs) {
    sub_handle[{node, topic}] = next + 1;
    w.event(0, "ros2:rcl_subscription_init", ts++, kPid, 1,
            {V(next), V(uint64_t{0x100u + static_cast<unsigned>(node)}), V(next + 1), V(topic),
             V(uint64_t{10})});
    next += 2;
  }
  for (const SimEvent& e : simulate()) {
    const int stream = e.node;
    const int32_t vtid = e.node + 1;
    const auto at = static_cast<uint64_t>(e.ts);
    switch (e.kind) {
      case K::kPublish:
        w.event(stream, "ros2:rmw_publish", at, kPid, vtid,
                {V(pub_handle.at({e.node, e.topic})), V(uint64_t{0}), V(e.stamp)});
        break;
      case K::kTake:
        w.event(stream, "ros2:rmw_take", at, kPid, vtid,
                {V(sub_handle.at({e.node, e.topic})), V(uint64_t{0}), V(e.stamp), V(int64_t{1})});
        break;
      case K::kCallbackStart:
        w.event(stream, "ros2:callback_start", at, kPid, vtid,
                {V(uint64_t{0x9000u + static_cast<unsigned>(e.node)}), V(int64_t{0})});
        break;
      case K::kCallbackEnd:
        w.event(stream, "ros2:callback_end", at, kPid, vtid,
                {V(uint64_t{0x9000u + static_cast<unsigned>(e.node)})});
        break;
    }
  }
  w.finish();

  AnalyzeOptions options;
  options.path = {"/cam", "/rect", "/det", "/fused", "/cmd"};
  const TraceAnalysis a = analyze_trace(dir.path(), options);
  ASSERT_TRUE(a.path.has_value());
  expect_full_chain(*a.path);
  EXPECT_EQ(to_json(a)["path"]["reached"], a.path->reached);
  EXPECT_NE(breakdown_table(a).find("path /cam -> /rect -> /det -> /fused -> /cmd"),
            std::string::npos)
      << breakdown_table(a);

  // The graph and its paths: from the camera to the actuator, and to the viewer (fan-out).
  ASSERT_EQ(a.graph.find("/rosout"), nullptr);
  const PathSearch search = find_paths(a.graph);
  EXPECT_TRUE(search.stopped.empty());
  std::vector<std::string> texts;
  for (const auto& p : search.paths) texts.push_back(p.text());
  EXPECT_EQ(texts, (std::vector<std::string>{
                       "/cam -> [rectify] -> /rect -> [detector] -> /det -> [sync] -> /fused -> "
                       "[controller] -> /cmd",
                       "/cam -> [rectify] -> /rect -> [sync] -> /fused -> [controller] -> /cmd"}));

  // A path the graph does not have: one line naming the missing link.
  options.path = {"/cam", "/det"};
  try {
    analyze_trace(dir.path(), options);
    FAIL() << "a path with no node between two of its topics was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(),
                 "no node in the trace subscribes /cam and publishes /det (robotperf trace paths "
                 "lists the trace's paths)");
  }
}

// 200 nodes in 20 layers of 10, each subscribing to every topic of the layer before: 10^20
// paths. The search stops at its bound, quickly.
TEST(PathSearch, EndsWithinItsBoundOnALargeGraph) {
  TracedGraph g;
  constexpr int kLayers = 20, kWidth = 10;
  auto topic = [](int layer, int i) {
    return "/l" + std::to_string(100 + layer) + "_" + std::to_string(i);
  };
  auto node = [](int layer, int i) {
    return "n" + std::to_string(100 + layer) + "_" + std::to_string(i);
  };
  for (int l = 0; l <= kLayers; ++l) {
    for (int i = 0; i < kWidth; ++i) {
      TracedGraph::Topic t{topic(l, i), {}, {}};
      t.publishers.push_back(l == 0 ? "source" : node(l, i));
      if (l < kLayers) {
        for (int j = 0; j < kWidth; ++j) t.subscribers.push_back(node(l + 1, j));
        std::sort(t.subscribers.begin(), t.subscribers.end());
      }
      g.topics.push_back(std::move(t));
    }
  }
  std::sort(g.topics.begin(), g.topics.end(),
            [](const auto& a, const auto& b) { return a.name < b.name; });
  const auto t0 = std::chrono::steady_clock::now();
  const PathSearch s = find_paths(g);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_EQ(s.paths.size(), 1000u);
  EXPECT_EQ(s.stopped, "stopped at 1000 paths");
  EXPECT_LT(seconds, 5.0);  // 10^6 steps at most; milliseconds on any machine
  ASSERT_FALSE(s.paths.empty());
  EXPECT_EQ(s.paths[0].topics.size(), static_cast<std::size_t>(kLayers + 1));

  // With the path count out of the way, the step bound ends it.
  const PathSearch by_steps =
      find_paths(g, {.max_paths = SIZE_MAX, .max_topics = 32, .max_steps = 100'000});
  EXPECT_EQ(by_steps.steps, 100'000u);
  EXPECT_EQ(by_steps.stopped, "stopped after 100000 search steps");
}

TEST(PathSearch, ACycleEndsThePathWithoutLooping) {
  TracedGraph g;
  g.topics = {{"/a", {"src"}, {"n1"}}, {"/b", {"n1", "n2"}, {"n2"}}, {"/c", {"n2"}, {}}};
  // n2 subscribes /b and publishes /b and /c: the self-loop on /b is no edge.
  const PathSearch s = find_paths(g);
  ASSERT_EQ(s.paths.size(), 1u);
  EXPECT_EQ(s.paths[0].text(), "/a -> [n1] -> /b -> [n2] -> /c");
}

}  // namespace
}  // namespace robotperf::tracing
