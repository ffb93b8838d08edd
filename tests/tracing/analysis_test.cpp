// The CTF reader and the analyzer on hand-built traces whose timestamps are
// known, so every latency, hop and count has an exact expected value.
#include "robotperf/tracing/analysis.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>

#include "../fixture_root.hpp"
#include "ctf_writer.hpp"
#include "robotperf/tracing/ctf.hpp"

namespace robotperf::tracing {
namespace {

namespace fs = std::filesystem;
using testing::CtfWriter;
using V = testing::FieldValue;

using robotperf::testing::FixtureRoot;

constexpr int32_t kRunPid = 42;
constexpr int64_t kBase = 1'700'000'000'000'000'000;  // message ID of frame 0
constexpr int64_t kPeriod = 10'000'000;               // 10 ms
constexpr uint64_t kStart = 5'000'000'000;            // first deadline, trace clock
constexpr int64_t kLateness = 100;
// End-to-end latency from the actual send, per frame; -1 = lost.
constexpr int64_t kLatency[] = {4'000'000, 7'000'000, -1, 3'000'000};

int64_t id_of(uint64_t k) {
  return kBase + static_cast<int64_t>(k) * kPeriod;
}
uint64_t sent_of(uint64_t k) {
  return kStart + k * kPeriod + kLateness;
}

// A relay run of 4 frames (warm-up 1), traced on two CPUs (streams): the
// Playback publishes /in, node "relay" runs kernel "k" and publishes /out,
// the Monitor takes /out. Frame 2 is lost after the kernel.
// With `device_stages`, the kernel runs on a device: upload 200 ns, compute 500 ns, download
// 150 ns inside its kernel_init..kernel_fini.
// With `repeated_outputs`, the Monitor takes frame 0 (warm-up, as when the Playback repeats the
// warm-up) and frame 1 (measured) a second time after the last frame. `declared_period` is the
// period the run_begin event gives (the IDs are kPeriod apart whatever it says).
// How the output is declared: a plain topic, or a state stream (the relay publishes frame 1's
// state twice more after the last frame and the Monitor takes it each time), recorded as such or
// in a trace from before run_begin recorded it.
// With `slow_warmup_take`, the relay takes frame 0 (warm-up) from the middleware kSlowWarmupTake
// after its rmw_publish instead of 500 ns.
// With `tf2_calls`, the relay's kernel calls its tf2 buffer in every frame: a set of 500 ns, then
// a lookup of 250 ns; and another process's buffer calls one lookup of 4 us.
enum class OutputKind { kPlain, kState, kStateUnrecorded };
constexpr int64_t kSlowWarmupTake = 10'000'000;
void write_run(CtfWriter& w, uint64_t discarded_in_second_packet = 0, bool device_stages = false,
               bool repeated_outputs = false, int64_t declared_period = kPeriod,
               OutputKind output = OutputKind::kPlain, bool slow_warmup_take = false,
               bool tf2_calls = false) {
  testing::define_robotperf_events(w, testing::Ros2Layout::kJazzy,
                                   output != OutputKind::kStateUnrecorded);
  for (const char* e : {"robotperf:tf2_begin", "robotperf:tf2_end"}) {
    w.define(e, {{"node", testing::FieldKind::kString},
                 {"operation", testing::FieldKind::kString},
                 {"call", testing::FieldKind::kU64}});
  }
  const std::string play = "robotperf_playback", relay = "relay", mon = "robotperf_monitor";
  const uint64_t t0 = kStart - 1'000'000;
  // Initialisation: node, subscription + callback, timer, publisher of /in.
  w.event(0, "ros2:rcl_node_init", t0, kRunPid, 1,
          {V(uint64_t{0x10}), V(uint64_t{0}), V(relay), V(std::string("/"))});
  w.event(0, "ros2:rcl_node_init", t0 + 1, kRunPid, 1,
          {V(uint64_t{0x11}), V(uint64_t{0}), V(play), V(std::string("/"))});
  w.event(0, "ros2:rcl_subscription_init", t0 + 2, kRunPid, 1,
          {V(uint64_t{0x20}), V(uint64_t{0x10}), V(uint64_t{0x30}), V(std::string("/in")),
           V(uint64_t{10})});
  w.event(0, "ros2:rclcpp_subscription_init", t0 + 3, kRunPid, 1,
          {V(uint64_t{0x20}), V(uint64_t{0x21})});
  w.event(0, "ros2:rclcpp_subscription_callback_added", t0 + 4, kRunPid, 1,
          {V(uint64_t{0x21}), V(uint64_t{0x40})});
  w.event(0, "ros2:rcl_timer_init", t0 + 5, kRunPid, 1,
          {V(uint64_t{0x50}), V(int64_t{100'000'000})});
  w.event(0, "ros2:rclcpp_timer_callback_added", t0 + 6, kRunPid, 1,
          {V(uint64_t{0x50}), V(uint64_t{0x60})});
  w.event(0, "ros2:rclcpp_timer_link_node", t0 + 7, kRunPid, 1,
          {V(uint64_t{0x50}), V(uint64_t{0x10})});
  w.event(0, "ros2:rcl_publisher_init", t0 + 8, kRunPid, 1,
          {V(uint64_t{0x70}), V(uint64_t{0x11}), V(uint64_t{0x80}), V(std::string("/in")),
           V(uint64_t{10})});
  std::vector<V> run_begin = {
      V(std::string("t1")), V(std::string("intra")), V(uint64_t{4}), V(uint64_t{1}),
      V(declared_period),   V(uint64_t{1}),          V(50.0)};
  if (output != OutputKind::kStateUnrecorded)
    run_begin.push_back(V(int64_t{output == OutputKind::kState ? 1 : 0}));
  w.event(0, "robotperf:run_begin", t0 + 9, kRunPid, 1, run_begin);

  for (uint64_t k = 0; k < 4; ++k) {
    const int64_t id = id_of(k);
    const uint64_t sent = sent_of(k);
    // Stream 0: the Playback thread; stream 1: the executor thread (another CPU).
    w.event(0, "robotperf:input", sent, kRunPid, 1,
            {V(play), V(id), V(k), V(static_cast<int64_t>(kStart + k * kPeriod))});
    w.event(0, "robotperf:publish", sent + 10, kRunPid, 1,
            {V(play), V(std::string("/in")), V(id), V(uint64_t{100})});
    w.event(0, "ros2:rmw_publish", sent + 20, kRunPid, 1,
            {V(uint64_t{0x80}), V(uint64_t{0x999}), V(static_cast<int64_t>(sent))});
    if (slow_warmup_take && k == 1) {
      w.event(1, "ros2:rmw_take", sent_of(0) + 20 + kSlowWarmupTake, kRunPid, 2,
              {V(uint64_t{0x30}), V(uint64_t{0x999}), V(static_cast<int64_t>(sent_of(0))),
               V(int64_t{1})});
    }
    if (!slow_warmup_take || k != 0) {
      w.event(
          1, "ros2:rmw_take", sent + 520, kRunPid, 2,
          {V(uint64_t{0x30}), V(uint64_t{0x999}), V(static_cast<int64_t>(sent)), V(int64_t{1})});
    }
    w.event(1, "ros2:callback_start", sent + 990, kRunPid, 2, {V(uint64_t{0x40}), V(int64_t{1})});
    w.event(1, "robotperf:callback_entry", sent + 1000, kRunPid, 2,
            {V(relay), V(std::string("/in")), V(id), V(uint64_t{100})});
    w.event(1, "robotperf:kernel_init", sent + 2000, kRunPid, 2,
            {V(relay), V(std::string("k")), V(id), V(uint64_t{100})});
    if (device_stages) {
      const std::pair<const char*, uint64_t> stages[] = {
          {"upload", 2100}, {"compute", 2300}, {"download", 2800}, {nullptr, 2950}};
      for (int i = 0; i < 3; ++i) {
        w.event(1, "robotperf:device_begin", sent + stages[i].second, kRunPid, 2,
                {V(relay), V(std::string(stages[i].first)), V(id), V(uint64_t{100})});
        w.event(1, "robotperf:device_end", sent + stages[i + 1].second, kRunPid, 2,
                {V(relay), V(std::string(stages[i].first)), V(id), V(uint64_t{100})});
      }
    }
    if (tf2_calls) {
      const std::pair<const char*, uint64_t> calls[] = {{"set", 2100}, {"lookup", 2650}};
      const uint64_t lasts[] = {500, 250};
      for (int i = 0; i < 2; ++i) {
        const std::vector<V> fields{V(relay), V(std::string(calls[i].first)), V(2 * k + i)};
        w.event(1, "robotperf:tf2_begin", sent + calls[i].second, kRunPid, 2, fields);
        w.event(1, "robotperf:tf2_end", sent + calls[i].second + lasts[i], kRunPid, 2, fields);
      }
      w.event(0, "robotperf:tf2_begin", sent + 2200, 99, 99,
              {V(std::string("other")), V(std::string("lookup")), V(k)});
      w.event(0, "robotperf:tf2_end", sent + 6200, 99, 99,
              {V(std::string("other")), V(std::string("lookup")), V(k)});
    }
    w.event(1, "robotperf:kernel_fini", sent + 3000 + 100 * k, kRunPid, 2,
            {V(relay), V(std::string("k")), V(id), V(uint64_t{100})});
    if (kLatency[k] >= 0) {
      w.event(1, "robotperf:publish", sent + 5000, kRunPid, 2,
              {V(relay), V(std::string("/out")), V(id), V(uint64_t{100})});
    }
    // The callback ends on the other CPU (the thread migrated): 6000 + k ns after its start.
    w.event(0, "ros2:callback_end", sent + 990 + 6000 + k, kRunPid, 2, {V(uint64_t{0x40})});
    if (kLatency[k] >= 0) {
      const uint64_t out = sent + static_cast<uint64_t>(kLatency[k]);
      w.event(1, "robotperf:callback_entry", out - 5, kRunPid, 3,
              {V(mon), V(std::string("/out")), V(id), V(uint64_t{100})});
      w.event(1, "robotperf:output", out, kRunPid, 3,
              {V(mon), V(std::string("/out")), V(id), V(uint64_t{100})});
    }
    // A timer callback of 250 ns.
    w.event(0, "ros2:callback_start", sent + 8'000'000, kRunPid, 4,
            {V(uint64_t{0x60}), V(int64_t{0})});
    w.event(0, "ros2:callback_end", sent + 8'000'250, kRunPid, 4, {V(uint64_t{0x60})});
    if (k == 1) {
      w.end_packet(0, 0);
      w.end_packet(1, discarded_in_second_packet);
    }
  }
  if (repeated_outputs) {
    for (uint64_t k : {0, 1}) {
      w.event(1, "robotperf:output", sent_of(3) + 8'500'000 + k, kRunPid, 3,
              {V(mon), V(std::string("/out")), V(id_of(k)), V(uint64_t{100})});
    }
  }
  if (output != OutputKind::kPlain) {
    for (uint64_t r = 0; r < 2; ++r) {
      const uint64_t t = sent_of(3) + 8'600'000 + 100'000 * r;
      w.event(1, "robotperf:publish", t, kRunPid, 2,
              {V(relay), V(std::string("/out")), V(id_of(1)), V(uint64_t{100})});
      w.event(1, "robotperf:callback_entry", t + 5000, kRunPid, 3,
              {V(mon), V(std::string("/out")), V(id_of(1)), V(uint64_t{100})});
      w.event(1, "robotperf:output", t + 5005, kRunPid, 3,
              {V(mon), V(std::string("/out")), V(id_of(1)), V(uint64_t{100})});
    }
  }
  // Another run's process receiving one of our IDs: not ours, not counted.
  w.event(1, "robotperf:output", sent_of(3) + 9'000'000, 99, 99,
          {V(mon), V(std::string("/out")), V(id_of(3)), V(uint64_t{100})});
  w.event(0, "robotperf:run_end", sent_of(3) + 9'500'000, kRunPid, 1, {V(uint64_t{4})});
  w.finish();
}

// IDs that are not base + k * period of the run (a trace robotperf's Playback did not write) are
// looked up instead of computed: the same counts, latencies and hops.
TEST(Analyzer, IdsOfAnotherSpacingGiveTheSameResult) {
  auto analysed = [](int64_t declared_period) {
    FixtureRoot dir;
    CtfWriter w(dir.path(), CtfWriter::Header::kCompact, false, 2);
    write_run(w, 0, false, true, declared_period);
    return analyze_trace(dir.path());
  };
  const TraceAnalysis computed = analysed(kPeriod);
  const TraceAnalysis looked_up = analysed(kPeriod + 1);
  EXPECT_EQ(looked_up.matched, 2u);
  EXPECT_EQ(looked_up.duplicates, 1u);
  EXPECT_EQ(looked_up.lost, computed.lost);
  EXPECT_DOUBLE_EQ(looked_up.latency_from_sent.max, 7'000'000.0);
  EXPECT_DOUBLE_EQ(looked_up.latency_from_sent.p50, computed.latency_from_sent.p50);
  ASSERT_EQ(looked_up.hops.size(), computed.hops.size());
  ASSERT_FALSE(computed.hops.empty());
  for (std::size_t i = 0; i < computed.hops.size(); ++i) {
    EXPECT_EQ(looked_up.hops[i].label(), computed.hops[i].label());
    EXPECT_DOUBLE_EQ(looked_up.hops[i].duration.mean, computed.hops[i].duration.mean);
  }
}

// A warm-up message the Playback sent again comes back again: not a duplicate, as in the
// black-box count; a measured message taken twice is one.
TEST(Analyzer, ARepeatedWarmupIsNoDuplicate) {
  FixtureRoot dir;
  CtfWriter w(dir.path(), CtfWriter::Header::kCompact, false, 2);
  write_run(w, 0, false, true);
  const TraceAnalysis a = analyze_trace(dir.path());
  EXPECT_EQ(a.duplicates, 1u);
  EXPECT_EQ(a.matched, 2u);
  EXPECT_EQ(a.unknown, 0u);
}

// A state stream (control benchmarks) keeps publishing the newest command's ID: its further
// receptions are repeats, as the Monitor counts them, and each hop takes one sample per message,
// from the first publish and the first take. A trace from before run_begin said so counts them
// as duplicates, as robotperf did then.
TEST(Analyzer, AStateStreamsRepeatsAreNeitherDuplicatesNorHopSamples) {
  auto analysed = [](OutputKind output) {
    FixtureRoot dir;
    CtfWriter w(dir.path(), CtfWriter::Header::kCompact, false, 2);
    write_run(w, 0, false, false, kPeriod, output);
    return analyze_trace(dir.path());
  };
  const TraceAnalysis plain = analysed(OutputKind::kPlain);
  const TraceAnalysis state = analysed(OutputKind::kState);
  ASSERT_TRUE(state.run.has_value());
  EXPECT_TRUE(state.run->state_output);
  EXPECT_FALSE(plain.run->state_output);
  EXPECT_EQ(state.matched, 2u);
  EXPECT_EQ(state.duplicates, 0u);
  EXPECT_EQ(state.repeats, 2u);
  EXPECT_TRUE(state.valid) << (state.invalid_reasons.empty() ? "" : state.invalid_reasons[0]);
  EXPECT_DOUBLE_EQ(state.latency_from_sent.max, plain.latency_from_sent.max);
  ASSERT_EQ(state.hops.size(), plain.hops.size());
  for (std::size_t i = 0; i < plain.hops.size(); ++i) {
    EXPECT_EQ(state.hops[i].label(), plain.hops[i].label());
    EXPECT_EQ(state.hops[i].duration.count, plain.hops[i].duration.count) << plain.hops[i].label();
    EXPECT_DOUBLE_EQ(state.hops[i].duration.max, plain.hops[i].duration.max)
        << plain.hops[i].label();
  }

  const TraceAnalysis unrecorded = analysed(OutputKind::kStateUnrecorded);
  ASSERT_TRUE(unrecorded.run.has_value());
  EXPECT_FALSE(unrecorded.run->state_output);
  EXPECT_EQ(unrecorded.matched, 2u);
  EXPECT_EQ(unrecorded.duplicates, 2u);
  EXPECT_EQ(unrecorded.repeats, 0u);
  EXPECT_FALSE(unrecorded.valid);
}

TEST(CtfReader, DecodesCompactAndExtendedHeadersWithClockWrap) {
  FixtureRoot dir;
  CtfWriter w(dir.path(), CtfWriter::Header::kCompact, true);
  w.define("a:b", {{"v", testing::FieldKind::kU64}, {"s", testing::FieldKind::kString}});
  // Low 27 bits wrap between the 2nd and 3rd event; a gap of more than 2^27 ns
  // forces an extended header; the last one has the largest possible compact delta.
  const uint64_t ts[] = {(1ull << 27) - 10, (1ull << 27) - 1, (1ull << 27) + 5, (1ull << 40),
                         (1ull << 40) + (1ull << 27) - 1};
  for (uint64_t i = 0; i < 5; ++i)
    w.event(0, "a:b", ts[i], 7, 8, {V(i * 3), V(std::string("x") + std::to_string(i))});
  w.finish();

  ctf::Trace trace(dir.path());
  EXPECT_EQ(trace.metadata().env_value("tracer_name"), "lttng-ust");
  ASSERT_EQ(trace.stream_count(), 1u);
  const int vpid = trace.stream_context_index(0, "vpid");
  const int procname = trace.stream_context_index(0, "procname");
  ASSERT_GE(vpid, 0);
  std::vector<uint64_t> seen;
  const auto stats = trace.read_stream(0, [&](const ctf::Event& e) {
    EXPECT_EQ(e.cls->name, "a:b");
    EXPECT_EQ(e.fields[0].u, seen.size() * 3);
    EXPECT_EQ(e.fields[1].s, "x" + std::to_string(seen.size()));
    EXPECT_EQ(e.stream_context[static_cast<std::size_t>(vpid)].as_int(), 7);
    EXPECT_EQ(e.stream_context[static_cast<std::size_t>(procname)].s, "robotperf");
    seen.push_back(e.timestamp);
  });
  EXPECT_EQ(stats.events, 5u);
  EXPECT_EQ(stats.packets, 1u);
  EXPECT_EQ(seen, std::vector<uint64_t>(std::begin(ts), std::end(ts)));
}

// Strings of every length up to 80 bytes (found a word at a time, then by memchr), each followed
// by a number that must be read from right after its NUL.
TEST(CtfReader, StringsOfEveryLengthEndAtTheirNul) {
  FixtureRoot dir;
  CtfWriter w(dir.path(), CtfWriter::Header::kLarge, false);
  w.define("a:s", {{"s", testing::FieldKind::kString}, {"v", testing::FieldKind::kU64}});
  auto text = [](uint64_t n) {
    std::string t;
    for (uint64_t i = 0; i < n; ++i) t += static_cast<char>('a' + (i * 7 + n) % 26);
    return t;
  };
  for (uint64_t n = 0; n <= 80; ++n) w.event(0, "a:s", 1000 + n, 7, 8, {V(text(n)), V(n * 11)});
  w.finish();
  ctf::Trace trace(dir.path());
  uint64_t n = 0;
  trace.read_stream(0, [&](const ctf::Event& e) {
    EXPECT_EQ(e.fields[0].s, text(n)) << n;
    EXPECT_EQ(e.fields[1].u, n * 11) << n;
    ++n;
  });
  EXPECT_EQ(n, 81u);
}

// A reader that selects fields gets those exactly as without a selection, and the others with no
// value; the events after an unselected string or gid array are still read from the right place.
TEST(CtfReader, FieldsNotSelectedAreSteppedOver) {
  FixtureRoot dir;
  CtfWriter w(dir.path(), CtfWriter::Header::kCompact, false);
  w.define("a:mixed", {{"name", testing::FieldKind::kString},
                       {"gid", testing::FieldKind::kGid},
                       {"x", testing::FieldKind::kF64},
                       {"id", testing::FieldKind::kI64},
                       {"tail", testing::FieldKind::kString},
                       {"n", testing::FieldKind::kU64}});
  for (uint64_t k = 0; k < 20; ++k) {
    w.event(0, "a:mixed", 1000 + k, 7, static_cast<int32_t>(100 + k),
            {V("node" + std::string(k, 'x')), V(uint64_t{0}), V(0.5 * static_cast<double>(k)),
             V(-static_cast<int64_t>(k)), V(std::string(k % 5, 't')), V(k * 3)});
  }
  w.finish();
  ctf::Trace trace(dir.path());
  ctf::StreamIndex index = trace.index_stream(0);
  ctf::FieldSelection selection;
  selection.payload = [](const ctf::EventClass&, std::size_t field) {
    return field == 3 || field == 5;
  };
  const int vtid = trace.stream_context_index(0, "vtid");
  ASSERT_GE(vtid, 0);
  selection.stream_context = [&](const ctf::StreamClass&, std::size_t field) {
    return static_cast<int>(field) == vtid;
  };
  uint64_t k = 0;
  const uint64_t events =
      trace
          .read_packets(
              0, index.packets,
              [&](const ctf::Event& e) {
                ASSERT_EQ(e.fields.size(), 6u);
                EXPECT_EQ(e.fields[0].tag, ctf::Value::Tag::kNone) << k;
                EXPECT_EQ(e.fields[2].tag, ctf::Value::Tag::kNone) << k;
                EXPECT_EQ(e.fields[4].tag, ctf::Value::Tag::kNone) << k;
                EXPECT_EQ(e.fields[3].as_int(), -static_cast<int64_t>(k)) << k;
                EXPECT_EQ(e.fields[5].u, k * 3) << k;
                EXPECT_EQ(e.stream_context[static_cast<std::size_t>(vtid)].as_int(),
                          static_cast<int64_t>(100 + k));
                EXPECT_EQ(e.timestamp, 1000 + k);
                ++k;
              },
              &selection)
          .events;
  EXPECT_EQ(events, 20u);
  EXPECT_EQ(k, 20u);
}

TEST(Analyzer, HandBuiltTraceGivesExactLatencies) {
  for (auto header : {CtfWriter::Header::kCompact, CtfWriter::Header::kLarge}) {
    FixtureRoot dir;
    CtfWriter w(dir.path() / "ust" / "uid" / "0" / "64-bit", header,
                header == CtfWriter::Header::kLarge, 2);
    write_run(w);
    const TraceAnalysis a = analyze_trace(dir.path());

    ASSERT_TRUE(a.run.has_value());
    EXPECT_EQ(a.run->benchmark, "t1");
    EXPECT_EQ(a.run->pid, kRunPid);
    EXPECT_DOUBLE_EQ(a.run->max_loss_percent, 50.0);
    EXPECT_EQ(a.discarded_events, 0u);
    EXPECT_EQ(a.sent, 4u);
    EXPECT_EQ(a.measured, 3u);
    EXPECT_EQ(a.matched, 2u);
    EXPECT_EQ(a.lost, 1u);
    EXPECT_EQ(a.duplicates, 0u) << "the other process's reception must not count";
    EXPECT_EQ(a.unknown, 0u);
    // Measured and matched: frames 1 (7 ms) and 3 (3 ms).
    EXPECT_EQ(a.latency_from_sent.count, 2u);
    EXPECT_DOUBLE_EQ(a.latency_from_sent.min, 3'000'000.0);
    EXPECT_DOUBLE_EQ(a.latency_from_sent.max, 7'000'000.0);
    EXPECT_DOUBLE_EQ(a.latency_from_scheduled.min, 3'000'000.0 + kLateness);
    EXPECT_DOUBLE_EQ(a.latency_from_scheduled.max, 7'000'000.0 + kLateness);
    EXPECT_DOUBLE_EQ(a.send_lateness.mean, static_cast<double>(kLateness));
    // Receptions at sent(1)+7 ms and sent(3)+3 ms: 16 ms apart, 2 of them.
    EXPECT_NEAR(a.throughput_hz, 1.0 / 0.016, 1e-9);
    EXPECT_TRUE(a.valid) << (a.invalid_reasons.empty() ? "" : a.invalid_reasons[0]);

    auto hop = [&](const std::string& label) -> const Hop* {
      for (const auto& h : a.hops) {
        if (h.label() == label) return &h;
      }
      ADD_FAILURE() << "no hop " << label;
      return nullptr;
    };
    if (const Hop* h = hop("/in: robotperf_playback -> relay")) {
      EXPECT_EQ(h->duration.count, 3u);
      EXPECT_DOUBLE_EQ(h->duration.min, 990.0);
      EXPECT_DOUBLE_EQ(h->duration.max, 990.0);
    }
    if (const Hop* h = hop("relay: k")) {
      EXPECT_EQ(h->duration.count, 3u);
      EXPECT_DOUBLE_EQ(h->duration.mean, 1200.0);  // 1100, 1200, 1300
    }
    if (const Hop* h = hop("relay: /in -> /out")) {
      EXPECT_EQ(h->duration.count, 2u);  // frame 2 was never published
      EXPECT_DOUBLE_EQ(h->duration.mean, 4000.0);
    }
    if (const Hop* h = hop("/out: relay -> robotperf_monitor")) {
      EXPECT_DOUBLE_EQ(h->duration.min, 3'000'000.0 - 5000 - 5);
      EXPECT_DOUBLE_EQ(h->duration.max, 7'000'000.0 - 5000 - 5);
    }
    ASSERT_EQ(a.hops.size(), 4u);
    EXPECT_EQ(a.hops.front().kind, "transport") << "hops are ordered along the path";

    ASSERT_EQ(a.callbacks.size(), 2u);
    for (const auto& cb : a.callbacks) {
      EXPECT_EQ(cb.node, "relay");
      EXPECT_EQ(cb.duration.count, 4u);
      if (cb.source == "/in") {
        EXPECT_DOUBLE_EQ(cb.duration.min, 6000.0);
        EXPECT_DOUBLE_EQ(cb.duration.max, 6003.0);
      } else {
        EXPECT_EQ(cb.source, "timer 100 ms");
        EXPECT_DOUBLE_EQ(cb.duration.mean, 250.0);
      }
    }
    ASSERT_EQ(a.topics.size(), 1u);
    EXPECT_EQ(a.topics[0].topic, "/in");
    EXPECT_EQ(a.topics[0].publisher, "robotperf_playback");
    EXPECT_EQ(a.topics[0].subscriber, "relay");
    EXPECT_DOUBLE_EQ(a.topics[0].latency.mean, 500.0);
  }
}

// The tf2 share: the calls of the run's processes from the first measured send to the last matched
// output (frames 1, 2 and 3: the lost frame's calls too, not the warm-up's), per matched message,
// over the mean latency from the actual send.
TEST(Analyzer, Tf2ShareIsTheCallsPerMessageOverTheLatency) {
  FixtureRoot dir;
  CtfWriter w(dir.path() / "ust" / "uid" / "0" / "64-bit", CtfWriter::Header::kCompact, false, 2);
  write_run(w, 0, false, false, kPeriod, OutputKind::kPlain, false, true);
  const TraceAnalysis a = analyze_trace(dir.path());
  ASSERT_TRUE(a.valid) << a.invalid_reasons.at(0);
  ASSERT_EQ(a.tf2_calls.size(), 2u);
  for (const auto& t : a.tf2_calls) {
    EXPECT_EQ(t.node, "relay");
    EXPECT_EQ(t.duration.count, 4u) << "every frame's call, the warm-up's too";
    EXPECT_DOUBLE_EQ(t.duration.mean, t.operation == "set" ? 500.0 : 250.0);
  }
  ASSERT_TRUE(a.tf2_share.has_value());
  EXPECT_EQ(a.tf2_share->calls, 6u);
  EXPECT_DOUBLE_EQ(a.tf2_share->calls_per_message, 3.0);  // 6 calls, 2 matched
  EXPECT_DOUBLE_EQ(a.tf2_share->per_message_ns, 3 * 750.0 / 2);
  // Mean latency from the send: (7 ms + 3 ms) / 2.
  EXPECT_DOUBLE_EQ(a.tf2_share->of_latency, 1125.0 / 5'000'000.0);
  EXPECT_NE(breakdown_table(a).find("tf2 share: 0.02 % of the end-to-end latency (1.1 us of tf2 "
                                    "calls per message, 3.0 calls)"),
            std::string::npos)
      << breakdown_table(a);
  EXPECT_DOUBLE_EQ(to_json(a)["tf2_share"]["per_message_us"].get<double>(), 1.125);

  // Without tf2 calls there is no share.
  FixtureRoot plain;
  CtfWriter w2(plain.path() / "ust" / "uid" / "0" / "64-bit", CtfWriter::Header::kCompact, false,
               2);
  write_run(w2);
  const TraceAnalysis b = analyze_trace(plain.path());
  EXPECT_FALSE(b.tf2_share.has_value());
  EXPECT_TRUE(to_json(b)["tf2_share"].is_null());
}

// A run whose streams hold many packets, names first used in late packets and handles
// re-declared in later ones: what decoding the streams in parts must merge exactly.
void write_long_run(CtfWriter& w, uint64_t frames) {
  testing::define_robotperf_events(w);
  const std::string play = "robotperf_playback", mon = "robotperf_monitor";
  w.event(0, "robotperf:run_begin", kStart - 10, kRunPid, 1,
          {V(std::string("t1")), V(std::string("intra")), V(frames), V(uint64_t{2}), V(kPeriod),
           V(uint64_t{1}), V(50.0), V(int64_t{0})});
  // A subscription of node 0x10 with callback 0x40: the callback table names the node.
  w.event(1, "ros2:rcl_subscription_init", kStart - 9, kRunPid, 1,
          {V(uint64_t{0x20}), V(uint64_t{0x10}), V(uint64_t{0x30}), V(std::string("/in")),
           V(uint64_t{10})});
  w.event(1, "ros2:rclcpp_subscription_init", kStart - 8, kRunPid, 1,
          {V(uint64_t{0x20}), V(uint64_t{0x21})});
  w.event(1, "ros2:rclcpp_subscription_callback_added", kStart - 7, kRunPid, 1,
          {V(uint64_t{0x21}), V(uint64_t{0x40})});
  for (uint64_t k = 0; k < frames; ++k) {
    const int64_t id = id_of(k);
    const uint64_t sent = sent_of(k);
    // Node handle 0x10 is re-declared every 7 frames under a new name: the last one holds.
    if (k % 7 == 0) {
      w.event(1, "ros2:rcl_node_init", sent - 5, kRunPid, 1,
              {V(uint64_t{0x10}), V(uint64_t{0}), V("relay_" + std::to_string(k / 7)),
               V(std::string("/"))});
    }
    // A node and kernel name used from frame k on only.
    const std::string relay = "relay_" + std::to_string(k / 5);
    const std::string kernel = "k" + std::to_string(k % 3);
    w.event(0, "robotperf:input", sent, kRunPid, 1,
            {V(play), V(id), V(k), V(static_cast<int64_t>(kStart + k * kPeriod))});
    w.event(0, "robotperf:publish", sent + 10, kRunPid, 1,
            {V(play), V(std::string("/in")), V(id), V(uint64_t{100})});
    w.event(1, "ros2:callback_start", sent + 990, kRunPid, 2, {V(uint64_t{0x40}), V(int64_t{1})});
    w.event(1, "robotperf:callback_entry", sent + 1000, kRunPid, 2,
            {V(relay), V(std::string("/in")), V(id), V(uint64_t{100})});
    w.event(1, "robotperf:kernel_init", sent + 2000, kRunPid, 2,
            {V(relay), V(kernel), V(id), V(uint64_t{100})});
    w.event(1, "robotperf:kernel_fini", sent + 3000 + 37 * k, kRunPid, 2,
            {V(relay), V(kernel), V(id), V(uint64_t{100})});
    w.event(1, "robotperf:publish", sent + 5000 + 11 * k, kRunPid, 2,
            {V(relay), V(std::string("/out")), V(id), V(uint64_t{100})});
    w.event(1, "ros2:callback_end", sent + 6000 + 7 * k, kRunPid, 2, {V(uint64_t{0x40})});
    w.event(0, "robotperf:output", sent + 9000 + 13 * (k % 17), kRunPid, 3,
            {V(mon), V(std::string("/out")), V(id), V(uint64_t{100})});
    if (k % 3 == 2) w.end_packet(0);
    if (k % 4 == 3) w.end_packet(1);
  }
  w.event(0, "robotperf:run_end", sent_of(frames) + 1000, kRunPid, 1, {V(frames)});
  w.finish();
}

// Decoding in parts on several threads gives what one thread reading every stream in order
// gives, to the last field.
TEST(Analyzer, DecodingInPartsGivesTheResultOfOneThread) {
  FixtureRoot dir;
  CtfWriter w(dir.path(), CtfWriter::Header::kCompact, false, 2);
  write_long_run(w, 60);
  AnalyzeOptions one;
  one.decode_threads = 1;
  one.part_bytes = uint64_t{1} << 40;
  nlohmann::json expected = to_json(analyze_trace(dir.path(), one));
  expected["trace"].erase("analysis_s");
  ASSERT_GT(expected["trace"]["packets"].get<int>(), 30);
  ASSERT_GT(expected["hops"].size(), 3u);
  ASSERT_EQ(expected["callbacks"].size(), 1u);
  EXPECT_EQ(expected["callbacks"][0]["node"], "relay_8") << "the handle's last declaration";
  for (unsigned threads : {2u, 3u, 8u}) {
    AnalyzeOptions parts;
    parts.decode_threads = threads;
    parts.part_bytes = 1;  // every packet a part of its own
    nlohmann::json got = to_json(analyze_trace(dir.path(), parts));
    got["trace"].erase("analysis_s");
    EXPECT_TRUE(got == expected) << threads << " threads differ from one: "
                                 << nlohmann::json::diff(expected, got).dump().substr(0, 600);
  }
}

// The publish -> take table counts the messages the hop table does: not the warm-up's, however
// long their transport took.
TEST(Analyzer, PublishToTakeLeavesTheWarmupOut) {
  FixtureRoot dir;
  CtfWriter w(dir.path(), CtfWriter::Header::kCompact, false, 2);
  write_run(w, 0, false, false, kPeriod, OutputKind::kPlain, true);
  const TraceAnalysis a = analyze_trace(dir.path());
  ASSERT_EQ(a.topics.size(), 1u);
  EXPECT_EQ(a.topics[0].topic, "/in");
  EXPECT_EQ(a.topics[0].latency.count, a.measured);
  EXPECT_LT(a.topics[0].latency.max, static_cast<double>(kSlowWarmupTake));
  EXPECT_DOUBLE_EQ(a.topics[0].latency.mean, 500.0);
}

// A kernel on a device: its upload, compute and download stages are hops of their own, beside
// the kernel's.
TEST(Analyzer, DeviceStagesAreHopsOfTheirOwn) {
  FixtureRoot dir;
  CtfWriter w(dir.path(), CtfWriter::Header::kCompact, false, 2);
  write_run(w, 0, true);
  const TraceAnalysis a = analyze_trace(dir.path());
  std::map<std::string, const Hop*> by_label;
  for (const auto& h : a.hops) by_label[h.label()] = &h;
  for (const auto& [stage, ns] :
       {std::pair{"upload", 200.0}, {"compute", 500.0}, {"download", 150.0}}) {
    const auto it = by_label.find(std::string("relay: device ") + stage);
    ASSERT_NE(it, by_label.end()) << stage;
    EXPECT_EQ(it->second->kind, "device");
    EXPECT_EQ(it->second->duration.count, 3u) << stage;
    EXPECT_DOUBLE_EQ(it->second->duration.mean, ns) << stage;
  }
  ASSERT_TRUE(by_label.contains("relay: k"));
  EXPECT_DOUBLE_EQ(by_label["relay: k"]->duration.mean, 1200.0);
  EXPECT_EQ(a.hops.size(), 7u);
}

TEST(Analyzer, DiscardedEventsAreReportedAndInvalidate) {
  FixtureRoot dir;
  CtfWriter w(dir.path(), CtfWriter::Header::kLarge, false, 2);
  write_run(w, 7);
  const TraceAnalysis a = analyze_trace(dir.path());
  EXPECT_EQ(a.discarded_events, 7u);
  EXPECT_FALSE(a.valid);
  ASSERT_FALSE(a.invalid_reasons.empty());
  EXPECT_NE(a.invalid_reasons[0].find("discarded 7 events"), std::string::npos)
      << a.invalid_reasons[0];
  EXPECT_EQ(to_json(a)["trace"]["discarded_events"], 7);
  // The message without an output event is not counted lost: its event may be among those
  // discarded.
  EXPECT_EQ(a.matched + 1, a.measured);
  EXPECT_EQ(a.unobserved, 1u);
  EXPECT_EQ(a.lost, 0u);
  EXPECT_EQ(a.loss_percent, 0.0);
}

TEST(Analyzer, TraceWithoutRobotperfRunStillGivesCallbacksAndTopics) {
  FixtureRoot dir;
  CtfWriter w(dir.path(), CtfWriter::Header::kCompact, false);
  testing::define_robotperf_events(w);
  w.event(0, "ros2:rcl_node_init", 100, 7, 7,
          {V(uint64_t{1}), V(uint64_t{0}), V(std::string("talker")), V(std::string("/demo"))});
  w.event(0, "ros2:rcl_timer_init", 110, 7, 7, {V(uint64_t{2}), V(int64_t{500'000'000})});
  w.event(0, "ros2:rclcpp_timer_callback_added", 120, 7, 7, {V(uint64_t{2}), V(uint64_t{3})});
  w.event(0, "ros2:rclcpp_timer_link_node", 130, 7, 7, {V(uint64_t{2}), V(uint64_t{1})});
  w.event(0, "ros2:callback_start", 1000, 7, 7, {V(uint64_t{3}), V(int64_t{0})});
  w.event(0, "ros2:callback_end", 1700, 7, 7, {V(uint64_t{3})});
  w.finish();
  const TraceAnalysis a = analyze_trace(dir.path());
  EXPECT_FALSE(a.run.has_value());
  EXPECT_TRUE(a.valid);
  ASSERT_EQ(a.callbacks.size(), 1u);
  EXPECT_EQ(a.callbacks[0].node, "/demo/talker");
  EXPECT_EQ(a.callbacks[0].source, "timer 500 ms");
  EXPECT_DOUBLE_EQ(a.callbacks[0].duration.mean, 700.0);
  EXPECT_NE(analysis_summary(a).find("no robotperf run"), std::string::npos);
}

// A process whose run the trace does not hold: no run is taken instead, and the reasons name the
// processes whose runs it holds.
TEST(Analyzer, ARunOfAnotherProcessIsNamedNotTaken) {
  FixtureRoot dir;
  CtfWriter w(dir.path(), CtfWriter::Header::kCompact, false, 2);
  write_run(w);
  AnalyzeOptions of_run;
  of_run.run_pid = kRunPid;
  EXPECT_EQ(analyze_trace(dir.path(), of_run).run_pids, std::vector<int>{kRunPid});
  AnalyzeOptions of_another;
  of_another.run_pid = kRunPid + 1;
  const TraceAnalysis a = analyze_trace(dir.path(), of_another);
  EXPECT_FALSE(a.run.has_value());
  EXPECT_FALSE(a.valid);
  const std::string expected = "no robotperf run of process " + std::to_string(kRunPid + 1) +
                               " in the trace (it holds the run of process " +
                               std::to_string(kRunPid) + ")";
  EXPECT_EQ(missing_run(a, kRunPid + 1), expected);
  EXPECT_EQ(a.invalid_reasons, std::vector<std::string>{expected});
  EXPECT_NE(breakdown_table(a).find("end-to-end latency: " + expected), std::string::npos)
      << breakdown_table(a);
}

// ros2_tracing's rclcpp_callback_register names callbacks; a Humble trace (rmw_publish without a
// timestamp) cannot pair publishes with takes, and the analysis says so instead of dropping the
// table silently.
TEST(Analyzer, CallbackSymbolsAndWhyATableIsMissing) {
  FixtureRoot dir;
  CtfWriter w(dir.path(), CtfWriter::Header::kCompact, false);
  testing::define_robotperf_events(w, testing::Ros2Layout::kHumble);
  w.event(0, "ros2:rcl_node_init", 100, 7, 7,
          {V(uint64_t{1}), V(uint64_t{0}), V(std::string("talker")), V(std::string("/"))});
  w.event(0, "ros2:rcl_timer_init", 110, 7, 7, {V(uint64_t{2}), V(int64_t{500'000'000})});
  w.event(0, "ros2:rclcpp_timer_callback_added", 120, 7, 7, {V(uint64_t{2}), V(uint64_t{3})});
  w.event(0, "ros2:rclcpp_timer_link_node", 130, 7, 7, {V(uint64_t{2}), V(uint64_t{1})});
  const std::string symbol =
      "demo::(anonymous namespace)::Talker::Talker(rclcpp::NodeOptions const&)::{lambda()#1}";
  w.event(0, "ros2:rclcpp_callback_register", 140, 7, 7, {V(uint64_t{3}), V(symbol)});
  w.event(0, "ros2:rmw_publish", 900, 7, 7, {V(uint64_t{0x99})});
  w.event(0, "ros2:callback_start", 1000, 7, 7, {V(uint64_t{3}), V(int64_t{0})});
  w.event(0, "ros2:callback_end", 1700, 7, 7, {V(uint64_t{3})});
  w.finish();
  const TraceAnalysis a = analyze_trace(dir.path());
  ASSERT_EQ(a.callbacks.size(), 1u);
  EXPECT_EQ(a.callbacks[0].symbol, symbol);
  const std::string table = breakdown_table(a);
  EXPECT_NE(table.find("demo::Talker::Talker(...)::{lambda(...)#1}"), std::string::npos) << table;
  EXPECT_NE(table.find("publish -> take latencies: ros2:rmw_publish has no timestamp field"),
            std::string::npos)
      << table;
  EXPECT_NE(table.find("per-hop breakdown and end-to-end latency: no robotperf run"),
            std::string::npos)
      << table;
  EXPECT_EQ(to_json(a)["callbacks"][0]["symbol"], symbol);
  EXPECT_EQ(to_json(a)["unavailable"].size(), a.unavailable.size());
}

// Event times count nanoseconds whatever the clock's frequency: its cycles are converted.
TEST(CtfReader, EventTimesAreNanosecondsOfAClockOfAnyFrequency) {
  FixtureRoot dir;
  CtfWriter w(dir.path(), CtfWriter::Header::kCompact, false);
  w.clock_frequency(1'000'000);  // 1 MHz: a cycle is 1 us
  testing::define_robotperf_events(w);
  w.event(0, "ros2:rcl_timer_init", 100, 7, 7, {V(uint64_t{2}), V(int64_t{500'000'000})});
  w.event(0, "ros2:rclcpp_timer_callback_added", 110, 7, 7, {V(uint64_t{2}), V(uint64_t{3})});
  w.event(0, "ros2:callback_start", 1000, 7, 7, {V(uint64_t{3}), V(int64_t{0})});
  w.event(0, "ros2:callback_end", 1700, 7, 7, {V(uint64_t{3})});
  w.finish();
  const TraceAnalysis a = analyze_trace(dir.path());
  ASSERT_EQ(a.callbacks.size(), 1u);
  EXPECT_DOUBLE_EQ(a.callbacks[0].duration.mean, 700'000.0);
  ctf::Trace trace(dir.path());
  std::vector<uint64_t> times;
  trace.read_stream(0, [&](const ctf::Event& e) { times.push_back(e.timestamp); });
  EXPECT_EQ(times, (std::vector<uint64_t>{100'000, 110'000, 1'000'000, 1'700'000}));

  // A frequency that is not one is refused, naming the clock.
  std::string metadata;
  {
    std::ifstream in(dir.path() / "metadata");
    metadata.assign(std::istreambuf_iterator<char>(in), {});
  }
  const auto at = metadata.find("freq = 1000000;");
  ASSERT_NE(at, std::string::npos);
  std::ofstream(dir.path() / "metadata") << metadata.replace(at, 15, "freq = -1000000;");
  try {
    analyze_trace(dir.path());
    FAIL() << "a negative clock frequency accepted";
  } catch (const ctf::CtfError& e) {
    EXPECT_NE(std::string(e.what()).find("clock 'monotonic'"), std::string::npos) << e.what();
  }
}

// Writes two events of class "t:e" with u64 fields `fields` ("sent" first), the second's sent
// being `second_sent`, in a trace whose metadata declares `declaration` after `after`.
void write_declared(const fs::path& dir, const std::vector<std::string>& fields,
                    uint64_t second_sent, const std::string& after,
                    const std::string& declaration) {
  CtfWriter w(dir, CtfWriter::Header::kCompact, false);
  std::vector<testing::FieldDef> defs;
  for (const auto& f : fields) defs.push_back({f, testing::FieldKind::kU64});
  w.define("t:e", defs);
  w.event(0, "t:e", 1000, 1, 1, std::vector<V>(fields.size(), V(uint64_t{0})));
  w.event(0, "t:e", 1001, 1, 1, std::vector<V>(fields.size(), V(second_sent)));
  w.finish();
  std::string metadata;
  {
    std::ifstream in(dir / "metadata");
    metadata.assign(std::istreambuf_iterator<char>(in), {});
  }
  const auto at = metadata.find(after);
  ASSERT_NE(at, std::string::npos);
  std::ofstream(dir / "metadata") << metadata.replace(at, after.size(), declaration);
}

// Every event of the trace in `dir`, or the reader's error; an endless stream of events is cut.
uint64_t read_events(const fs::path& dir) {
  ctf::Trace trace(dir);
  ctf::StreamIndex index = trace.index_stream(0);
  uint64_t events = 0;
  return trace
      .read_packets(0, index.packets,
                    [&](const ctf::Event&) {
                      if (++events > 1000)
                        throw std::runtime_error("endless events from a trace of two");
                    })
      .events;
}

// A length read from the trace whose count of bits overflows 64 bits (2^61 - 74 bytes: the
// product wraps 74 bytes back, to the first event) is past the end of the packet, not a step
// back into events already read; so is a length from the metadata whose bytes overflow.
// Elements that take no bits are refused before being decoded 2^40 times.
TEST(CtfReader, LengthsBeyondThePacketAreErrorsNotStepsBack) {
  FixtureRoot dir;
  const uint64_t wraps_back = (uint64_t{1} << 61) - 74;
  const std::pair<uint64_t, std::string> sequences[] = {
      {wraps_back, "_sent;\n\t\tuint8_t _blob[_sent];"},
      {wraps_back,
       "_sent;\n\t\tinteger { size = 8; align = 8; signed = 0; encoding = UTF8; } _text[_sent];"},
      {uint64_t{1} << 40, "_sent;\n\t\tstruct { } _empty[_sent];"}};
  for (const auto& [sent, declaration] : sequences) {
    fs::remove_all(dir.path());
    write_declared(dir.path(), {"sent"}, sent, "_sent;", declaration);
    EXPECT_THROW(read_events(dir.path()), ctf::CtfError) << declaration;
  }
  // 2^61 + 1 elements of 8 bytes: as many bytes as 8 once the product wraps, which the second
  // field's 8 bytes would hold.
  fs::remove_all(dir.path());
  write_declared(dir.path(), {"sent", "pad"}, 0, "_pad;", "_pad[2305843009213693953];");
  EXPECT_THROW(read_events(dir.path()), ctf::CtfError);
}

// A packet size near 2^64 does not wrap the next packet's start back to an earlier packet: it
// does not fit the file.
TEST(CtfReader, APacketSizeNear2To64DoesNotFitTheFile) {
  FixtureRoot dir;
  CtfWriter w(dir.path(), CtfWriter::Header::kCompact, false);
  testing::define_robotperf_events(w);
  w.event(0, "robotperf:run_end", 1000, 1, 1, {V(uint64_t{4})});
  w.end_packet(0);
  w.event(0, "robotperf:run_end", 2000, 1, 1, {V(uint64_t{4})});
  w.finish();
  const fs::path stream = dir.path() / "channel0_0";
  const uint64_t second = ctf::Trace(dir.path()).index_stream(0).packets.at(1).start_bits / 8;
  // packet_size follows the 32-byte packet header, timestamp_begin, timestamp_end and
  // content_size: 2^64 - second * 8 bits would take packet_start back to 0.
  const uint64_t size = uint64_t{0} - second * 8;
  std::fstream(stream, std::ios::in | std::ios::out | std::ios::binary)
      .seekp(static_cast<std::streamoff>(second + 56))
      .write(reinterpret_cast<const char*>(&size), sizeof size);
  try {
    analyze_trace(dir.path());
    FAIL() << "a packet larger than its file accepted";
  } catch (const ctf::CtfError& e) {
    EXPECT_NE(std::string(e.what()).find(stream.string() + ": packet size"), std::string::npos)
        << e.what();
  }
}

TEST(CtfReader, CorruptTracesGiveClearErrors) {
  FixtureRoot dir;
  CtfWriter w(dir.path(), CtfWriter::Header::kLarge, false);
  testing::define_robotperf_events(w);
  w.event(0, "robotperf:run_end", 1000, 1, 1, {V(uint64_t{4})});
  w.finish();
  const fs::path stream = dir.path() / "channel0_0";
  // Cut the stream inside its packet: the packet no longer fits the file.
  fs::resize_file(stream, 100);
  EXPECT_THROW(analyze_trace(dir.path()), ctf::CtfError);
  // Not a CTF stream at all.
  std::ofstream(stream, std::ios::binary) << std::string(200, 'x');
  try {
    analyze_trace(dir.path());
    FAIL() << "garbage stream accepted";
  } catch (const ctf::CtfError& e) {
    EXPECT_NE(std::string(e.what()).find("magic"), std::string::npos) << e.what();
  }
  // Broken metadata names the line.
  std::ofstream(dir.path() / "metadata")
      << "/* CTF 1.8 */\ntrace {\n major = 1;\n packet.header := struct { nonsense_t x; };\n};\n";
  try {
    analyze_trace(dir.path());
    FAIL() << "broken metadata accepted";
  } catch (const ctf::CtfError& e) {
    EXPECT_NE(std::string(e.what()).find("line 4"), std::string::npos) << e.what();
  }
  EXPECT_THROW(analyze_trace(dir.path() / "nothing-here"), ctf::CtfError);
  const FixtureRoot empty;
  fs::create_directories(empty.path());
  EXPECT_THROW(analyze_trace(empty.path()), std::invalid_argument);
}

// A value of type T at byte `offset` of file `path`, read or overwritten (a corrupt byte, a
// tracer's quirk).
template <class T>
T read_at(const fs::path& path, uint64_t offset) {
  T value{};
  std::ifstream(path, std::ios::binary)
      .seekg(static_cast<std::streamoff>(offset))
      .read(reinterpret_cast<char*>(&value), sizeof value);
  return value;
}
template <class T>
void write_at(const fs::path& path, uint64_t offset, T value) {
  std::fstream(path, std::ios::in | std::ios::out | std::ios::binary)
      .seekp(static_cast<std::streamoff>(offset))
      .write(reinterpret_cast<const char*>(&value), sizeof value);
}

// Where the writer's packet context puts timestamp_begin and timestamp_end, from the packet's
// start: after the 32-byte packet header.
constexpr uint64_t kBeginAt = 32, kEndAt = 40;

// The times of every event of stream 0 that the reader gives.
std::vector<uint64_t> event_times(const fs::path& dir) {
  ctf::Trace trace(dir);
  std::vector<uint64_t> times;
  trace.read_stream(0, [&](const ctf::Event& e) { times.push_back(e.timestamp); });
  return times;
}

// The `trace` block of the analysis's JSON (the defective packets and their lines).
nlohmann::json trace_block(const fs::path& dir) {
  return to_json(analyze_trace(dir))["trace"];
}

// A timer callback of node "talker" every 10 ms that takes 5 ms, `per_packet` callbacks a packet.
void write_timer_callbacks(CtfWriter& w, uint64_t callbacks, uint64_t per_packet) {
  testing::define_robotperf_events(w);
  w.event(0, "ros2:rcl_node_init", kStart - 40, 7, 7,
          {V(uint64_t{1}), V(uint64_t{0}), V(std::string("talker")), V(std::string("/"))});
  w.event(0, "ros2:rcl_timer_init", kStart - 30, 7, 7, {V(uint64_t{2}), V(int64_t{kPeriod})});
  w.event(0, "ros2:rclcpp_timer_callback_added", kStart - 20, 7, 7,
          {V(uint64_t{2}), V(uint64_t{3})});
  w.event(0, "ros2:rclcpp_timer_link_node", kStart - 10, 7, 7, {V(uint64_t{2}), V(uint64_t{1})});
  for (uint64_t k = 0; k < callbacks; ++k) {
    const uint64_t start = kStart + k * kPeriod;
    w.event(0, "ros2:callback_start", start, 7, 7, {V(uint64_t{3}), V(int64_t{0})});
    w.event(0, "ros2:callback_end", start + 5'000'000, 7, 7, {V(uint64_t{3})});
    if (k % per_packet == per_packet - 1) w.end_packet(0);
  }
  w.finish();
}

// Issue #47: one flipped byte in a 32-bit event time (LTTng's large event header) lowers it,
// which the reader takes for a wrap of the clock's low 32 bits: the event, and the rest of its
// packet, 4.26 s later. A 5 ms timer callback measured 4,266 ms in a trace analysed as valid. The
// event lies after its packet's end: the packet's events are left out, and the result says why.
TEST(Analyzer, AFlippedTimeByteLeavesItsPacketOutAndInvalidates) {
  FixtureRoot dir;
  CtfWriter w(dir.path(), CtfWriter::Header::kLarge, false);
  write_timer_callbacks(w, 20, 5);
  const fs::path stream = dir.path() / "channel0_0";
  // Callback 7's end, in the second packet (callbacks 5 to 9): a callback_start takes 43 bytes
  // (16-bit id, 32-bit time, 25 bytes of context, 12 of payload), a callback_end 39.
  const uint64_t second = ctf::Trace(dir.path()).index_stream(0).packets.at(1).events_bits / 8;
  const uint64_t end_7 = second + 2 * (43 + 39) + 43;
  ASSERT_EQ(read_at<uint16_t>(stream, end_7), w.id("ros2:callback_end"));
  const uint64_t time_7 = kStart + 7 * kPeriod + 5'000'000;
  ASSERT_EQ(read_at<uint32_t>(stream, end_7 + 2), static_cast<uint32_t>(time_7));
  const uint64_t top = end_7 + 5;  // the time's most significant byte
  write_at(stream, top, static_cast<uint8_t>(read_at<uint8_t>(stream, top) ^ 0x02));

  const TraceAnalysis a = analyze_trace(dir.path());
  ASSERT_EQ(a.callbacks.size(), 1u);
  EXPECT_EQ(a.callbacks[0].duration.count, 15u) << "the second packet's 5 callbacks left out";
  EXPECT_DOUBLE_EQ(a.callbacks[0].duration.max, 5'000'000.0);
  EXPECT_FALSE(a.valid);
  ASSERT_FALSE(a.invalid_reasons.empty());
  const std::string defect =
      stream.string() + ": packet at byte " +
      std::to_string(ctf::Trace(dir.path()).index_stream(0).packets[1].start_bits / 8) +
      ": event 'ros2:callback_end' at 9.336412864 s" +
      " is after the packet's end at 5.095000000 s";
  EXPECT_EQ(a.invalid_reasons[0],
            "the trace is corrupt: the events of 1 packet are left out, their times out of order "
            "(" +
                defect + ")");
  const nlohmann::json trace = to_json(a)["trace"];
  EXPECT_EQ(trace["defective_packets"], 1);
  EXPECT_EQ(trace["packet_defects"], nlohmann::json::array({defect}));
  EXPECT_NE(analysis_summary(a).find("result: INVALID — the trace is corrupt"), std::string::npos)
      << analysis_summary(a);
}

// A corrupt end far in the future overlaps every later packet, but only the pair it breaks is
// left out: the packets after it are checked against the last packet left in.
TEST(Analyzer, ACorruptPacketEndLeavesOutItsPairNotTheRestOfTheStream) {
  FixtureRoot dir;
  CtfWriter w(dir.path(), CtfWriter::Header::kLarge, false);
  write_timer_callbacks(w, 20, 5);
  const fs::path stream = dir.path() / "channel0_0";
  const uint64_t second = ctf::Trace(dir.path()).index_stream(0).packets.at(1).start_bits / 8;
  write_at(stream, second + kEndAt + 7, uint8_t{0x40});  // the end's top byte: 146 years later
  const TraceAnalysis a = analyze_trace(dir.path());
  EXPECT_EQ(to_json(a)["trace"]["defective_packets"], 2);
  ASSERT_EQ(a.callbacks.size(), 1u);
  EXPECT_EQ(a.callbacks[0].duration.count, 10u) << "the first and the last two packets' callbacks";
  EXPECT_DOUBLE_EQ(a.callbacks[0].duration.max, 5'000'000.0);
  EXPECT_FALSE(a.valid);
}

// The reader's checks of event and packet times, one corrupt time each in a trace of two packets
// (compact headers; the fourth event's time is a full 64-bit one): the defective packets' events
// are left out, and each defect is one line naming the stream, the packet and the times.
TEST(CtfReader, TimesOutOfOrderMakeTheirPacketsDefective) {
  FixtureRoot dir;
  const fs::path stream = dir.path() / "channel0_0";
  const uint64_t first[] = {1000, 2000, 3000, (uint64_t{1} << 28) + 4000,
                            (uint64_t{1} << 28) + 5000};
  const uint64_t second[] = {uint64_t{1} << 29, (uint64_t{1} << 29) + 10};
  // A compact event takes 37 bytes (32-bit header, 25 bytes of context, 8 of payload); the
  // extended header's 64-bit time follows its 5-bit id, its padding and its 32-bit id.
  const uint64_t full_time_at = 84 + 3 * 37 + 5;
  uint64_t second_packet = 0;
  auto write = [&] {
    fs::remove_all(dir.path());
    CtfWriter w(dir.path(), CtfWriter::Header::kCompact, false);
    w.define("a:b", {{"v", testing::FieldKind::kU64}});
    for (const uint64_t t : first) w.event(0, "a:b", t, 1, 1, {V(t)});
    w.end_packet(0);
    for (const uint64_t t : second) w.event(0, "a:b", t, 1, 1, {V(t)});
    w.finish();
    second_packet = ctf::Trace(dir.path()).index_stream(0).packets.at(1).start_bits / 8;
    ASSERT_EQ(read_at<uint64_t>(stream, full_time_at), first[3]);
  };
  const std::vector<uint64_t> first_times(std::begin(first), std::end(first));
  const std::vector<uint64_t> second_times(std::begin(second), std::end(second));
  auto packet = [&](uint64_t at) {
    return stream.string() + ": packet at byte " + std::to_string(at);
  };
  struct Case {
    const char* what;
    uint64_t offset;  // of the corrupt 64-bit time: from the stream's start
    uint64_t value;
    std::vector<uint64_t> times;  // the events read
    std::vector<std::string> defects;
  };
  write();
  const Case cases[] = {
      {"an event before the one before it",
       full_time_at,
       2500,
       second_times,
       {packet(0) + ": event 'a:b' at 0.000002500 s is before the event before it at "
                    "0.000003000 s"}},
      {"an event before its packet's begin",
       full_time_at,
       500,
       second_times,
       {packet(0) + ": event 'a:b' at 0.000000500 s is before the packet's begin at "
                    "0.000001000 s"}},
      {"an event after its packet's end",
       kEndAt,
       4000,
       second_times,
       {packet(0) + ": event 'a:b' at 0.268439456 s is after the packet's end at 0.000004000 s"}},
      {"a packet beginning after its end",
       second_packet + kBeginAt,
       second[1] + 1,
       first_times,
       {packet(second_packet) + " begins at 0.536870923 s, after its end at 0.536870922 s"}},
      {"a packet beginning before the previous one ends",
       second_packet + kBeginAt,
       2000,
       {},
       {packet(0) + " ends at 0.268440456 s, after the packet at byte " +
            std::to_string(second_packet) + " begins at 0.000002000 s",
        packet(second_packet) + " begins at 0.000002000 s, before the packet at byte 0 ends at "
                                "0.268440456 s"}},
  };
  for (const Case& c : cases) {
    write();
    write_at(stream, c.offset, c.value);
    EXPECT_EQ(event_times(dir.path()), c.times) << c.what;
    const nlohmann::json trace = trace_block(dir.path());
    EXPECT_EQ(trace["defective_packets"], c.defects.size()) << c.what;
    EXPECT_EQ(trace["packet_defects"], nlohmann::json(c.defects)) << c.what;
    EXPECT_EQ(trace["events"], c.times.size()) << c.what;
  }
}

// Compact times hold the low 27 or 32 bits of the clock: a value below the one before it is a
// wrap of those bits, not a step back, also for a packet's first event after its begin.
TEST(CtfReader, WrapsOfCompactTimesAreNoDefects) {
  FixtureRoot dir;
  const fs::path stream = dir.path() / "channel0_0";
  for (const auto header : {CtfWriter::Header::kCompact, CtfWriter::Header::kLarge}) {
    const uint64_t wrap = uint64_t{1} << (header == CtfWriter::Header::kCompact ? 27 : 32);
    fs::remove_all(dir.path());
    CtfWriter w(dir.path(), header, false);
    w.define("a:b", {{"v", testing::FieldKind::kU64}});
    // Wraps between events of a packet, and from the second packet's begin (set 5 cycles before
    // the wrap) to its first event.
    const uint64_t first[] = {5 * wrap - 3, 5 * wrap + 2, 6 * wrap - 10};
    const uint64_t second[] = {6 * wrap + 1, 7 * wrap - 1, 7 * wrap + 7};
    for (const uint64_t t : first) w.event(0, "a:b", t, 1, 1, {V(t)});
    w.end_packet(0);
    for (const uint64_t t : second) w.event(0, "a:b", t, 1, 1, {V(t)});
    w.finish();
    const uint64_t second_packet =
        ctf::Trace(dir.path()).index_stream(0).packets.at(1).start_bits / 8;
    write_at(stream, second_packet + kBeginAt, 6 * wrap - 5);
    std::vector<uint64_t> expected(std::begin(first), std::end(first));
    expected.insert(expected.end(), std::begin(second), std::end(second));
    EXPECT_EQ(event_times(dir.path()), expected);
    const TraceAnalysis a = analyze_trace(dir.path());
    EXPECT_TRUE(a.valid) << analysis_summary(a);
    EXPECT_EQ(to_json(a)["trace"]["defective_packets"], 0);
  }
}

// The packet ends that tracers are known to get wrong bound nothing but what the next packet's
// begin bounds (as babeltrace2 reads them): the end of a crashed session's packets, left 0, and
// the end LTTng-UST wrote before 2.11, which its last events may follow.
TEST(CtfReader, PacketEndsKnownWrongAreNoDefects) {
  FixtureRoot dir;
  const fs::path stream = dir.path() / "channel0_0";
  uint64_t second_packet = 0;
  auto write = [&](const std::string& tracer_minor) {
    fs::remove_all(dir.path());
    CtfWriter w(dir.path(), CtfWriter::Header::kCompact, false);
    w.define("a:b", {{"v", testing::FieldKind::kU64}});
    for (const uint64_t t : {1000, 2000}) w.event(0, "a:b", t, 1, 1, {V(t)});
    w.end_packet(0);
    for (const uint64_t t : {3000, 4000}) w.event(0, "a:b", t, 1, 1, {V(t)});
    w.finish();
    second_packet = ctf::Trace(dir.path()).index_stream(0).packets.at(1).start_bits / 8;
    std::string metadata;
    {
      std::ifstream in(dir.path() / "metadata");
      metadata.assign(std::istreambuf_iterator<char>(in), {});
    }
    const auto at = metadata.find("tracer_minor = 13;");
    ASSERT_NE(at, std::string::npos);
    std::ofstream(dir.path() / "metadata")
        << metadata.replace(at, 18, "tracer_minor = " + tracer_minor + ";");
  };
  const std::vector<uint64_t> all = {1000, 2000, 3000, 4000};
  // A crashed session: both packets' ends 0.
  write("13");
  write_at(stream, kEndAt, uint64_t{0});
  write_at(stream, second_packet + kEndAt, uint64_t{0});
  EXPECT_EQ(event_times(dir.path()), all);
  EXPECT_EQ(trace_block(dir.path())["defective_packets"], 0);
  // The first packet's events past its end: a defect from LTTng-UST 2.11 on only.
  for (const char* minor : {"10", "13"}) {
    write(minor);
    write_at(stream, kEndAt, uint64_t{1500});
    EXPECT_EQ(trace_block(dir.path())["defective_packets"], minor == std::string("10") ? 0 : 1)
        << "lttng-ust 2." << minor;
  }
  // Past the next packet's begin is a defect whatever the version.
  write("10");
  write_at(stream, second_packet + kBeginAt, uint64_t{1500});
  EXPECT_EQ(event_times(dir.path()), (std::vector<uint64_t>{3000, 4000}));
}

// A corrupt packet is left out whichever part of a stream holds it and however many threads
// decode: the result is the one of a single thread.
TEST(Analyzer, ADefectivePacketGivesTheSameResultInParts) {
  FixtureRoot dir;
  CtfWriter w(dir.path(), CtfWriter::Header::kCompact, false, 2);
  write_long_run(w, 60);
  // The end of stream 1's fourth packet before its last event.
  const fs::path stream = dir.path() / "channel0_1";
  const uint64_t fourth = ctf::Trace(dir.path()).index_stream(1).packets.at(3).start_bits / 8;
  write_at(stream, fourth + kEndAt, read_at<uint64_t>(stream, fourth + kEndAt) - 1);
  AnalyzeOptions one;
  one.decode_threads = 1;
  one.part_bytes = uint64_t{1} << 40;
  nlohmann::json expected = to_json(analyze_trace(dir.path(), one));
  expected["trace"].erase("analysis_s");
  EXPECT_EQ(expected["trace"]["defective_packets"], 1);
  for (unsigned threads : {2u, 8u}) {
    AnalyzeOptions parts;
    parts.decode_threads = threads;
    parts.part_bytes = 1;
    nlohmann::json got = to_json(analyze_trace(dir.path(), parts));
    got["trace"].erase("analysis_s");
    EXPECT_TRUE(got == expected) << threads << " threads differ from one: "
                                 << nlohmann::json::diff(expected, got).dump().substr(0, 600);
  }
}

}  // namespace
}  // namespace robotperf::tracing
