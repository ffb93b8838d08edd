// Results files on arbitrary bytes: load_run either returns a run or throws ReportError naming
// the file; a folder holding the file scans to a run or one skipped line, never an exception.
#include <cstdint>
#include <stdexcept>

#include "fuzz_scratch.hpp"
#include "robotperf/report/run_store.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  namespace fz = robotperf::fuzz;
  const auto dir = fz::scratch_dir() / "results";
  std::filesystem::create_directories(dir);
  const auto file = fz::write_scratch("results/a1-intra-20260101T000000000Z.json", data, size);
  (void)robotperf::report::looks_like_result(file);
  try {
    (void)robotperf::report::load_run(file);
  } catch (const robotperf::report::ReportError&) {
  }
  const auto scan = robotperf::report::scan_results(dir);
  if (scan.runs.size() + scan.skipped.size() > 1) throw std::logic_error("one file, two outcomes");
  return 0;
}
