#include "overhead_verdict.hpp"

#include <algorithm>
#include <cmath>

#include "robotperf/metrics/latency_stats.hpp"

namespace robotperf::bench {

OverheadVerdict judge_overhead(const std::vector<OverheadRound>& rounds, double target_ratio) {
  OverheadVerdict v;
  std::vector<double> reference, graph;
  bool every_round_faster = !rounds.empty();
  v.round_low = INFINITY;
  v.round_high = -INFINITY;
  for (const auto& round : rounds) {
    reference.insert(reference.end(), round.reference.begin(), round.reference.end());
    graph.insert(graph.end(), round.graph.begin(), round.graph.end());
    const double r = metrics::compute_stats(round.reference).p50;
    const double ratio = (metrics::compute_stats(round.graph).p50 - r) / r;
    v.round_low = std::min(v.round_low, ratio);
    v.round_high = std::max(v.round_high, ratio);
    every_round_faster = every_round_faster && ratio < 0;
  }
  const metrics::SampleStats r = metrics::compute_stats(reference);
  const metrics::SampleStats g = metrics::compute_stats(graph);
  v.reference_p50 = r.p50;
  v.graph_p50 = g.p50;
  v.ratio = (g.p50 - r.p50) / r.p50;
  // An interval without an end (too few samples) is no evidence either way: no band.
  double half = 0;
  for (const auto* s : {&r, &g}) {
    const double h = (s->p50_ci.upper - s->p50_ci.lower) / 2;
    if (!std::isfinite(h) || !std::isfinite(half)) {
      half = NAN;
    } else {
      half = std::max(half, h);
    }
  }
  v.band = std::isfinite(half) ? std::max(half / r.p50, (v.round_high - v.round_low) / 2) : NAN;
  auto p10 = [](std::vector<double> x) {
    std::sort(x.begin(), x.end());
    return metrics::quantile_of_sorted(x, 0.10);
  };
  const double reference_floor = p10(reference);
  v.floor_ratio = (p10(graph) - reference_floor) / reference_floor;
  v.defect =
      std::isfinite(v.band) && v.ratio < -v.band && v.floor_ratio < -v.band && every_round_faster;
  v.met = !v.defect && v.ratio <= target_ratio;
  return v;
}

std::string verdict_text(const OverheadVerdict& v, bool target_applies) {
  if (v.defect) return "(BENCH DEFECT: the graph is faster than its reference beyond the noise)";
  if (!target_applies) return "(information)";
  return v.met ? "(met)" : "(NOT met)";
}

BenchOptions parse_bench_options(int argc, char** argv) {
  BenchOptions o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--smoke") {
      o.smoke = true;
    } else {
      o.args.push_back(a);
    }
  }
  return o;
}

}  // namespace robotperf::bench
