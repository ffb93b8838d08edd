// Graph overhead of the manipulation kernels (d2-d6) and FCL vs Bullet on the same states.
// Run on demand: ./build/bench/manipulation/bench_manipulation [d2 d3 d4 d5 d6]
//
// 1. Each kernel's time inside the benchmark graph (intra, grey-box: the node's callback from
//    its input to its published answer, from the LTTng trace) against a direct call of the same
//    kernel code on the same requests, in the same order. Target (issue #9): overhead <= 10 % for
//    d2-d5, judged on p50; d6 (FK, about a microsecond) is for information. The end-to-end
//    latency from send (Playback -> kernel -> Monitor) is printed beside it. Both paths are paced
//    at the graph's rate with fresh input copies, so that they meet the same cache and scheduler
//    conditions. Without LTTng the node time is unavailable and only the end-to-end figure shows.
// 2. FCL and Bullet answer the collision dataset's states in a tight loop: time per query (mean,
//    p50, p99), and how often they agree with each other and with the sampled ground truth.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "robotperf/categories/builtin.hpp"
#include "robotperf/harness/benchmark_spec.hpp"
#include "robotperf/harness/dataset.hpp"
#include "robotperf/harness/run.hpp"
#include "robotperf/manipulation/collision.hpp"
#include "robotperf/manipulation/kinematics.hpp"
#include "robotperf/manipulation/pose_msgs.hpp"
#include "robotperf/msgs/geometry_msgs.hpp"
#include "robotperf/msgs/robotperf_msgs.hpp"
#include "robotperf/msgs/sensor_msgs.hpp"

using namespace robotperf;
namespace fs = std::filesystem;

namespace {

constexpr std::size_t kCount = 160;  // requests per kernel, warm-up included
constexpr std::size_t kWarmup = 10;
constexpr double kRateHz = 50;  // every kernel answers well within the 20 ms period
constexpr double kTargetRatio = 0.10;
constexpr int kCollisionPasses = 25;  // over the collision dataset, per backend

double percentile(std::vector<double> v, double p) {
  std::sort(v.begin(), v.end());
  const double at = p * static_cast<double>(v.size() - 1);
  const auto lo = static_cast<std::size_t>(at);
  const std::size_t hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (at - static_cast<double>(lo)) * (v[hi] - v[lo]);
}

double mean(const std::vector<double>& v) {
  double sum = 0;
  for (double x : v) sum += x;
  return sum / static_cast<double>(v.size());
}

// Request k of a stream, a fresh copy as the Playback sends it (the graph cycles the dataset).
template <class T>
std::shared_ptr<const T> fresh(const harness::DatasetStream& s, std::size_t k) {
  return std::make_shared<const T>(*static_cast<const T*>(s.messages[k % s.messages.size()].get()));
}

// Microseconds per call of `call(k)` for the measured requests, p50. Every request the graph gets
// is made here too, warm-up included and in the same order (IK restarts draw from one generator),
// paced at the graph's rate with `prepare(k)` (untimed) making fresh inputs first.
double direct_p50_us(const std::function<void(std::size_t)>& prepare,
                     const std::function<void(std::size_t)>& call) {
  std::vector<double> us;
  const auto period = std::chrono::duration<double>(1.0 / kRateHz);
  auto next = std::chrono::steady_clock::now();
  for (std::size_t k = 0; k < kCount; ++k) {
    next += std::chrono::duration_cast<std::chrono::steady_clock::duration>(period);
    std::this_thread::sleep_until(next);
    prepare(k);
    const auto start = std::chrono::steady_clock::now();
    call(k);
    const auto end = std::chrono::steady_clock::now();
    if (k >= kWarmup) us.push_back(std::chrono::duration<double, std::micro>(end - start).count());
  }
  return percentile(us, 0.5);
}

struct GraphTimes {
  std::optional<double> node_p50_us;  // grey-box: the kernel node's callback, input -> answer
  double end_to_end_p50_us = 0;       // from send to the Monitor
};

GraphTimes graph_times(const harness::BenchmarkSpec& spec) {
  harness::RunOptions o;
  o.rate_hz = kRateHz;
  o.count = kCount;
  o.warmup = kWarmup;
  o.mode = harness::RunMode::kGrey;
  o.trace_dir = fs::temp_directory_path() /
                ("robotperf-bench-manipulation-" + std::to_string(getpid()) + "-" + spec.id);
  GraphTimes t;
  std::optional<harness::RunResult> r;
  try {
    r = harness::run_benchmark(spec, o);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: grey-box run failed (%s); black-box only\n", spec.id.c_str(),
                 e.what());
    o.mode = harness::RunMode::kBlack;
    r = harness::run_benchmark(spec, o);
  }
  std::error_code ignored;
  fs::remove_all(o.trace_dir, ignored);
  if (r->matched + 5 < kCount - kWarmup)
    std::fprintf(stderr, "%s: only %zu of %zu outputs matched\n", spec.id.c_str(), r->matched,
                 kCount - kWarmup);
  t.end_to_end_p50_us = r->latency_from_sent.p50 / 1e3;
  if (r->grey) {
    for (const auto& hop : r->grey->hops)
      if (hop.kind == "node") t.node_p50_us = hop.duration.p50 / 1e3;
  }
  return t;
}

void report(const char* label, bool target_applies, double direct, const GraphTimes& g) {
  std::printf("%-36s %9.1f ", label, direct);
  if (g.node_p50_us) {
    const double ratio = (*g.node_p50_us - direct) / direct;
    std::printf("%9.1f %8.1f %%", *g.node_p50_us, 100 * ratio);
    if (target_applies) {
      std::printf("  ratio %5.2f %-9s", ratio / kTargetRatio,
                  ratio <= kTargetRatio ? "(met)" : "(NOT met)");
    } else {
      std::printf("  %-21s", "(information)");
    }
  } else {
    std::printf("%9s %10s  %-21s", "-", "-", "(no trace)");
  }
  std::printf(" %9.1f %9.1f %%\n", g.end_to_end_p50_us,
              100 * (g.end_to_end_p50_us - direct) / direct);
}

std::vector<double> positions(const harness::DatasetStream& states, std::size_t k) {
  return static_cast<const msgs::JointState*>(states.messages[k % states.messages.size()].get())
      ->position;
}

void kernel_overheads(const std::vector<std::string>& ids) {
  using manipulation::RobotModel;
  const RobotModel& arm = RobotModel::xarm6();
  std::printf(
      "Kernel time in the graph (intra, grey-box node p50) vs a direct call (p50), %zu requests "
      "at %.0f Hz, microseconds\n",
      kCount - kWarmup, kRateHz);
  std::printf("%-36s %9s %9s %10s  %-21s %9s %10s\n", "kernel", "direct", "in graph", "overhead",
              "target <= 10 %", "end2end", "overhead");
  for (const std::string& id : ids) {
    const harness::BenchmarkSpec spec = harness::find_benchmark(ROBOTPERF_BENCHMARKS_DIR, id);
    const harness::Dataset d = harness::load_dataset(spec.dataset, spec.workload);
    const std::string label = id + " " + spec.nodes.front().kernel;
    double direct = 0;
    const std::string kernel = spec.nodes.front().kernel;
    if (kernel != "manipulation/collision_fcl" && kernel != "manipulation/collision_bullet" &&
        kernel != "manipulation/ik_kdl" && kernel != "manipulation/ik_lma" &&
        kernel != "manipulation/forward_kinematics")
      throw std::invalid_argument(id + " is not one of d2-d6 (its kernel is " + kernel + ")");
    if (kernel == "manipulation/collision_fcl" || kernel == "manipulation/collision_bullet") {
      auto checker = manipulation::make_collision_checker(
          kernel == "manipulation/collision_fcl" ? manipulation::CollisionBackend::kFcl
                                                 : manipulation::CollisionBackend::kBullet,
          arm, manipulation::default_scene());
      const auto& states = d.stream("joint_states");
      std::shared_ptr<const msgs::JointState> state;
      direct = direct_p50_us([&](std::size_t k) { state = fresh<msgs::JointState>(states, k); },
                             [&](std::size_t) { checker->check(state->position.data()); });
    } else if (kernel == "manipulation/ik_kdl" || kernel == "manipulation/ik_lma") {
      // The options of the benchmark's graph.yaml, as the node reads them.
      manipulation::IkOptions options;
      options.solver = kernel == "manipulation/ik_kdl"
                           ? manipulation::IkSolver::kNewtonRaphsonJL
                           : manipulation::IkSolver::kLevenbergMarquardt;
      const plugin::KernelConfig c = harness::kernel_config(spec.nodes.front(), spec.workload);
      options.eps = c.parameters.get_double("eps");
      options.max_iterations = static_cast<unsigned>(c.parameters.get_int("max_iterations"));
      options.timeout_s = c.parameters.get_double("timeout_s");
      options.seed = static_cast<uint64_t>(c.parameters.get_int("seed"));
      manipulation::InverseKinematics ik(arm, options);
      const std::vector<double> seed_state(arm.dof(), 0.0);
      const auto& poses = d.stream("poses");
      std::shared_ptr<const msgs::PoseStamped> pose;
      direct = direct_p50_us(
          [&](std::size_t k) { pose = fresh<msgs::PoseStamped>(poses, k); },
          [&](std::size_t) { ik.solve(manipulation::isometry_of(pose->pose), seed_state); });
    } else {
      manipulation::ForwardKinematics fk(arm);
      const auto& states = d.stream("joint_states");
      std::shared_ptr<const msgs::JointState> state;
      direct = direct_p50_us([&](std::size_t k) { state = fresh<msgs::JointState>(states, k); },
                             [&](std::size_t) { fk.tip_pose(state->position.data()); });
    }
    report(label.c_str(), id != "d6", direct, graph_times(spec));
  }
}

void fcl_vs_bullet() {
  using manipulation::RobotModel;
  const harness::BenchmarkSpec spec = harness::find_benchmark(ROBOTPERF_BENCHMARKS_DIR, "d2");
  const harness::Dataset d = harness::load_dataset(spec.dataset, spec.workload);
  const auto& states = d.stream("joint_states");
  const auto& truth = d.stream("truth");
  const std::size_t n = states.messages.size();
  auto fcl = manipulation::make_fcl_checker(RobotModel::xarm6(), manipulation::default_scene());
  auto bullet =
      manipulation::make_bullet_checker(RobotModel::xarm6(), manipulation::default_scene());
  std::vector<double> fcl_us, bullet_us;
  std::size_t agree = 0, fcl_truth = 0, bullet_truth = 0, colliding = 0;
  auto timed = [](manipulation::CollisionChecker& c, const double* q, std::vector<double>& us) {
    const auto start = std::chrono::steady_clock::now();
    const bool hit = c.check(q).in_collision;
    us.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start)
                     .count());
    return hit;
  };
  for (int pass = 0; pass < kCollisionPasses; ++pass) {
    for (std::size_t k = 0; k < n; ++k) {
      const std::vector<double> q = positions(states, k);
      // Alternate which backend goes first, so that neither always meets the other's caches.
      bool f, b;
      if ((k + static_cast<std::size_t>(pass)) % 2) {
        f = timed(*fcl, q.data(), fcl_us);
        b = timed(*bullet, q.data(), bullet_us);
      } else {
        b = timed(*bullet, q.data(), bullet_us);
        f = timed(*fcl, q.data(), fcl_us);
      }
      if (pass > 0) continue;
      const bool t =
          static_cast<const msgs::CollisionResult*>(truth.messages[k].get())->in_collision;
      agree += f == b;
      fcl_truth += f == t;
      bullet_truth += b == t;
      colliding += t;
    }
  }
  std::printf(
      "\nFCL vs Bullet on d2's %zu states (%zu in collision by the sampled ground truth), %d "
      "passes, microseconds per query\n",
      n, colliding, kCollisionPasses);
  std::printf("%-8s %9s %9s %9s %18s\n", "backend", "mean", "p50", "p99", "agrees with truth");
  std::printf("%-8s %9.1f %9.1f %9.1f %17.1f %%\n", "fcl", mean(fcl_us), percentile(fcl_us, 0.5),
              percentile(fcl_us, 0.99),
              100.0 * static_cast<double>(fcl_truth) / static_cast<double>(n));
  std::printf("%-8s %9.1f %9.1f %9.1f %17.1f %%\n", "bullet", mean(bullet_us),
              percentile(bullet_us, 0.5), percentile(bullet_us, 0.99),
              100.0 * static_cast<double>(bullet_truth) / static_cast<double>(n));
  std::printf("FCL and Bullet agree on %.1f %% of the states; Bullet/FCL time (p50): %.2fx\n",
              100.0 * static_cast<double>(agree) / static_cast<double>(n),
              percentile(bullet_us, 0.5) / percentile(fcl_us, 0.5));
}

}  // namespace

int main(int argc, char** argv) {
  robotperf::categories::register_builtin_categories();
  std::vector<std::string> ids(argv + 1, argv + argc);
  if (ids.empty()) ids = {"d2", "d3", "d4", "d5", "d6"};
  try {
    kernel_overheads(ids);
    fcl_vs_bullet();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_manipulation: %s\n", e.what());
    return 1;
  }
  return 0;
}
