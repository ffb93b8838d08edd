#include "overhead_verdict.hpp"

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <stdexcept>

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
  if (!v.defect) {
    v.met = v.ratio + v.band <= target_ratio;
    v.undecided = !v.met && !(v.ratio - v.band > target_ratio);
  }
  return v;
}

std::string verdict_text(const OverheadVerdict& v, bool target_applies) {
  if (v.defect) return "(BENCH DEFECT: the graph is faster than its reference beyond the noise)";
  if (!target_applies) return "(information)";
  if (v.undecided) return "(undecided)";  // the band holds the target
  return v.met ? "(met)" : "(NOT met)";
}

BenchOptions parse_bench_options(int argc, char** argv) {
  BenchOptions o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--smoke") {
      o.smoke = true;
    } else if (a == "--confirm") {
      o.confirming = true;
    } else {
      o.args.push_back(a);
    }
  }
  return o;
}

bool confirm_defect(const std::vector<std::string>& command, int processes) {
  if (command.empty()) throw std::invalid_argument("confirm_defect: no command");
  std::vector<char*> args;
  for (const auto& a : command) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  for (int i = 1; i <= processes; ++i) {
    std::printf("suspected bench defect: measuring again in a fresh process (%d of %d)\n", i,
                processes);
    std::fflush(stdout);  // before the child's lines
    std::fflush(stderr);
    pid_t pid = 0;
    if (const int e = posix_spawn(&pid, args[0], nullptr, nullptr, args.data(), environ); e != 0)
      throw std::runtime_error("cannot start " + command[0] +
                               " to confirm a bench defect: " + std::to_string(e));
    int status = 0;
    while (waitpid(pid, &status, 0) < 0) {
      if (errno != EINTR) throw std::runtime_error("waitpid failed while confirming a defect");
    }
    if (WIFEXITED(status) && WEXITSTATUS(status) == 0) {
      std::printf("not confirmed: a fresh process found no defect\n");
      return false;
    }
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 1)
      throw std::runtime_error("the process confirming a bench defect failed (status " +
                               std::to_string(status) + ")");
  }
  std::printf("confirmed: %d fresh processes found the defect too\n", processes);
  return true;
}

std::vector<std::string> confirming_command(const BenchOptions& options, const std::string& id) {
  std::vector<std::string> command = {"/proc/self/exe"};
  if (options.smoke) command.emplace_back("--smoke");
  command.push_back(id);
  command.emplace_back("--confirm");
  return command;
}

bool confirm_defects(const BenchOptions& options, const std::vector<std::string>& suspected) {
  bool confirmed = false;
  for (const std::string& id : suspected) {
    std::printf("%s: ", id.c_str());
    confirmed = confirm_defect(confirming_command(options, id)) || confirmed;
  }
  return confirmed;
}

int run_overhead_bench(const BenchOptions& options, const std::string& bench,
                       const std::vector<std::string>& ids,
                       const std::function<bool(const std::string&)>& compare,
                       const std::function<void()>& after) {
  try {
    std::vector<std::string> suspected;
    for (const auto& id : ids)
      if (compare(id)) suspected.push_back(id);
    bool defect = !suspected.empty();
    if (defect && !options.confirming) defect = confirm_defects(options, suspected);
    if (after) after();
    return defect ? 1 : 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: %s\n", bench.c_str(), e.what());
    return 2;
  }
}

void print_overhead_columns() {
  std::printf("%-34s %10s %10s %10s %10s\n", "kernel", "reference", "graph", "overhead", "share");
}

void print_overhead_row(const std::string& label, const OverheadVerdict& v, double target_ratio) {
  std::printf(
      "%-34s %10.3f %10.3f %10.3f %9.1f %%   noise +-%.1f %% (rounds %+.1f..%+.1f %%, p10 "
      "%+.1f %%)   target <= %.0f %%: ratio %.2f %s\n",
      label.c_str(), v.reference_p50, v.graph_p50, v.graph_p50 - v.reference_p50, 100 * v.ratio,
      100 * v.band, 100 * v.round_low, 100 * v.round_high, 100 * v.floor_ratio, 100 * target_ratio,
      v.ratio / target_ratio, verdict_text(v, true).c_str());
}

}  // namespace robotperf::bench
