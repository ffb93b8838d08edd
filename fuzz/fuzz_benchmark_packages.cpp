// Benchmark packages on arbitrary text: the input is a benchmark.yaml, a line "---8<---", and a
// graph.yaml. load_benchmark either returns a checked spec or throws BenchmarkError; the same
// benchmark.yaml read as a published RobotPerf file imports or throws ReportError. A spec that
// loads has an id, a name and node and launched process names that keep every file named after
// them inside the output folder: anything else aborts.
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "fuzz_scratch.hpp"
#include "robotperf/categories/builtin.hpp"
#include "robotperf/files/paths.hpp"
#include "robotperf/harness/benchmark_spec.hpp"
#include "robotperf/report/benchmark_yaml.hpp"
#include "robotperf/report/run_store.hpp"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  robotperf::categories::register_builtin_categories();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  namespace fz = robotperf::fuzz;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  constexpr std::string_view kCut = "\n---8<---\n";
  const auto cut = text.find(kCut);
  const std::string_view meta = cut == std::string_view::npos ? text : text.substr(0, cut);
  const std::string_view graph =
      cut == std::string_view::npos ? std::string_view() : text.substr(cut + kCut.size());

  // A package folder of its own category folder, as discover_benchmarks lays them out.
  const auto package = fz::scratch_dir() / "perception" / "p1";
  std::filesystem::create_directories(package);
  const auto as_bytes = [](std::string_view s) {
    return reinterpret_cast<const uint8_t*>(s.data());
  };
  fz::write_scratch("perception/p1/benchmark.yaml", as_bytes(meta), meta.size());
  fz::write_scratch("perception/p1/graph.yaml", as_bytes(graph), graph.size());
  try {
    const auto spec = robotperf::harness::load_benchmark(package);
    // As run names its results (<id>-<rmw>-<time>.json) and logs (<id>-<token>.<name>.log).
    auto stays_inside = [](const std::string& name) {
      if (!robotperf::harness::valid_file_name_part(name) ||
          !robotperf::files::is_inside("out", std::filesystem::path("out") / (name + "-x.json")))
        std::abort();
    };
    stays_inside(spec.id);
    stays_inside(spec.name);
    for (const auto& node : spec.nodes) stays_inside(node.name);
    for (const auto& process : spec.launch) stays_inside(process.name);
    for (const auto& node : spec.nodes) {
      try {
        (void)robotperf::harness::kernel_config(node, spec.workload);
      } catch (const robotperf::harness::BenchmarkError&) {
      }
    }
  } catch (const robotperf::harness::BenchmarkError&) {
  }
  try {
    (void)robotperf::report::import_benchmark_yaml(package / "benchmark.yaml");
  } catch (const robotperf::report::ReportError&) {
  }
  return 0;
}
