// The harness's own overhead: latency added by Playback + transport + Monitor
// around a null graph. Run on demand: ./build/bench/harness/bench_harness
//
//   machine floor:           one thread wakes another (a condition variable), nothing else
//   intra, one process:      Playback -> Monitor on the same topic (no node)
//   intra, Monitor spinning: the same with --monitor-wait spin: no wake-up, one core kept busy
//   fastdds, one process:    Playback -> Monitor through Fast DDS
//   fastdds, inter-process:  Playback -> relay node in its own process -> Monitor
//
// Targets (issue #21): intra p50 <= 5 us and p99 <= 20 us at 1 kHz. A message from the Playback
// reaches the Monitor through one thread wake-up, so the machine's own wake-up latency at the same
// rate is measured first and printed beside: the harness's cost is its figure over that floor.
// A spinning Monitor takes the wake-up out: its figure is the harness's own cost alone.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <thread>
#include <vector>

#include "bench_start.hpp"
#include "robotperf/harness/run.hpp"
#include "robotperf/metrics/latency_stats.hpp"
#include "robotperf/rmw/transport.hpp"

namespace fs = std::filesystem;
using namespace robotperf;

namespace {

fs::path write_package(const fs::path& root, const std::string& name, bool with_relay) {
  const fs::path dir = root / "bench" / ("b_" + name);
  fs::create_directories(dir);
  std::ofstream(dir / "benchmark.yaml") << "id: b_" << name << "\nname: b_" << name << "\n";
  std::ofstream g(dir / "graph.yaml");
  g << "dataset: perception/image\ndrain_s: 2\n"
       "validity: {min_samples: 10, max_loss_percent: 0}\n"
       "inputs:\n  - {topic: /in, type: sensor_msgs/msg/CameraInfo, stream: camera_info}\n";
  if (with_relay) {
    g << "output: {topic: /out, type: sensor_msgs/msg/CameraInfo}\n"
         "nodes:\n  - name: relay\n    kernel: util/relay\n"
         "    parameters: {type: sensor_msgs/msg/CameraInfo}\n"
         "    topics: {input: /in, output: /out}\n";
  } else {
    g << "output: {topic: /in, type: sensor_msgs/msg/CameraInfo}\nnodes: []\n";
  }
  return dir;
}

constexpr double kRateHz = 1000;
constexpr std::size_t kMessages = 2000, kWarmup = 50;
constexpr double kTargetP50Us = 5, kTargetP99Us = 20;

struct Floor {
  double p50_us = 0, p99_us = 0;
};

// The machine floor: at the same rate, a thread stamps the time and wakes another through a
// condition variable, which reads the time again: what any hand-off between two threads costs
// here, before a harness does anything.
Floor machine_floor() {
  std::mutex mutex;
  std::condition_variable cv;
  int64_t stamped = 0;
  bool pending = false, done = false;
  std::vector<double> us;
  std::thread woken([&] {
    for (;;) {
      std::unique_lock lock(mutex);
      cv.wait(lock, [&] { return pending || done; });
      if (done) return;
      us.push_back(static_cast<double>(rmw::steady_now_ns() - stamped) / 1e3);
      pending = false;
    }
  });
  const auto period = std::chrono::nanoseconds(static_cast<int64_t>(1e9 / kRateHz));
  auto next = std::chrono::steady_clock::now() + std::chrono::milliseconds(10);
  for (std::size_t k = 0; k < kMessages + kWarmup; ++k) {
    next += period;
    std::this_thread::sleep_until(next);
    {
      std::lock_guard lock(mutex);
      stamped = rmw::steady_now_ns();
      pending = true;
    }
    cv.notify_one();
  }
  {
    std::lock_guard lock(mutex);
    done = true;
  }
  cv.notify_one();
  woken.join();
  us.erase(us.begin(), us.begin() + static_cast<long>(std::min(kWarmup, us.size())));
  const auto stats = metrics::compute_stats(us);
  return {stats.p50, stats.p99};
}

void report(const char* label, const harness::RunResult& r, const Floor& floor, bool targets) {
  const double p50 = r.latency_from_sent.p50 / 1e3;
  const double p99 = r.latency_from_sent.p99 / 1e3;
  std::printf("%-34s %6zu/%-6zu %10.1f %10.1f %8.2fx %8.2fx", label, r.matched, r.measured, p50,
              p99, p50 / floor.p50_us, p99 / floor.p99_us);
  if (targets) {
    std::printf("   targets p50 <= %.0f us: ratio %.2f %s, p99 <= %.0f us: ratio %.2f %s",
                kTargetP50Us, p50 / kTargetP50Us, p50 <= kTargetP50Us ? "(met)" : "(NOT met)",
                kTargetP99Us, p99 / kTargetP99Us, p99 <= kTargetP99Us ? "(met)" : "(NOT met)");
  }
  std::printf("\n");
}

}  // namespace

int main() {
  robotperf::bench::start_with_builtin_categories();
  const fs::path root =
      fs::temp_directory_path() / ("robotperf-bench-harness-" + std::to_string(getpid()));
  const int domain = rmw::reserved_domain();
  std::printf(
      "Harness overhead, null graph, sensor_msgs/CameraInfo payload, %zu messages at %.0f Hz, "
      "latency from the actual send\n",
      kMessages, kRateHz);
  std::printf("%-34s %13s %10s %10s %9s %9s\n", "path", "matched", "p50 (us)", "p99 (us)",
              "p50/floor", "p99/floor");
  const Floor floor = machine_floor();
  std::printf("%-34s %13s %10.1f %10.1f %9s %9s   (one condition-variable wake-up, nothing else)\n",
              "machine floor", "", floor.p50_us, floor.p99_us, "1.00x", "1.00x");

  harness::RunOptions o;
  o.load.count = kMessages + kWarmup;
  o.load.warmup = kWarmup;
  o.load.rate_hz = kRateHz;

  report("intra, one process",
         harness::run_benchmark(harness::load_benchmark(write_package(root, "intra", false)), o),
         floor, true);
  o.transport.monitor_wait = graph::WaitMode::kSpin;
  report(
      "intra, Monitor spinning",
      harness::run_benchmark(harness::load_benchmark(write_package(root, "intra_spin", false)), o),
      floor, true);
  o.transport.monitor_wait = graph::WaitMode::kSleep;

  o.transport.rmw = "fastdds";
  o.transport.domain_id = domain;
  report("fastdds, one process",
         harness::run_benchmark(harness::load_benchmark(write_package(root, "dds", false)), o),
         floor, false);

  o.processes.layout = harness::ProcessLayout::kPerNode;
  o.processes.node_command = {ROBOTPERF_EXECUTABLE, "node"};
  report("fastdds, relay in a 2nd process",
         harness::run_benchmark(harness::load_benchmark(write_package(root, "dds2", true)), o),
         floor, false);
  fs::remove_all(root);
  return 0;
}
