#include "robotperf/harness/peak_search.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "robotperf/metrics/delivery_validity.hpp"

namespace robotperf::harness {
namespace {

// The Playback itself must keep the rate: below this share of it, the step measured the Playback.
constexpr double kPlaybackKeepsUp = 0.95;
// Outputs slower than this share of the inputs mean a graph falling behind (ros2_benchmark's 5 %).
constexpr double kGraphKeepsUp = 0.95;
constexpr double kHighestRateHz = 1e6;  // a 1 us period, the Playback's limit
// Halving below the low rate stops here: a graph slower than this is not a throughput question.
constexpr int kMaxHalvings = 10;
constexpr int kMaxSteps = 40;

std::string text(double v, int precision = 4) {
  std::ostringstream out;
  out.precision(precision);
  out << v;
  return out.str();
}

// The q-th percentile (0-100) of the latency from the scheduled send, in ms; NaN without samples.
double latency_percentile_ms(const RunResult& r, double percentile) {
  std::vector<double> latencies = scheduled_latencies_ms(r);
  std::ranges::sort(latencies);
  return metrics::quantile_of_sorted(latencies, percentile / 100.0);
}

// The rate the schedule asked for over the measured messages, reckoned as the offered rate is:
// the nominal one for fixed arrivals, but a Poisson seed's own mean over a few hundred intervals
// lies 5-13 % off it, which a Playback hitting every deadline must not be failed for.
double scheduled_rate_hz(const RunResult& r) {
  std::vector<metrics::TimedEvent> deadlines;
  for (const auto& rec : r.records) {
    if (!rec.warmup) deadlines.push_back({rec.scheduled_ns, rec.scheduled_ns});
  }
  return metrics::event_rate_hz(deadlines);
}

}  // namespace

std::string peak_step_failure(const RunResult& r, const BenchmarkSpec& spec,
                              const PeakSearchOptions& search, double latency_ms) {
  if (!r.errors.empty()) return "run ended early: " + r.errors.front();
  if (r.duplicates > 0) return std::to_string(r.duplicates) + " duplicate receptions";
  if (r.unknown > 0) return std::to_string(r.unknown) + " receptions with unknown IDs";
  if (const double scheduled = scheduled_rate_hz(r);
      r.offered_rate_hz < kPlaybackKeepsUp * scheduled) {
    return "the Playback sent at only " + text(r.offered_rate_hz) + " Hz of the " +
           text(scheduled) + " Hz its schedule asked for: the harness, not the graph, is the " +
           "limit here";
  }
  const double loss_bound = search.loss_bound_percent.value_or(spec.max_loss_percent);
  if (r.loss_percent > loss_bound)
    return text(r.loss_percent, 3) + " % lost, above the " + text(loss_bound) + " % bound";
  if (r.matched < spec.min_samples)
    return std::to_string(r.matched) + " matched samples, fewer than the " +
           std::to_string(spec.min_samples) + " required";
  if (r.throughput_hz < kGraphKeepsUp * r.offered_rate_hz) {
    return "outputs came at " + text(r.throughput_hz) + " Hz, below " +
           text(100 * kGraphKeepsUp, 3) + " % of the " + text(r.offered_rate_hz) +
           " Hz offered: the graph fell behind";
  }
  if (search.latency_bound_ms && !(latency_ms <= *search.latency_bound_ms)) {
    return "p" + text(search.latency_percentile) + " latency " + text(latency_ms) +
           " ms, above the " + text(*search.latency_bound_ms) + " ms bound";
  }
  return {};
}

PeakSearchResult find_peak(const BenchmarkSpec& spec, const RunOptions& options,
                           const PeakSearchOptions& search,
                           const std::function<void(const PeakStep&)>& on_step) {
  if (search.loss_bound_percent &&
      !(*search.loss_bound_percent >= 0 && *search.loss_bound_percent < 100))
    throw std::invalid_argument("--loss-bound must be a percentage from 0 to below 100");
  if (search.latency_bound_ms &&
      !(*search.latency_bound_ms > 0 && std::isfinite(*search.latency_bound_ms)))
    throw std::invalid_argument("--latency-bound must be a positive number of ms");
  if (!(search.latency_percentile > 0 && search.latency_percentile <= 100))
    throw std::invalid_argument("--latency-percentile must be above 0 and at most 100");
  if (!(search.resolution_percent >= 0.1 && search.resolution_percent <= 100))
    throw std::invalid_argument("--peak-resolution must be from 0.1 to 100 percent");
  if (!(search.step_duration_s > 0 && std::isfinite(search.step_duration_s)))
    throw std::invalid_argument("--duration (per step) must be a positive number of seconds");
  if (options.load.bag_timeline)
    throw std::invalid_argument("--find-peak searches over fixed rates: not with --rate bag");
  if (options.load.count)
    throw std::invalid_argument("--find-peak sizes each step by --duration: not with --count");

  PeakSearchResult out;
  PeakSearchRecord& rec = out.record;
  rec.loss_bound_percent = search.loss_bound_percent.value_or(spec.max_loss_percent);
  rec.latency_bound_ms = search.latency_bound_ms;
  rec.latency_percentile = search.latency_percentile;
  rec.rate_low_hz = search.rate_low_hz.value_or(options.load.rate_hz.value_or(spec.rate_hz));
  rec.rate_high_hz = search.rate_high_hz.value_or(std::max(kHighestRateHz, rec.rate_low_hz));
  rec.resolution_percent = search.resolution_percent;
  rec.step_duration_s = search.step_duration_s;
  if (!(rec.rate_low_hz > 0) || !(rec.rate_high_hz >= rec.rate_low_hz) ||
      !std::isfinite(rec.rate_high_hz))
    throw std::invalid_argument("--rate-range LO:HI needs 0 < LO <= HI");

  // Runs one step; false when the search must end (an error or an interrupt).
  double passing = 0, failing = 0;
  std::string failing_reason;
  auto step = [&](double rate) {
    RunOptions o = options;
    o.load.rate_hz = rate;
    o.load.duration_s =
        search.step_duration_s + static_cast<double>(o.load.warmup.value_or(spec.warmup)) / rate;
    RunResult r;
    try {
      r = run_benchmark(spec, o);
    } catch (const RunInterrupted&) {
      // Before this step's timing began: the steps already measured stand.
      rec.stop_reason = "interrupted before the step at " + text(rate) + " Hz";
      return false;
    }
    PeakStep s;
    s.rate_hz = rate;
    s.offered_hz = r.offered_rate_hz;
    s.output_hz = r.throughput_hz;
    s.loss_percent = r.loss_percent;
    s.latency_ms = latency_percentile_ms(r, search.latency_percentile);
    s.reason = peak_step_failure(r, spec, search, s.latency_ms);
    s.passed = s.reason.empty();
    rec.steps.push_back(s);
    if (on_step) on_step(s);
    if (r.interrupted || !r.errors.empty()) {
      rec.stop_reason = "stopped at " + text(rate) + " Hz: " + s.reason;
      if (r.interrupted) rec.stop_reason = "interrupted at " + text(rate) + " Hz";
      return false;
    }
    if (s.passed) {
      if (rate > passing) {
        passing = rate;
        out.peak = std::move(r);
      }
    } else if (failing == 0 || rate < failing) {
      failing = rate;
      failing_reason = s.reason;
    }
    return true;
  };

  // Bracket: up from the low rate while it passes, or down while it fails.
  double rate = rec.rate_low_hz;
  bool going = step(rate);
  if (going && passing == 0) {
    // Down while a step still measures enough messages to be judged.
    for (int h = 0; h < kMaxHalvings && going && passing == 0 &&
                    rate / 2 * search.step_duration_s >= static_cast<double>(spec.min_samples);
         ++h)
      going = step(rate /= 2);
  } else {
    while (going && failing == 0 && rate < rec.rate_high_hz &&
           static_cast<int>(rec.steps.size()) < kMaxSteps)
      going = step(rate = std::min(rate * 2, rec.rate_high_hz));
  }
  // Bisect between the highest pass and the lowest fail.
  while (going && passing > 0 && failing > 0 &&
         failing - passing > passing * search.resolution_percent / 100.0 &&
         static_cast<int>(rec.steps.size()) < kMaxSteps)
    going = step((passing + failing) / 2);

  if (!going) {
    rec.finished = false;  // stop_reason says why
  } else if (passing == 0) {
    rec.stop_reason =
        "no rate down to " + text(rate) + " Hz met the bounds; the last: " + failing_reason;
  } else if (failing == 0) {
    rec.stop_reason = "the top of the range (" + text(rec.rate_high_hz) +
                      " Hz) met the bounds: the peak may be higher";
  } else {
    rec.stop_reason = "the next rate tried, " + text(failing) + " Hz, failed: " + failing_reason;
  }
  if (out.peak) {
    // An unfinished search's best run is one the graph sustained, not its peak: written as an
    // offered throughput, marked as the search was, with the search that found it.
    if (rec.finished) {
      out.peak->throughput_kind = "peak";
    } else {
      out.peak->interrupted = options.interrupted && options.interrupted->load() != 0;
      out.peak->warnings.push_back(
          {"peak_search_unfinished", "the peak search did not finish (" + rec.stop_reason +
                                         "): this rate was sustained; the peak may be higher"});
    }
    out.peak->peak_search = rec;
  }
  return out;
}

}  // namespace robotperf::harness
