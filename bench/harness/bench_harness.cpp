// The harness's own overhead: latency added by Playback + transport + Monitor
// around a null graph. Run on demand: ./build/bench/harness/bench_harness
//
//   intra, one process:      Playback -> Monitor on the same topic (no node)
//   fastdds, one process:    Playback -> Monitor through Fast DDS
//   fastdds, inter-process:  Playback -> relay node in its own process -> Monitor
//
// Target (issue #2): intra p50 <= 20 us.
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "robotperf/categories/builtin.hpp"
#include "robotperf/harness/run.hpp"
#include "robotperf/rmw/transport.hpp"

namespace fs = std::filesystem;
using namespace robotperf;

namespace {

fs::path write_package(const fs::path& root, const std::string& name, bool with_relay) {
  const fs::path dir = root / "bench" / ("b_" + name);
  fs::create_directories(dir);
  std::ofstream(dir / "benchmark.yaml") << "id: b_" << name << "\nname: b_" << name << "\n";
  std::ofstream g(dir / "graph.yaml");
  g << "dataset: perception/image\nwarmup: 50\ndrain_s: 2\n"
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

void report(const char* label, const harness::RunResult& r, double target_p50_us) {
  const double p50 = r.latency_from_sent.p50 / 1e3;
  const double p99 = r.latency_from_sent.p99 / 1e3;
  std::printf("%-34s %6zu/%-6zu %10.1f %10.1f", label, r.matched, r.measured, p50, p99);
  if (target_p50_us > 0) {
    std::printf("   target p50 <= %.0f us: ratio %.2f %s", target_p50_us, p50 / target_p50_us,
                p50 <= target_p50_us ? "(met)" : "(NOT met)");
  }
  std::printf("\n");
}

}  // namespace

int main() {
  robotperf::categories::register_builtin_categories();
  const fs::path root =
      fs::temp_directory_path() / ("robotperf-bench-harness-" + std::to_string(getpid()));
  const int domain = rmw::reserved_domain();
  std::printf(
      "Harness overhead, null graph, sensor_msgs/CameraInfo payload, 1000 messages at 500 Hz\n");
  std::printf("%-34s %13s %10s %10s\n", "path", "matched", "p50 (us)", "p99 (us)");

  harness::RunOptions o;
  o.count = 1050;
  o.rate_hz = 500;

  report("intra, one process",
         harness::run_benchmark(harness::load_benchmark(write_package(root, "intra", false)), o),
         20.0);

  o.rmw = "fastdds";
  o.domain_id = domain;
  report("fastdds, one process",
         harness::run_benchmark(harness::load_benchmark(write_package(root, "dds", false)), o), 0);

  o.processes = harness::ProcessLayout::kPerNode;
  o.node_command = {ROBOTPERF_EXECUTABLE, "node"};
  report("fastdds, relay in a 2nd process",
         harness::run_benchmark(harness::load_benchmark(write_package(root, "dds2", true)), o), 0);
  fs::remove_all(root);
  return 0;
}
