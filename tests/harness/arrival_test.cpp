// Arrival patterns and the message IDs that keep runs apart.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <set>
#include <string>
#include <vector>

#include "black_box.hpp"
#include "robotperf/harness/peak_search.hpp"
#include "robotperf/metrics/delivery_validity.hpp"
#include "run_isolation.hpp"

namespace robotperf::harness {
namespace {

TEST(ArrivalPattern, ParsesWhatTheCommandLineTakesAndRefusesTheRest) {
  EXPECT_EQ(ArrivalPattern::parse("fixed").kind, ArrivalPattern::Kind::kFixed);
  EXPECT_EQ(ArrivalPattern::parse("poisson").kind, ArrivalPattern::Kind::kPoisson);
  const ArrivalPattern burst = ArrivalPattern::parse("burst:8");
  EXPECT_EQ(burst.kind, ArrivalPattern::Kind::kBurst);
  EXPECT_EQ(burst.burst, 8u);
  EXPECT_EQ(burst.name(), "burst:8");
  for (const char* bad : {"burst:0", "burst:", "burst:-3", "burst:2x", "zipf", "", "burst:1e9"})
    EXPECT_THROW(ArrivalPattern::parse(bad), std::invalid_argument) << bad;
}

TEST(ArrivalSchedule, PoissonHasTheMeanIntervalAndExponentialSpread) {
  ArrivalPattern poisson = ArrivalPattern::parse("poisson");
  poisson.seed = 42;
  const int64_t period = 1'000'000;  // 1 kHz
  const std::size_t n = 20'001;
  const auto schedule = arrival_schedule(poisson, period, n);
  ASSERT_EQ(schedule.size(), n);
  EXPECT_EQ(schedule[0], 0);
  double sum = 0, sum_sq = 0;
  std::size_t longer_than_mean = 0;
  for (std::size_t k = 1; k < n; ++k) {
    const double gap = static_cast<double>(schedule[k] - schedule[k - 1]);
    ASSERT_GE(gap, 0);
    sum += gap;
    sum_sq += gap * gap;
    longer_than_mean += gap > static_cast<double>(period);
  }
  const double mean = sum / static_cast<double>(n - 1);
  const double sd = std::sqrt(sum_sq / static_cast<double>(n - 1) - mean * mean);
  // The mean of 20000 exponential intervals is within 3 % (4 standard errors of 0.7 %).
  EXPECT_NEAR(mean, static_cast<double>(period), 0.03 * static_cast<double>(period));
  // An exponential's standard deviation equals its mean; P(gap > mean) = 1/e.
  EXPECT_NEAR(sd / mean, 1.0, 0.05);
  EXPECT_NEAR(static_cast<double>(longer_than_mean) / static_cast<double>(n - 1), std::exp(-1.0),
              0.02);
}

TEST(ArrivalSchedule, PoissonIsReproducibleFromItsSeed) {
  ArrivalPattern a = ArrivalPattern::parse("poisson");
  a.seed = 7;
  ArrivalPattern b = a;
  b.seed = 8;
  EXPECT_EQ(arrival_schedule(a, 33'333'333, 500), arrival_schedule(a, 33'333'333, 500));
  EXPECT_NE(arrival_schedule(a, 33'333'333, 500), arrival_schedule(b, 33'333'333, 500));
  // The first intervals of seed 7 are fixed here, so that a change of generator is noticed.
  const auto s = arrival_schedule(a, 1'000'000, 3);
  EXPECT_GT(s[1], 0);
  EXPECT_GT(s[2], s[1]);
}

TEST(ArrivalSchedule, FixedAndBurstKeepTheMeanRate) {
  const auto fixed = arrival_schedule(ArrivalPattern{}, 10, 5);
  EXPECT_EQ(fixed, (std::vector<int64_t>{0, 10, 20, 30, 40}));
  const auto burst = arrival_schedule(ArrivalPattern::parse("burst:3"), 10, 7);
  EXPECT_EQ(burst, (std::vector<int64_t>{0, 0, 0, 30, 30, 30, 60}));
}

// A peak-search step whose Playback sent every message at its deadline on `schedule`, the graph
// answering each 1 ms later; sent_stretch > 1 draws the sends out: a Playback falling behind.
RunResult step_on(const std::vector<int64_t>& schedule, double rate_hz, double sent_stretch) {
  RunResult r;
  r.rate_hz = rate_hz;
  std::vector<metrics::TimedEvent> sends, receptions;
  for (std::size_t k = 0; k < schedule.size(); ++k) {
    const int64_t deadline = 1'000'000'000 + schedule[k];
    const int64_t sent =
        1'000'000'000 + std::llround(static_cast<double>(schedule[k]) * sent_stretch);
    r.records.push_back({k, deadline, sent, sent + 1'000'000, false});
    sends.push_back({deadline, sent});
    receptions.push_back({deadline, sent + 1'000'000});
  }
  r.sent = r.measured = r.matched = schedule.size();
  const metrics::DeliveryRates rates = metrics::delivery_rates(sends, receptions);
  r.offered_rate_hz = rates.offered_hz;
  r.throughput_hz = rates.output_hz;
  return r;
}

// A Poisson schedule's own mean rate is not the nominal one (seed 17's 155 messages at 30 Hz
// come at under 28.5 Hz): a Playback that met every deadline kept the rate asked of it.
TEST(PeakStep, APlaybackThatKeptItsPoissonScheduleIsNotTheLimit) {
  ArrivalPattern poisson = ArrivalPattern::parse("poisson");
  poisson.seed = 17;
  const auto schedule = arrival_schedule(poisson, 1'000'000'000 / 30, 155);
  BenchmarkSpec spec;
  spec.min_samples = 5;
  const RunResult kept = step_on(schedule, 30, 1.0);
  ASSERT_LT(kept.offered_rate_hz, 0.95 * 30) << "the seed no longer shows the difference";
  EXPECT_EQ(peak_step_failure(kept, spec, {}, 1.0), "");
  // One that fell a fifth behind its schedule is.
  const std::string behind = peak_step_failure(step_on(schedule, 30, 1.25), spec, {}, 1.0);
  EXPECT_NE(behind.find("the Playback sent at only"), std::string::npos) << behind;
}

TEST(MessageIds, EachRunHasItsOwnRandomBaseNearTheWallClock) {
  const auto now = std::chrono::duration_cast<std::chrono::nanoseconds>(
                       std::chrono::system_clock::now().time_since_epoch())
                       .count();
  const MessageIds a = make_message_ids(1'000'000, 100);
  const MessageIds b = make_message_ids(1'000'000, 100);
  for (const MessageIds& ids : {a, b}) {
    EXPECT_GE(ids.base_ns, now - 1'000'000);
    EXPECT_LT(ids.base_ns, now + 1'000'000'000);
  }
  // Two runs at 1 kHz started in the same millisecond share no ID but with a probability of
  // 1e-6; that is what this would catch failing every time.
  int overlapping = 0;
  for (int i = 0; i < 20; ++i) {
    const MessageIds x = make_message_ids(1'000'000, 100);
    const MessageIds y = make_message_ids(1'000'000, 100);
    overlapping += (x.base_ns - y.base_ns) % 1'000'000 == 0;
  }
  EXPECT_LT(overlapping, 2);
  for (uint64_t id : {0u, 1u, 99u}) EXPECT_EQ(a.id_of(a.stamp_ns(id)), id);
  EXPECT_FALSE(a.id_of(a.stamp_ns(100)).has_value());
}

TEST(RunUserData, RoundTripsAndToleratesOtherKeys) {
  const MessageIds ids{1700000000123456789, 1'000'000, 5000};
  const PeerRun run = parse_run_user_data("enclave=/;" + run_user_data("00ff", &ids));
  EXPECT_EQ(run.token, "00ff");
  ASSERT_TRUE(run.ids.has_value());
  EXPECT_EQ(run.ids->base_ns, ids.base_ns);
  EXPECT_EQ(run.ids->period_ns, ids.period_ns);
  EXPECT_EQ(run.ids->count, ids.count);
  EXPECT_FALSE(parse_run_user_data(run_user_data("abc")).ids.has_value());
  EXPECT_TRUE(parse_run_user_data("enclave=/;").token.empty());
  // Another process's malformed announcement is ignored, not trusted.
  EXPECT_FALSE(parse_run_user_data("robotperf_ids=1,0,5;").ids.has_value());
  EXPECT_FALSE(parse_run_user_data("robotperf_ids=1,2;").ids.has_value());
  EXPECT_FALSE(parse_run_user_data("robotperf_ids=1,2,3x;").ids.has_value());
}

rmw::PeerParticipant peer(const std::string& name, std::set<std::string> topics,
                          const std::string& user_data = "") {
  rmw::PeerParticipant p;
  p.name = name;
  p.topics = std::move(topics);
  p.user_data = user_data;
  return p;
}

std::vector<std::string> names(const std::vector<rmw::PeerParticipant>& peers) {
  std::vector<std::string> out;
  for (const auto& p : peers) out.push_back(p.name);
  return out;
}

TEST(OutsideGraph, AnExternalGraphsParticipantsAreItsOwnThroughItsTopics) {
  // A launched pipeline rectify -> resize between the run's input and output: both are the
  // graph's, the second through the topic it shares with the first, listed after it or not.
  const std::vector<rmw::PeerParticipant> peers{
      peer("resize", {"/rect", "/out"}), peer("rectify", {"/in", "/rect"}),
      peer("stranger", {"/chatter"}),    peer("another run", {"/in"}, "robotperf_run=00ff;"),
      peer("undiscovered", {}),
  };
  EXPECT_EQ(names(outside_graph(peers, {"/in", "/final"})),
            (std::vector<std::string>{"stranger", "another run", "undiscovered"}));
  EXPECT_EQ(names(outside_graph(peers, {"/out"})),
            (std::vector<std::string>{"stranger", "another run", "undiscovered"}));
  EXPECT_EQ(outside_graph(peers, {"/elsewhere"}).size(), peers.size());
}

}  // namespace
}  // namespace robotperf::harness
