// Graph overhead of the a3 and a4 kernels: each kernel's latency inside the benchmark graph
// (black-box, intra transport: Playback -> pairing -> kernel -> Monitor) against a direct call
// of the same code on the same frames. Run on demand: ./build/bench/perception/bench_perception
//
// Target (issue #7): graph overhead <= 10 % of the kernel time on intra, judged on p50.
// The graph runs at 10 Hz so that no frame queues behind the previous one.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <thread>
#include <vector>

#include "robotperf/harness/dataset.hpp"
#include "robotperf/harness/run.hpp"
#include "robotperf/kernels/depth_image_proc.hpp"
#include "robotperf/kernels/stereo_image_proc.hpp"
#include "robotperf/msgs/stereo_msgs.hpp"

using namespace robotperf;

namespace {

constexpr std::size_t kCalls = 60;
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

// Milliseconds per call of `call(k)` for k = 0 .. kCalls-1, after a few warm-up calls. Calls are
// paced at the graph's 10 Hz and `prepare(k)` makes fresh inputs before each (untimed), as the
// Playback does, so that both paths meet the same cache and scheduler conditions.
template <class P, class F>
double direct_p50_ms(P&& prepare, F&& call) {
  std::vector<double> ms;
  for (std::size_t k = 0; k < kCalls + 3; ++k) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    prepare(k);
    const auto start = std::chrono::steady_clock::now();
    call(k);
    if (k >= 3) {
      ms.push_back(
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
              .count());
    }
  }
  return median(ms);
}

double graph_p50_ms(const char* id) {
  const auto spec = harness::find_benchmark(ROBOTPERF_BENCHMARKS_DIR, id);
  harness::RunOptions o;
  o.rate_hz = 10;
  o.count = kCalls + 5;
  o.warmup = 5;
  const auto r = harness::run_benchmark(spec, o);
  if (r.matched < kCalls)
    std::fprintf(stderr, "%s: only %zu of %zu outputs matched\n", id, r.matched, kCalls);
  return r.latency_from_sent.p50 / 1e6;
}

void report(const char* label, double direct, double graph) {
  const double overhead = graph - direct;
  const double ratio = overhead / direct;
  std::printf("%-34s %10.3f %10.3f %10.3f %9.1f %%   target <= %.0f %%: ratio %.2f %s\n", label,
              direct, graph, overhead, 100 * ratio, 100 * kTargetRatio, ratio / kTargetRatio,
              ratio <= kTargetRatio ? "(met)" : "(NOT met)");
}

}  // namespace

int main() {
  std::printf(
      "Kernel time in the graph (intra, black-box p50 from send) vs a direct call (p50), "
      "%zu frames\n",
      kCalls);
  std::printf("%-34s %10s %10s %10s %10s\n", "kernel", "direct ms", "graph ms", "overhead",
              "share");

  {
    const harness::Dataset d = harness::load_dataset("perception/stereo");
    kernels::DisparityProcessor bm;  // stereo_image_proc defaults, as a3's graph.yaml
    msgs::DisparityImage out;        // reused, as the node reuses its output once released
    std::shared_ptr<const msgs::Image> left, right;
    std::shared_ptr<const msgs::CameraInfo> left_info, right_info;
    const double direct = direct_p50_ms(
        [&](std::size_t k) {
          left = fresh<msgs::Image>(d, "left_image", k);
          right = fresh<msgs::Image>(d, "right_image", k);
          left_info = fresh<msgs::CameraInfo>(d, "left_camera_info", k);
          right_info = fresh<msgs::CameraInfo>(d, "right_camera_info", k);
        },
        [&](std::size_t) { bm.compute(*left, *right, *left_info, *right_info, out); });
    report("a3 stereo_image_proc/disparity", direct, graph_p50_ms("a3"));
  }
  {
    const harness::Dataset d = harness::load_dataset("perception/depth");
    std::shared_ptr<const msgs::Image> depth, image;
    std::shared_ptr<const msgs::CameraInfo> info;
    msgs::PointCloud2 cloud;  // reused, as the node reuses its output once released
    const double direct = direct_p50_ms(
        [&](std::size_t k) {
          depth = fresh<msgs::Image>(d, "depth", k);
          image = fresh<msgs::Image>(d, "image", k);
          info = fresh<msgs::CameraInfo>(d, "camera_info", k);
        },
        [&](std::size_t) { kernels::point_cloud_xyzrgb(*depth, *image, *info, {}, cloud); });
    report("a4 depth_image_proc/xyzrgb", direct, graph_p50_ms("a4"));
  }
  return 0;
}
