#include "robotperf/metrics/delivery_validity.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace robotperf::metrics {

std::vector<std::string> delivery_invalid_reasons(const DeliveryCounts& c, std::size_t min_samples,
                                                  double max_loss_percent) {
  std::vector<std::string> out;
  if (c.matched == 0 && c.unknown > 0) {
    // Not loss: the graph answered, but with stamps that are none of the inputs'.
    out.push_back(
        "all " + std::to_string(c.unknown) +
        " outputs carry a header.stamp that no input had: the graph does not copy its "
        "input's header into its output, and robotperf's message IDs travel in the "
        "stamp (see docs/guides/your-own-graphs.md, \"A node that does not copy the header\")");
    return out;
  }
  if (c.matched < min_samples) {
    out.push_back(std::to_string(c.matched) + " matched samples, fewer than the " +
                  std::to_string(min_samples) + " required");
  }
  if (c.loss_percent > max_loss_percent) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "%.2f %% lost, above the %.2f %% bound", c.loss_percent,
                  max_loss_percent);
    out.emplace_back(buf);
  }
  if (c.duplicates > 0) out.push_back(std::to_string(c.duplicates) + " duplicate receptions");
  if (c.unknown > 0)
    out.push_back(std::to_string(c.unknown) + " receptions with unknown message IDs");
  return out;
}

double event_rate_hz(std::span<const TimedEvent> events) {
  std::vector<int64_t> deadlines, times;
  deadlines.reserve(events.size());
  times.reserve(events.size());
  for (const TimedEvent& e : events) {
    deadlines.push_back(e.deadline_ns);
    times.push_back(e.time_ns);
  }
  std::ranges::sort(deadlines);
  // The events of each deadline: the first's, the last's, and a whole burst's (the most).
  std::size_t first_group = 0, last_group = 0, whole_group = 0;
  for (std::size_t i = 0; i < deadlines.size();) {
    std::size_t j = i;
    while (j < deadlines.size() && deadlines[j] == deadlines[i]) ++j;
    if (i == 0) first_group = j;
    last_group = j - i;
    whole_group = std::max(whole_group, j - i);
    i = j;
  }
  if (times.size() <= last_group) return 0;
  std::ranges::sort(times);
  const std::size_t before = times.size() - last_group;
  const int64_t span = times[before] - times.front();
  const std::size_t counted = before + (whole_group - first_group);
  return span > 0 ? static_cast<double>(counted) / (static_cast<double>(span) * 1e-9) : 0;
}

DeliveryRates delivery_rates(std::span<const TimedEvent> sends,
                             std::span<const TimedEvent> receptions) {
  DeliveryRates rates;
  rates.offered_hz = event_rate_hz(sends);
  rates.output_hz = event_rate_hz(receptions);
  if (receptions.size() >= 2 && !sends.empty()) {
    const int64_t last = std::ranges::max(receptions, {}, &TimedEvent::time_ns).time_ns;
    rates.window_s = static_cast<double>(last - sends.front().time_ns) * 1e-9;
  }
  return rates;
}

OutputJitter output_jitter(std::vector<int64_t> arrival_ns, double period_ns) {
  std::ranges::sort(arrival_ns);
  std::vector<double> intervals, jitter;
  for (std::size_t i = 1; i < arrival_ns.size(); ++i) {
    const auto interval = static_cast<double>(arrival_ns[i] - arrival_ns[i - 1]);
    intervals.push_back(interval);
    jitter.push_back(std::abs(interval - period_ns));
  }
  return {compute_stats(intervals), compute_stats(jitter)};
}

}  // namespace robotperf::metrics
