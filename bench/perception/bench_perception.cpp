// Graph overhead of the a3 and a4 kernels: each kernel's latency inside the benchmark graph
// (black-box, intra transport: Playback -> pairing -> kernel -> Monitor) against a direct call
// of the same code on the same frames. Run on demand: ./build/bench/perception/bench_perception
//
// Target (issue #7): graph overhead <= 10 % of the kernel time on intra, judged on p50.
// The graph runs at 10 Hz so that no frame queues behind the previous one, and the direct calls
// run in the same process between its frames, half a period after each send: both sides meet the
// same load from other processes, which on a shared machine comes and goes within seconds.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <memory>
#include <optional>
#include <thread>
#include <vector>

#include "robotperf/categories/builtin.hpp"
#include "robotperf/harness/dataset.hpp"
#include "robotperf/harness/run.hpp"
#include "robotperf/metrics/latency_stats.hpp"
#include "robotperf/msgs/stereo_msgs.hpp"
#include "robotperf/perception/depth_image_proc.hpp"
#include "robotperf/perception/stereo_image_proc.hpp"
#include "robotperf/sysinfo/run_rules.hpp"

using namespace robotperf;

namespace {

using Clock = std::chrono::steady_clock;

constexpr std::size_t kFrames = 80;  // measured, after warm-up
constexpr std::size_t kWarmup = 5;
constexpr auto kPeriod = std::chrono::milliseconds(100);  // 10 Hz
// How long before its send the Playback prepares a message, at least (black_box.cpp).
constexpr auto kPrepareLead = std::chrono::milliseconds(2);
constexpr double kTargetRatio = 0.10;

// A fresh copy of frame k of a stream, as the Playback sends it.
template <class T>
std::shared_ptr<const T> fresh(const harness::Dataset& d, const char* stream, std::size_t k) {
  const auto& s = d.stream(stream);
  return std::make_shared<const T>(*static_cast<const T*>(s.messages[k % s.messages.size()].get()));
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : (v[n / 2 - 1] + v[n / 2]) / 2;
}

// How far apart two p50s may be by chance: the wider half of the two medians' distribution-free
// 95 % intervals, relative to the direct call's p50 (NaN when an interval has no end).
double noise_band(const std::vector<double>& direct, const std::vector<double>& graph) {
  double band = 0;
  for (const auto* side : {&direct, &graph}) {
    const metrics::SampleStats s = metrics::compute_stats(*side);
    band = std::max(band, (s.p50_ci.upper - s.p50_ci.lower) / 2);
  }
  return band / median(direct);
}

void report(const char* label, const std::vector<double>& direct_ms,
            const std::vector<double>& graph_ms, std::optional<double> other_load) {
  const double direct = median(direct_ms), graph = median(graph_ms);
  const double overhead = graph - direct;
  const double ratio = overhead / direct;
  const double band = noise_band(direct_ms, graph_ms);
  // The graph does the direct call's work and more: a graph faster beyond the noise means the
  // reference does different or colder work, and the verdict would say nothing.
  const char* verdict = !(ratio >= -band)       ? "(BENCH DEFECT: the graph is faster than its "
                                                  "reference beyond the noise)"
                        : ratio <= kTargetRatio ? "(met)"
                                                : "(NOT met)";
  std::printf(
      "%-34s %10.3f %10.3f %10.3f %9.1f %%   noise +-%.1f %%   target <= %.0f %%: ratio "
      "%.2f %s\n",
      label, direct, graph, overhead, 100 * ratio, 100 * band, 100 * kTargetRatio,
      ratio / kTargetRatio, verdict);
  // Woken threads wait for a core while other processes hold both: the hand-offs of the graph
  // then cost what the scheduler makes them cost, and the figure says little about the runtime.
  if (other_load && *other_load > sysinfo::kBusyThresholdPercent) {
    std::printf("%-34s other processes used %.0f %% of a core meanwhile: not a quiet machine\n", "",
                *other_load);
  }
}

// Runs benchmark `id` on intra and, half a period after each of its sends, `call(k)` directly.
// Before each direct call, `prepare(k)` makes fresh inputs (untimed) on another thread and
// kPrepareLead ahead, as the Playback does: inputs just written by the calling thread would leave
// its cache full of dirty lines for the kernel to evict, a cost the graph's kernel does not meet.
template <class P, class F>
void compare(const char* label, const char* id, P&& prepare, F&& call) {
  const auto spec = harness::find_benchmark(ROBOTPERF_BENCHMARKS_DIR, id);
  std::atomic<Clock::rep> first_send{0};
  harness::RunOptions o;
  o.rate_hz = 10;
  o.count = kWarmup + kFrames;
  o.warmup = kWarmup;
  o.progress = [&](std::size_t sent, std::size_t, std::size_t) {
    if (sent == 1) first_send = Clock::now().time_since_epoch().count();
  };

  std::vector<double> direct;
  std::thread direct_caller([&] {
    while (first_send == 0) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    const Clock::time_point first{Clock::duration(first_send.load())};
    for (std::size_t k = 0; k < kWarmup + kFrames; ++k) {
      const auto call_at = first + k * kPeriod + kPeriod / 2;
      std::this_thread::sleep_until(call_at - kPrepareLead);
      std::thread([&] { prepare(k); }).join();
      std::this_thread::sleep_until(call_at);
      const auto start = Clock::now();
      call(k);
      const std::chrono::duration<double, std::milli> took = Clock::now() - start;
      if (k >= kWarmup) direct.push_back(took.count());
    }
  });
  const auto r = harness::run_benchmark(spec, o);
  direct_caller.join();

  if (r.matched < kFrames)
    std::fprintf(stderr, "%s: only %zu of %zu outputs matched\n", id, r.matched, kFrames);
  std::vector<double> graph;
  for (const auto& rec : r.records) {
    if (!rec.warmup && rec.received_ns >= 0)
      graph.push_back(static_cast<double>(rec.received_ns - rec.sent_ns) / 1e6);
  }
  report(label, direct, graph, r.resources.other_cpu_percent);
}

}  // namespace

int main() {
  robotperf::categories::register_builtin_categories();
  std::printf(
      "Kernel time in the graph (intra, black-box p50 from send) vs a direct call (p50), "
      "%zu frames at 10 Hz\n",
      kFrames);
  std::printf("%-34s %10s %10s %10s %10s\n", "kernel", "direct ms", "graph ms", "overhead",
              "share");

  {
    const harness::Dataset d = harness::load_dataset("perception/stereo");
    perception::DisparityProcessor bm;  // stereo_image_proc defaults, as a3's graph.yaml
    msgs::DisparityImage out;           // reused, as the node reuses its output once released
    std::shared_ptr<const msgs::Image> left, right;
    std::shared_ptr<const msgs::CameraInfo> left_info, right_info;
    compare(
        "a3 stereo_image_proc/disparity", "a3",
        [&](std::size_t k) {
          left = fresh<msgs::Image>(d, "left_image", k);
          right = fresh<msgs::Image>(d, "right_image", k);
          left_info = fresh<msgs::CameraInfo>(d, "left_camera_info", k);
          right_info = fresh<msgs::CameraInfo>(d, "right_camera_info", k);
        },
        [&](std::size_t) { bm.compute(*left, *right, *left_info, *right_info, out); });
  }
  {
    const harness::Dataset d = harness::load_dataset("perception/depth");
    std::shared_ptr<const msgs::Image> depth, image;
    std::shared_ptr<const msgs::CameraInfo> info;
    msgs::PointCloud2 cloud;  // reused, as the node reuses its output once released
    compare(
        "a4 depth_image_proc/xyzrgb", "a4",
        [&](std::size_t k) {
          depth = fresh<msgs::Image>(d, "depth", k);
          image = fresh<msgs::Image>(d, "image", k);
          info = fresh<msgs::CameraInfo>(d, "camera_info", k);
        },
        [&](std::size_t) { perception::point_cloud_xyzrgb(*depth, *image, *info, {}, cloud); });
  }
  return 0;
}
