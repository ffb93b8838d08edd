// The perception benchmarks on each backend of this machine: p50 and p99 latency (black-box,
// intra, from send: transfers to and from the device included, as every message pays them), the
// speed-up over the cpu backend of the same machine, and whether the answer still passes the
// benchmark's functional checks.
// Run on demand: ./build/bench/backends/bench_backends [--count N] [a1 a2 a3 a4 a5]
// a3 is left out of the default list: on a CPU OpenCL device (pocl) its block matcher takes about
// 150 ms a pair and cannot keep up with a3's 30 Hz, so the figure would be queueing; name it on a
// machine with a GPU.
//
// Targets (issue #19), for the cuda backend on a data-centre GPU: a3 >= 10x, a1, a2, a5 >= 3x,
// a1 p50 <= 1 ms. They are printed beside every backend; a CPU "device" behind OpenCL (pocl) is
// there to test the path, not to be fast.
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "robotperf/categories/builtin.hpp"
#include "robotperf/harness/benchmark_spec.hpp"
#include "robotperf/harness/run.hpp"
#include "robotperf/perception/opencl_device.hpp"

using namespace robotperf;

namespace {

struct Measured {
  double p50_ms = 0, p99_ms = 0;
  bool functional_ok = false;
  std::string device;
};

Measured measure(const harness::BenchmarkSpec& spec, const std::string& backend,
                 std::size_t count) {
  harness::RunOptions o;
  o.count = count;
  o.backend = backend;
  const harness::RunResult r = harness::run_benchmark(spec, o);
  Measured m;
  m.p50_ms = r.latency_from_sent.p50 / 1e6;
  m.p99_ms = r.latency_from_sent.p99 / 1e6;
  m.functional_ok = r.functional ? r.functional->valid : true;
  for (const auto& n : r.nodes) {
    if (n.device) m.device = n.device->name;
  }
  return m;
}

}  // namespace

int main(int argc, char** argv) {
  categories::register_builtin_categories();
  std::size_t count = 300;
  std::vector<std::string> ids;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--count" && i + 1 < argc) {
      count = std::strtoul(argv[++i], nullptr, 10);
    } else {
      ids.push_back(a);
    }
  }
  if (ids.empty()) ids = {"a1", "a2", "a4", "a5"};
  const std::map<std::string, double> target_speedup = {
      {"a1", 3}, {"a2", 3}, {"a3", 10}, {"a5", 3}};

  std::vector<std::string> backends = {"opencl"};
  try {
    const auto& d = perception::opencl_device();
    std::printf("opencl device: %s (%s, %s)\n", d.name.c_str(), d.vendor.c_str(),
                d.runtime.c_str());
  } catch (const std::exception& e) {
    std::printf("opencl: %s\n", e.what());
    backends.clear();
  }
  std::printf("cuda: not built in this robotperf (issue #19)\n");
  std::printf(
      "latency from send, intra, %zu messages at each benchmark's rate, ms; speed-up = cpu p50 / "
      "backend p50 on this machine\n",
      count);
  std::printf("%-4s %-8s %9s %9s %9s  %-10s %s\n", "id", "backend", "p50", "p99", "speed-up",
              "functional", "target (cuda, data-centre GPU)");
  int status = 0;
  try {
    for (const auto& id : ids) {
      const auto spec = harness::find_benchmark(ROBOTPERF_BENCHMARKS_DIR, id);
      const Measured cpu = measure(spec, "cpu", count);
      std::printf("%-4s %-8s %9.3f %9.3f %9s  %-10s\n", id.c_str(), "cpu", cpu.p50_ms, cpu.p99_ms,
                  "1.00x", cpu.functional_ok ? "ok" : "INVALID");
      for (const auto& b : backends) {
        const Measured m = measure(spec, b, count);
        const auto t = target_speedup.find(id);
        std::printf("%-4s %-8s %9.3f %9.3f %8.2fx  %-10s %s\n", id.c_str(), b.c_str(), m.p50_ms,
                    m.p99_ms, cpu.p50_ms / m.p50_ms, m.functional_ok ? "ok" : "INVALID",
                    t == target_speedup.end()
                        ? "-"
                        : (">= " + std::to_string(static_cast<int>(t->second)) + "x" +
                           (id == "a1" ? ", p50 <= 1 ms" : ""))
                              .c_str());
        if (!m.functional_ok) status = 1;
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_backends: %s\n", e.what());
    return 2;
  }
  return status;
}
