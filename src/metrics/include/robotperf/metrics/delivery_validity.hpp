// The rules docs/design.md §3.5-3.6 set on a run's message counts, and its rates, shared by
// black-box results and the grey-box trace analysis so that both judge and count a run alike.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "robotperf/metrics/latency_stats.hpp"

namespace robotperf::metrics {

struct DeliveryCounts {
  std::size_t matched = 0;  // measured messages whose output arrived
  std::size_t duplicates = 0;
  std::size_t unknown = 0;  // receptions with IDs that were never sent
  double loss_percent = 0;
};

// One reason per broken rule: too few samples, loss above the bound, duplicates, unknown IDs.
std::vector<std::string> delivery_invalid_reasons(const DeliveryCounts& counts,
                                                  std::size_t min_samples, double max_loss_percent);

// A send or reception of a measured message: when, and its input's deadline (the messages of a
// burst share one).
struct TimedEvent {
  int64_t deadline_ns;
  int64_t time_ns;
};

// The rate of a run's sends or receptions, in Hz. With the last deadline's k events last in
// time, the n - k others over the time from the first event to the first of those k: f for
// messages at f Hz one by one ((n - 1) / span) or in bursts of any size (where (n - 1) / span
// would count the last burst's time as none), and the rate of a graph that cannot keep up. A
// first burst cut short (the warm-up ended inside it) counts as whole, as its time does. 0 when
// that spans no time.
double event_rate_hz(std::span<const TimedEvent> events);

// A run's rates (event_rate_hz of its sends and of its receptions) and the window it measured
// them over: from the first measured send to the last reception, once two have come (else 0).
struct DeliveryRates {
  double offered_hz = 0;
  double output_hz = 0;
  double window_s = 0;
};
// `sends` in message order.
DeliveryRates delivery_rates(std::span<const TimedEvent> sends,
                             std::span<const TimedEvent> receptions);

// An output's jitter (docs/design.md §3.5): the intervals between consecutive arrivals (in time
// order; `arrival_ns` in any), and |interval - period| of each. Nanoseconds.
struct OutputJitter {
  SampleStats interval, jitter;
};
OutputJitter output_jitter(std::vector<int64_t> arrival_ns, double period_ns);

}  // namespace robotperf::metrics
