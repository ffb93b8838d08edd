// The harness against graphs whose behaviour is known exactly.
#include <gtest/gtest.h>

#include <atomic>
#include <csignal>
#include <functional>
#include <limits>
#include <set>
#include <vector>

#include "../fixture_root.hpp"
#include "robotperf/harness/run.hpp"
#include "robotperf/rmw/transport.hpp"
#include "test_package.hpp"

namespace robotperf::harness {
namespace {

using testing::relay_graph;
using testing::TestPackage;

constexpr double kMs = 1e6;

RunResult run_package(const std::string& name, const std::string& graph, RunOptions options) {
  TestPackage p(name, graph);
  return run_benchmark(load_benchmark(p.dir()), options);
}

RunOptions with_count(std::size_t n, double rate_hz) {
  RunOptions o;
  o.load.count = n;
  o.load.rate_hz = rate_hz;
  return o;
}

void expect_sane(const RunResult& r) {
  EXPECT_LE(r.lost, r.measured);
  EXPECT_GE(r.loss_percent, 0.0);
  EXPECT_LE(r.loss_percent, 100.0);
  EXPECT_EQ(r.lost + r.matched, r.measured);
  for (const auto& rec : r.records) {
    if (rec.received_ns < 0) continue;
    EXPECT_GE(rec.received_ns, rec.sent_ns) << "negative latency for id " << rec.id;
    EXPECT_GE(rec.sent_ns, rec.scheduled_ns) << "sent before its deadline, id " << rec.id;
  }
}

TEST(BlackBox, NullGraphMatchesEverythingWithSmallOverhead) {
  const RunResult r = run_package("null", relay_graph("none"), with_count(60, 100));
  expect_sane(r);
  EXPECT_EQ(r.sent, 60u);
  EXPECT_EQ(r.matched, 60u);
  EXPECT_EQ(r.lost, 0u);
  EXPECT_EQ(r.duplicates, 0u);
  EXPECT_EQ(r.unknown, 0u);
  EXPECT_TRUE(r.valid) << (r.invalid_reasons.empty() ? "" : r.invalid_reasons[0]);
  EXPECT_GE(r.latency_from_sent.min, 0.0);
  // In-process delivery of a shared pointer: microseconds; 20 ms allows for a
  // heavily loaded CI machine and still catches a broken wake-up path.
  EXPECT_LT(r.latency_from_sent.p50, 20 * kMs);
  EXPECT_LE(r.latency_from_sent.p50, r.latency_from_scheduled.p50);
}

TEST(BlackBox, KnownDelayIsMeasured) {
  // 20 ms of work per message at 20 Hz: never queued, so latency ≈ 20 ms.
  const RunResult r = run_package("delay", relay_graph("delay_ms: 20"), with_count(30, 20));
  expect_sane(r);
  ASSERT_EQ(r.matched, 30u);
  EXPECT_GE(r.latency_from_sent.min, 20 * kMs);
  EXPECT_LT(r.latency_from_sent.p50, 20 * kMs + 15 * kMs);
  EXPECT_GE(r.latency_from_scheduled.min, r.latency_from_sent.min);
}

TEST(BlackBox, DroppingEveryFourthMessageIsCountedExactly) {
  const RunResult r = run_package("drop", relay_graph("drop_every: 4"), with_count(40, 200));
  expect_sane(r);
  EXPECT_EQ(r.measured, 40u);
  EXPECT_EQ(r.lost, 10u);
  EXPECT_DOUBLE_EQ(r.loss_percent, 25.0);
  for (const auto& rec : r.records) {
    // The relay drops its 4th, 8th, ... message: ids 3, 7, 11, ...
    EXPECT_EQ(rec.received_ns < 0, (rec.id + 1) % 4 == 0) << "id " << rec.id;
  }
  EXPECT_FALSE(r.valid);
  ASSERT_FALSE(r.invalid_reasons.empty());
  EXPECT_NE(r.invalid_reasons[0].find("25.00 % lost"), std::string::npos);
  // Two runs that did different work must not look alike: the node says what it computed with.
  ASSERT_EQ(r.nodes.size(), 1u);
  EXPECT_EQ(r.nodes[0].origin, "built-in util");
  EXPECT_EQ(r.nodes[0].parameters,
            (std::map<std::string, std::string>{{"type", "sensor_msgs/msg/Image"},
                                                {"delay_ms", "0"},
                                                {"drop_every", "4"},
                                                {"fail_after", "0"},
                                                {"restamp", "false"}}));
}

TEST(BlackBox, WarmupIsExcludedAndIdsStayUniqueWhenTheDatasetLoops) {
  RunOptions o = with_count(150, 300);  // the dataset has 68 frames: it loops twice
  o.load.warmup = 10;
  const RunResult r = run_package("loop", relay_graph(""), o);
  expect_sane(r);
  EXPECT_EQ(r.sent, 150u);
  EXPECT_EQ(r.measured, 140u);
  EXPECT_EQ(r.matched, 140u);
  EXPECT_EQ(r.duplicates, 0u);
  EXPECT_EQ(r.unknown, 0u);
  EXPECT_EQ(r.latency_from_sent.count, 140u);
  std::set<uint64_t> ids;
  for (const auto& rec : r.records) ids.insert(rec.id);
  EXPECT_EQ(ids.size(), 150u);
}

TEST(BlackBox, ThroughputOfNMessagesAtFHzIsF) {
  const RunResult r = run_package("rate", relay_graph(""), with_count(50, 50));
  ASSERT_EQ(r.matched, 50u);
  // Not N/(N-1)·f: within 10 % of 50 Hz on a noisy machine, where N/(N-1) alone is 2 %.
  EXPECT_NEAR(r.throughput_hz, 50.0, 5.0);
  EXPECT_NEAR(r.offered_rate_hz, 50.0, 5.0);
}

TEST(BlackBox, FailingNodeEndsTheRunEarlyAndKeepsWhatWasMeasured) {
  const RunResult r = run_package("fail", relay_graph("fail_after: 10"), with_count(60, 100));
  expect_sane(r);
  EXPECT_FALSE(r.completed);
  ASSERT_EQ(r.errors.size(), 1u);
  EXPECT_NE(r.errors[0].find("node 'relay'"), std::string::npos) << r.errors[0];
  EXPECT_NE(r.errors[0].find("fail_after"), std::string::npos) << r.errors[0];
  EXPECT_EQ(r.matched, 10u);
  EXPECT_LT(r.sent, 60u);
  EXPECT_FALSE(r.valid);
  // The node is reported as the one that ended the run, as a child process would be.
  ASSERT_EQ(r.nodes.size(), 1u);
  EXPECT_EQ(r.nodes[0].exit_status, "its callback threw during the run");
}

// An interrupt during the warm-up ends the run before timing started: nothing to keep, so no
// result (the command line then writes none), whatever the warm-up sent.
TEST(BlackBox, AnInterruptDuringTheWarmupMeasuresNothing) {
  RunOptions o = with_count(40, 100);
  o.load.warmup = 20;
  std::atomic<int> interrupted{0};
  o.interrupted = &interrupted;
  o.progress = [&](std::size_t sent, std::size_t, std::size_t) {
    if (sent == 3) interrupted = SIGINT;
  };
  try {
    run_package("warmup_interrupted", relay_graph(""), o);
    ADD_FAILURE() << "an interrupt during the warm-up gave a result";
  } catch (const RunInterrupted& e) {
    EXPECT_EQ(std::string(e.what()),
              "interrupted by SIGINT before timing started: nothing was measured");
  }
}

TEST(BlackBox, FastDdsInOneProcessLosesNothing) {
  RunOptions o = with_count(40, 100);
  o.transport.rmw = "fastdds";
  o.transport.domain_id = rmw::reserved_domain();
  const RunResult r = run_package("fastdds", relay_graph(""), o);
  expect_sane(r);
  EXPECT_EQ(r.matched, 40u);
  EXPECT_EQ(r.lost, 0u);
  EXPECT_TRUE(r.valid);
}

TEST(BlackBox, BadOptionsAreRejectedBeforeTiming) {
  RunOptions o = with_count(10, 100);
  o.load.warmup = 10;
  EXPECT_THROW(run_package("warm", relay_graph(""), o), std::invalid_argument);
  o = with_count(10, 100);
  o.transport.rmw = "carrier-pigeon";
  EXPECT_THROW(run_package("rmw", relay_graph(""), o), std::invalid_argument);
  o = with_count(10, 100);
  o.processes.layout = ProcessLayout::kPerNode;
  EXPECT_THROW(run_package("layout", relay_graph(""), o), std::invalid_argument);
}

// Every rate, count, duration and wait is checked before anything runs: values that used to
// crash (SIGFPE), overflow the schedule or wrap are one clear error each.
TEST(BlackBox, OutOfRangeValuesAreRejectedWithTheOptionNamed) {
  struct Case {
    const char* option;
    std::function<void(RunOptions&)> set;
  };
  const std::vector<Case> cases = {
      {"--rate", [](RunOptions& o) { o.load.rate_hz = 3e9; }},
      {"--rate", [](RunOptions& o) { o.load.rate_hz = 1e-300; }},
      {"--rate", [](RunOptions& o) { o.load.rate_hz = std::numeric_limits<double>::infinity(); }},
      {"--rate", [](RunOptions& o) { o.load.rate_hz = -5; }},
      {"--drain", [](RunOptions& o) { o.load.drain_s = 1e10; }},
      {"--drain", [](RunOptions& o) { o.load.drain_s = -1; }},
      {"--duration",
       [](RunOptions& o) {
         o.load.count.reset();
         o.load.duration_s = std::numeric_limits<double>::quiet_NaN();
       }},
      {"--duration",
       [](RunOptions& o) {
         o.load.count.reset();
         o.load.duration_s = 1e300;
       }},
      {"--count", [](RunOptions& o) { o.load.count = 0; }},
      {"--callback-timeout", [](RunOptions& o) { o.processes.callback_timeout_s = 0; }},
      {"--connect-timeout", [](RunOptions& o) { o.processes.connect_timeout_s = 1e12; }},
      {"messages need",
       [](RunOptions& o) {
         o.load.rate_hz = 1e6;
         o.load.count = 100'000'000'000;
       }},
      {"longer than a week",
       [](RunOptions& o) {
         o.load.rate_hz = 0.01;
         o.load.count = 10'000;
       }},
  };
  for (const auto& c : cases) {
    RunOptions o = with_count(10, 100);
    c.set(o);
    try {
      run_package("bad", relay_graph(""), o);
      ADD_FAILURE() << c.option << ": accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(c.option), std::string::npos)
          << c.option << ": " << e.what();
      EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
    }
  }
}

// Every message of a burst is copied before their common deadline: a burst of large frames that
// would not fit in memory is refused in one line before anything runs.
TEST(BlackBox, ABurstThatWouldNotFitInMemoryIsRefusedBeforeTiming) {
  RunOptions o = with_count(1'000'000, 100'000);
  // 640x480 RGB frames: about 0.9 TB at once.
  o.load.arrival = ArrivalPattern::parse("burst:1000000");
  try {
    run_package("huge_burst", relay_graph(""), o);
    ADD_FAILURE() << "accepted";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("--arrival burst:1000000 prepares 1000000 messages"), std::string::npos)
        << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
}

// What has not arrived by the end of the drain is lost (docs/design.md §3.4), however long the run
// then takes to end: here the external power meter's last reading takes over a second, in which the
// outputs a relay held back arrive.
TEST(BlackBox, OutputsArrivingAfterTheDrainAreNotCounted) {
  RunOptions o = with_count(2, 100);
  o.load.drain_s = 0;
  o.power.types = {"external"};
  o.power.meter_command = "sleep 1.2; echo 10";
  const RunResult r = run_package("cut_off", relay_graph("delay_ms: 300"), o);
  expect_sane(r);
  ASSERT_EQ(r.records.size(), 2u);
  // The drain ends at the last send; the relay answers 300 ms after each.
  const int64_t cut_off = r.records.back().sent_ns + 150'000'000;
  for (const auto& rec : r.records) {
    EXPECT_TRUE(rec.received_ns < 0 || rec.received_ns <= cut_off)
        << "message " << rec.id << " counted, received "
        << (rec.received_ns - r.records.back().sent_ns) / 1e6 << " ms after the last send";
  }
}

TEST(BlackBox, BurstsAreSentBackToBackAtTheirDeadline) {
  RunOptions o = with_count(40, 100);
  o.load.arrival = ArrivalPattern::parse("burst:4");
  const RunResult r = run_package("burst", relay_graph(""), o);
  expect_sane(r);
  EXPECT_EQ(r.matched, 40u);
  EXPECT_EQ(r.timeline, "burst");
  EXPECT_EQ(r.burst, 4u);
  // The mean rate, though its last burst's messages go out at once ((n-1)/span gave 106 Hz).
  EXPECT_NEAR(r.offered_rate_hz, 100.0, 2.0);
  ASSERT_EQ(r.records.size(), 40u);
  for (std::size_t k = 0; k < 40; ++k) {
    EXPECT_EQ(r.records[k].scheduled_ns, r.records[k / 4 * 4].scheduled_ns) << k;
    if (k >= 4 && k % 4 == 0) {
      // 4 messages at 100 Hz: a burst every 40 ms.
      EXPECT_EQ(r.records[k].scheduled_ns - r.records[k - 4].scheduled_ns, 40'000'000) << k;
    }
  }
}

// Single-stream: each message goes out once the previous one's output is back, so a relay that
// takes 20 ms sets the pace (not the 1 kHz rate) and nothing queues.
TEST(Scenarios, SingleStreamSendsWhenTheLastOutputArrived) {
  RunOptions o = with_count(30, 1000);
  o.load.warmup = 5;
  o.load.scenario = Scenario::kSingleStream;
  const RunResult r = run_package("single_stream", relay_graph("delay_ms: 20"), o);
  expect_sane(r);
  EXPECT_EQ(r.timeline, "single-stream");
  EXPECT_EQ(r.matched, 25u);
  ASSERT_EQ(r.records.size(), 30u);
  for (std::size_t k = 1; k < r.records.size(); ++k) {
    ASSERT_GE(r.records[k - 1].received_ns, 0);
    EXPECT_GE(r.records[k].sent_ns, r.records[k - 1].received_ns) << k;
    // Due when it may go: sent at once (a publish's time at most).
    EXPECT_LT(r.records[k].sent_ns - r.records[k].scheduled_ns, 5 * kMs) << k;
  }
  // Each latency is the relay's 20 ms and a wake-up or two: never two relays' worth.
  EXPECT_GE(r.latency_from_scheduled.min, 20 * kMs);
  EXPECT_LT(r.latency_from_scheduled.p50, 40 * kMs);
  EXPECT_LT(r.throughput_hz, 50.5);
}

// Offline: as many messages at once as the graph's queues hold (the relay's KEEP_LAST 10), the
// next one as each output comes back; the relay answers one after another, so the throughput is
// its own rate and the latency from the batch's issue grows with each message's place. No
// message is lost to an overflowing queue.
TEST(Scenarios, OfflineKeepsTheGraphFullAndCountsSamplesPerSecond) {
  RunOptions o = with_count(25, 1);
  o.load.warmup = 5;
  o.load.scenario = Scenario::kOffline;
  const RunResult r = run_package("offline", relay_graph("delay_ms: 10"), o);
  expect_sane(r);
  EXPECT_EQ(r.timeline, "offline");
  EXPECT_EQ(r.matched, 20u);
  ASSERT_EQ(r.records.size(), 25u);
  // The first ten go out back to back (at 1 Hz they would take 9 s), the rest as outputs return.
  EXPECT_LT(r.records[9].sent_ns - r.records[0].sent_ns, 100 * kMs);
  for (std::size_t k = 10; k < r.records.size(); ++k) {
    ASSERT_GE(r.records[k - 10].received_ns, 0);
    EXPECT_GE(r.records[k].sent_ns, r.records[k - 10].received_ns) << k;
  }
  const int64_t issued = r.records[5].sent_ns;
  for (std::size_t k = 5; k < r.records.size(); ++k) EXPECT_EQ(r.records[k].scheduled_ns, issued);
  // The last measured output waited behind the 19 before it (and the warm-up's): 20 relay
  // delays from the issue at least.
  EXPECT_GE(r.latency_from_scheduled.max, 20 * 10 * kMs);
  EXPECT_GT(r.throughput_hz, 40.0);
  EXPECT_LT(r.throughput_hz, 105.0);
}

TEST(Scenarios, ClosedLoopsRefuseWhatNeedsDeadlines) {
  RunOptions o;
  o.load.scenario = Scenario::kOffline;
  o.load.arrival = ArrivalPattern::parse("poisson");
  EXPECT_THROW(o.check(), std::invalid_argument);
  o.load.arrival = {};
  o.tracing.mode = RunMode::kGrey;
  try {
    o.check();
    FAIL() << "an offline grey run was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "--scenario offline is measured black-box: give it without --mode grey");
  }
  EXPECT_THROW(parse_scenario("closed"), std::invalid_argument);
  EXPECT_EQ(scenario_name(parse_scenario("single-stream")), "single-stream");
}

// a5 in both closed-loop scenarios: valid, with their lead figures.
TEST(Scenarios, A5RunsInBothClosedLoopScenarios) {
  const auto a5 = find_benchmark(std::filesystem::path(ROBOTPERF_SOURCE_DIR) / "benchmarks", "a5");
  for (const Scenario scenario : {Scenario::kSingleStream, Scenario::kOffline}) {
    RunOptions o;
    o.load.count = 60;
    o.load.scenario = scenario;
    const RunResult r = run_benchmark(a5, o);
    expect_sane(r);
    EXPECT_TRUE(r.valid) << scenario_name(scenario) << ": "
                         << (r.invalid_reasons.empty() ? "" : r.invalid_reasons[0]);
    EXPECT_EQ(r.timeline, scenario_name(scenario));
    EXPECT_GT(r.throughput_hz, 0.0);
  }
}

// A graph that fans out to two outputs, each monitored: a fast relay to /out, a slow one that
// drops every 4th message to /slow. Each output has its own latency, loss and jitter; the
// second's loss makes the run invalid as the first's would.
TEST(Outputs, EachOfSeveralOutputsHasItsLatencyLossAndJitter) {
  const std::string graph =
      "dataset: perception/image\n"
      "rate_hz: 50\n"
      "warmup: 2\n"
      "drain_s: 1.0\n"
      "validity: {min_samples: 5, max_loss_percent: 0.0}\n"
      "inputs:\n"
      "  - {topic: /in, type: sensor_msgs/msg/Image, stream: image}\n"
      "outputs:\n"
      "  - {topic: /out, type: sensor_msgs/msg/Image}\n"
      "  - {topic: /slow, type: sensor_msgs/msg/Image}\n"
      "nodes:\n"
      "  - name: fast\n"
      "    kernel: util/relay\n"
      "    topics: {input: /in, output: /out}\n"
      "  - name: slow\n"
      "    kernel: util/relay\n"
      "    parameters: {delay_ms: 5, drop_every: 4}\n"
      "    topics: {input: /in, output: /slow}\n";
  RunOptions o;
  o.load.count = 42;
  const RunResult r = run_package("fan_out", graph, o);
  expect_sane(r);
  ASSERT_EQ(r.outputs.size(), 2u);
  const OutputFigures& fast = r.outputs[0];
  const OutputFigures& slow = r.outputs[1];
  EXPECT_EQ(fast.topic, "/out");
  EXPECT_EQ(slow.topic, "/slow");
  // The first output is the run's own figures.
  EXPECT_EQ(fast.matched, r.matched);
  EXPECT_EQ(fast.lost, 0u);
  EXPECT_DOUBLE_EQ(fast.latency_from_scheduled.p50, r.latency_from_scheduled.p50);
  // The slow relay's every 4th message (counting from its first, a warm-up one) is lost.
  EXPECT_EQ(slow.lost, 10u);
  EXPECT_EQ(slow.matched, 30u);
  EXPECT_GE(slow.latency_from_scheduled.min, 5 * kMs);
  EXPECT_GT(slow.latency_from_scheduled.p50, fast.latency_from_scheduled.p50);
  // Jitter against the 20 ms period: the fast output's intervals are about it; the slow one's
  // include the 40 ms gaps its drops leave, 20 ms away from the period.
  EXPECT_NEAR(fast.period_ns, 20 * kMs, 2 * kMs);
  EXPECT_NEAR(fast.interval.p50, 20 * kMs, 5 * kMs);
  EXPECT_LT(fast.jitter.p50, 5 * kMs);
  EXPECT_GE(slow.interval.max, 35 * kMs);
  EXPECT_GE(slow.jitter.max, 15 * kMs);
  EXPECT_FALSE(r.valid);
  ASSERT_FALSE(r.invalid_reasons.empty());
  EXPECT_EQ(r.invalid_reasons.back(), "output /slow: 25.00 % lost, above the 0.00 % bound");
}

TEST(Outputs, OutputAndOutputsAreOneOrTheOther) {
  std::string graph = relay_graph("");
  graph += "outputs:\n  - {topic: /out, type: sensor_msgs/msg/Image}\n";
  TestPackage p("both_outputs", graph);
  try {
    load_benchmark(p.dir());
    FAIL() << "a graph with output and outputs was accepted";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("give 'output' (one) or 'outputs' (a list), not both"),
              std::string::npos)
        << e.what();
  }
}

// A grey run's trace is recorded in a temporary folder and moved beside the results: no line of
// the result may go on naming the temporary folder once it is gone.
TEST(MoveTrace, RewritesEveryLineThatNamedTheTemporaryFolder) {
  robotperf::testing::FixtureRoot root;
  const std::filesystem::path recorded = root.path() / ".trace-ab12cd" / "trace";
  root.write(".trace-ab12cd/trace/ust/metadata", "");
  RunResult r;
  r.trace_dir = recorded;
  const std::string stream = (recorded / "ust" / "channel0_0").string();
  r.invalid_reasons = {"grey-box: the trace in " + recorded.string() + " could not be analysed (" +
                       stream + ": bad packet magic)"};
  r.errors = {"kept " + recorded.string()};
  r.grey.emplace();
  r.grey->traces = {(recorded / "ust").string()};
  r.grey->packet_defects = {stream + ": packet at byte 0: event 'x' is after the packet's end"};

  const std::filesystem::path kept = root.path() / "a1-intra.trace";
  move_trace(r, kept);

  EXPECT_EQ(r.trace_dir, kept);
  EXPECT_TRUE(std::filesystem::exists(kept / "ust" / "metadata"));
  EXPECT_FALSE(std::filesystem::exists(recorded));
  const std::string moved = (kept / "ust" / "channel0_0").string();
  EXPECT_EQ(r.invalid_reasons.front(), "grey-box: the trace in " + kept.string() +
                                           " could not be analysed (" + moved +
                                           ": bad packet magic)");
  EXPECT_EQ(r.errors.front(), "kept " + kept.string());
  EXPECT_EQ(r.grey->traces.front(), (kept / "ust").string());
  EXPECT_EQ(r.grey->packet_defects.front(),
            moved + ": packet at byte 0: event 'x' is after the packet's end");
}

}  // namespace
}  // namespace robotperf::harness
