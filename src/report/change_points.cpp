#include "robotperf/report/change_points.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <stdexcept>

#include "robotperf/metrics/latency_stats.hpp"

namespace robotperf::report {

namespace {

// Sums and counts of the values seen so far, indexed by rank: the distance of a new value to all
// of them in O(log n).
class RankedSums {
 public:
  explicit RankedSums(std::size_t ranks) : count_(ranks + 1, 0), sum_(ranks + 1, 0) {}
  void clear() {
    std::fill(count_.begin(), count_.end(), 0);
    std::fill(sum_.begin(), sum_.end(), 0);
    total_count_ = total_sum_ = 0;
  }
  void add(std::size_t rank, double value) {
    for (std::size_t i = rank + 1; i < count_.size(); i += i & (~i + 1)) {
      count_[i] += 1;
      sum_[i] += value;
    }
    ++total_count_;
    total_sum_ += value;
  }
  // The sum of |value - v| over the values v added so far.
  double distance_to(std::size_t rank, double value) const {
    double below_count = 0, below_sum = 0;  // ranks <= rank
    for (std::size_t i = rank + 1; i > 0; i -= i & (~i + 1)) {
      below_count += count_[i];
      below_sum += sum_[i];
    }
    return (value * below_count - below_sum) +
           ((total_sum_ - below_sum) - value * (total_count_ - below_count));
  }

 private:
  std::vector<double> count_, sum_;
  double total_count_ = 0, total_sum_ = 0;
};

// A segment's values with what does not change when they are shuffled: their ranks, each one's
// distance to all the others, and the sum of the distances of every pair.
struct Segment {
  std::vector<double> values;
  std::vector<std::size_t> rank;  // of each value among the sorted values (the first equal one)
  std::vector<double> to_all;     // sum over j of |values[i] - values[j]|
  double every_pair = 0;

  explicit Segment(std::vector<double> v) : values(std::move(v)) {
    const std::size_t n = values.size();
    std::vector<double> sorted(values);
    std::sort(sorted.begin(), sorted.end());
    std::vector<double> prefix(n + 1, 0);
    for (std::size_t i = 0; i < n; ++i) prefix[i + 1] = prefix[i] + sorted[i];
    for (std::size_t i = 0; i < n; ++i)
      every_pair += sorted[i] * (2.0 * static_cast<double>(i) - static_cast<double>(n) + 1);
    for (double x : values) {
      rank.push_back(static_cast<std::size_t>(std::lower_bound(sorted.begin(), sorted.end(), x) -
                                              sorted.begin()));
      const auto above = static_cast<std::size_t>(
          std::upper_bound(sorted.begin(), sorted.end(), x) - sorted.begin());
      to_all.push_back((x * static_cast<double>(above) - prefix[above]) +
                       ((prefix[n] - prefix[above]) - x * static_cast<double>(n - above)));
    }
  }
};

struct Split {
  std::size_t at = 0;  // within the segment; 0 when the segment has no admissible split
  double statistic = -1;
};

// The split of the segment's values, taken in `order`, maximising
// Q(tau) = m k / n * (2/(m k) B - W_L / C(m,2) - W_R / C(k,2)), where m = tau and k = n - tau are
// the sides' sizes, B the sum of distances between the sides and W the sums within each side
// (Matteson & James 2014, alpha = 1). One pass moves each value from the right side to the left,
// updating the three sums; `left` is scratch space.
Split best_split(const Segment& segment, const std::vector<std::size_t>& order,
                 std::size_t min_segment, RankedSums& left) {
  const std::size_t n = order.size();
  Split best;
  if (n < 2 * min_segment) return best;
  left.clear();
  double within_left = 0, within_right = segment.every_pair, between = 0;
  for (std::size_t tau = 0; tau < n; ++tau) {
    if (tau >= min_segment && n - tau >= min_segment) {
      const double m = static_cast<double>(tau), k = static_cast<double>(n - tau);
      const double q = m * k / static_cast<double>(n) *
                       (2 * between / (m * k) - 2 * within_left / (m * (m - 1)) -
                        2 * within_right / (k * (k - 1)));
      if (q > best.statistic) best = {tau, q};
    }
    const std::size_t i = order[tau];
    const double v = segment.values[i];
    const double to_left = left.distance_to(segment.rank[i], v);
    const double to_right = segment.to_all[i] - to_left;
    within_left += to_left;
    within_right -= to_right;
    between += to_right - to_left;
    left.add(segment.rank[i], v);
  }
  return best;
}

std::vector<std::size_t> identity(std::size_t n) {
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), std::size_t{0});
  return order;
}

}  // namespace

double ChangePoint::change_percent() const {
  if (before == 0) return std::nan("");
  return (after - before) / std::abs(before) * 100;
}

std::vector<ChangePoint> change_points(const std::vector<double>& values,
                                       const ChangePointOptions& options) {
  if (options.min_segment < 2) throw std::invalid_argument("change_points: min_segment below 2");
  if (options.significance * static_cast<double>(options.permutations + 1) < 1)
    throw std::invalid_argument("change_points: too few permutations for that significance");
  for (double v : values) {
    if (!std::isfinite(v)) throw std::invalid_argument("change_points: a value is not finite");
  }
  // Segment boundaries: [bounds[i], bounds[i + 1]).
  std::vector<std::size_t> bounds{0, values.size()};
  std::vector<std::pair<std::size_t, double>> found;  // (index, p-value)
  std::mt19937_64 random(options.seed);
  auto segment = [&](std::size_t i) {
    return std::vector<double>(values.begin() + static_cast<std::ptrdiff_t>(bounds[i]),
                               values.begin() + static_cast<std::ptrdiff_t>(bounds[i + 1]));
  };
  while (true) {
    // The best split over all segments (E-divisive's iteration).
    std::vector<Segment> segments;
    for (std::size_t i = 0; i + 1 < bounds.size(); ++i) segments.emplace_back(segment(i));
    std::vector<RankedSums> scratch;  // one per segment, as large as it
    for (const Segment& seg : segments) scratch.emplace_back(seg.values.size());
    std::size_t chosen = 0;
    Split best;
    for (std::size_t i = 0; i < segments.size(); ++i) {
      const Split s = best_split(segments[i], identity(segments[i].values.size()),
                                 options.min_segment, scratch[i]);
      if (s.at > 0 && s.statistic > best.statistic) {
        best = s;
        chosen = i;
      }
    }
    if (best.at == 0) break;
    // Its significance: how often the best split of the segments, each shuffled within itself,
    // is as large. Stops as soon as the p-value can no longer reach the significance level.
    const auto allowed = static_cast<std::size_t>(
        std::floor(options.significance * static_cast<double>(options.permutations + 1)));
    std::vector<std::vector<std::size_t>> orders;
    for (const Segment& seg : segments) orders.push_back(identity(seg.values.size()));
    std::size_t as_large = 0, done = 0;
    for (; done < options.permutations && as_large + 1 <= allowed; ++done) {
      double largest = -1;
      for (std::size_t i = 0; i < segments.size(); ++i) {
        std::shuffle(orders[i].begin(), orders[i].end(), random);
        largest = std::max(
            largest, best_split(segments[i], orders[i], options.min_segment, scratch[i]).statistic);
      }
      // A tolerance: a shuffle that leaves the series as it was gives the same statistic.
      if (largest >= best.statistic * (1 - 1e-12)) ++as_large;
    }
    const double p = static_cast<double>(as_large + 1) / static_cast<double>(done + 1);
    if (as_large + 1 > allowed || p > options.significance) break;
    const std::size_t at = bounds[chosen] + best.at;
    found.emplace_back(at, p);
    bounds.insert(bounds.begin() + static_cast<std::ptrdiff_t>(chosen) + 1, at);
  }
  std::sort(found.begin(), found.end());
  std::vector<ChangePoint> out;
  for (const auto& [at, p] : found) {
    const auto i =
        static_cast<std::size_t>(std::find(bounds.begin(), bounds.end(), at) - bounds.begin());
    ChangePoint c;
    c.index = at;
    c.p_value = p;
    c.before = metrics::median(segment(i - 1));
    c.after = metrics::median(segment(i));
    out.push_back(c);
  }
  return out;
}

}  // namespace robotperf::report
