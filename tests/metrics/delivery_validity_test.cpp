// The rates a run reports, for sends and receptions one by one and in bursts.
#include "robotperf/metrics/delivery_validity.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace robotperf::metrics {
namespace {

constexpr int64_t kSecond = 1'000'000'000;

// `count` messages at `hz` in bursts of `burst` (1: one by one), each sent `spacing_ns` after the
// one before it in its burst.
std::vector<TimedEvent> sends(int count, double hz, int burst, int64_t spacing_ns) {
  std::vector<TimedEvent> events;
  const auto period = static_cast<int64_t>(kSecond / hz);
  for (int k = 0; k < count; ++k) {
    const int64_t deadline = (k / burst) * burst * period;
    events.push_back({deadline, deadline + (k % burst) * spacing_ns});
  }
  return events;
}

TEST(EventRate, MessagesOneByOneGiveTheirRate) {
  EXPECT_DOUBLE_EQ(event_rate_hz(sends(11, 10, 1, 0)), 10.0);
}

// (n - 1) / span gave 11 Hz for 100 messages at 10 Hz in bursts of 10: it counted the last
// burst's second as none.
TEST(EventRate, BurstsGiveTheirMeanRate) {
  EXPECT_NEAR(event_rate_hz(sends(100, 10, 10, 1000)), 10.0, 1e-3);
  EXPECT_NEAR(event_rate_hz(sends(120, 30, 4, 50'000)), 30.0, 1e-2);
  // The measured messages after a warm-up of 5 in bursts of 4 (the first burst holds 3 of
  // them), and a last burst cut short too.
  std::vector<TimedEvent> measured = sends(42, 100, 4, 1000);
  measured.erase(measured.begin(), measured.begin() + 5);
  EXPECT_NEAR(event_rate_hz(measured), 100.0, 0.1);
}

// A graph that answers every 0.2 s whatever comes in: its rate, not the input's.
TEST(EventRate, AnswersOfAGraphThatCannotKeepUpGiveItsRate) {
  std::vector<TimedEvent> receptions = sends(100, 10, 10, 0);
  for (std::size_t k = 0; k < receptions.size(); ++k)
    receptions[k].time_ns = static_cast<int64_t>(k) * kSecond / 5;
  EXPECT_NEAR(event_rate_hz(receptions), 5.0, 1e-9);
  // Out of order, the same.
  std::swap(receptions[3], receptions[70]);
  EXPECT_NEAR(event_rate_hz(receptions), 5.0, 1e-9);
}

TEST(EventRate, NoRateWithoutTwoDeadlinesOrTime) {
  EXPECT_EQ(event_rate_hz({}), 0.0);
  EXPECT_EQ(event_rate_hz(sends(1, 10, 1, 0)), 0.0);
  EXPECT_EQ(event_rate_hz(sends(8, 10, 8, 1000)), 0.0) << "one burst";
  EXPECT_EQ(event_rate_hz(std::vector<TimedEvent>{{0, 5}, {1, 5}}), 0.0) << "no time between";
}

// The window runs from the first measured send to the last reception, whichever came last.
TEST(DeliveryRates, WindowFromTheFirstSendToTheLastReception) {
  const std::vector<TimedEvent> sent = sends(11, 10, 1, 0);
  std::vector<TimedEvent> received = sent;
  for (auto& e : received) e.time_ns += 5'000'000;
  std::swap(received[2].time_ns, received[10].time_ns);
  const DeliveryRates rates = delivery_rates(sent, received);
  EXPECT_DOUBLE_EQ(rates.offered_hz, 10.0);
  EXPECT_NEAR(rates.window_s, 1.005, 1e-12);
  EXPECT_EQ(delivery_rates(sent, std::vector<TimedEvent>(received.begin(), received.begin() + 1))
                .window_s,
            0.0)
      << "one reception: no window";
}

}  // namespace
}  // namespace robotperf::metrics
