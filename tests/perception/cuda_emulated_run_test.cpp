// The perception benchmarks end to end on the cuda backend's host emulation
// (cuda_emulation/cuda_runtime.h): the nodes' device path (staging, one stream per node, the
// device stages, the warm-up), the check of their answers against the cpu backend's and the
// benchmarks' functional checks, on machines without a GPU. Only the perception category is
// registered: this program's perception library is the emulated one. Nothing here is timed.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>
#include <vector>

#include "../sanitized_build.hpp"
#include "../tracing/device_hops.hpp"
#include "robotperf/harness/benchmark_spec.hpp"
#include "robotperf/harness/run.hpp"
#include "robotperf/plugin/registry.hpp"
#include "robotperf/tracing/session.hpp"

namespace robotperf::perception {
void register_category(plugin::Registrar& registrar);
}

namespace robotperf {
namespace {

class EmulatedPerception final : public ::testing::Environment {
 public:
  void SetUp() override {
    plugin::registry().add("built-in perception", perception::register_category);
  }
};
const auto* const environment = ::testing::AddGlobalTestEnvironment(new EmulatedPerception);

harness::RunResult run_on_cuda(const std::string& id, harness::RunOptions o) {
  o.nodes.backend = "cuda";
  return harness::run_benchmark(
      harness::find_benchmark(std::string(ROBOTPERF_SOURCE_DIR) + "/benchmarks", id), o);
}

// `few_samples`: a run too short to be a valid measurement (its answers are still checked).
void expect_cpus_answers_on_the_emulation(const std::string& what, const harness::RunResult& r,
                                          bool few_samples = false) {
  EXPECT_TRUE(r.completed) << what;
  EXPECT_TRUE(r.errors.empty()) << what << ": " << r.errors.front();
  if (!few_samples) {
    EXPECT_TRUE(r.valid) << what << ": "
                         << (r.invalid_reasons.empty() ? "" : r.invalid_reasons.front());
  }
  // a4 and a3 have ground truth; the others' answers are the cpu's or nothing.
  if (r.functional) {
    EXPECT_TRUE(r.functional->valid) << what;
  }
  ASSERT_TRUE(r.backend_check.has_value()) << what;
  EXPECT_TRUE(r.backend_check->passed) << what << ": " << r.backend_check->criterion;
  EXPECT_GT(r.backend_check->compared, 0u) << what;
  bool any_on_cuda = false;
  for (const auto& node : r.nodes) {
    if (node.backend != "cuda") continue;
    any_on_cuda = true;
    ASSERT_TRUE(node.device.has_value()) << what << ": " << node.name;
    EXPECT_NE(node.device->name.find("emulation"), std::string::npos) << node.device->name;
  }
  EXPECT_TRUE(any_on_cuda) << what << ": no node ran on cuda";
}

TEST(CudaEmulatedRun, ImageBenchmarksGiveTheCpusAnswers) {
  for (const std::string id : {"a1", "a2", "a4", "a5"}) {
    // A rate the emulation keeps up with on a busy two-core machine: under the sanitizers, beside
    // another test, a1 kept 9 of 30 measured messages at 5 Hz.
    harness::RunOptions o;
    o.load.count = 40;
    o.load.rate_hz = test_rate(5, 1);
    expect_cpus_answers_on_the_emulation(id, run_on_cuda(id, o));
  }
}

// a1 device-resident: the rectified image goes from rectify to resize on the device (no download
// after rectify, no upload before resize), and the answers are still the cpu's.
TEST(CudaEmulatedRun, DeviceResidentA1KeepsTheRectifiedImageOnTheDevice) {
  harness::RunOptions o;
  o.load.count = 35;
  o.load.rate_hz = test_rate(5, 1);
  o.nodes.device_resident = true;
  o.tracing.mode = harness::RunMode::kGrey;
  o.tracing.trace_dir = std::filesystem::temp_directory_path() /
                        ("cuda-emulated-a1-resident-" + std::to_string(getpid()) + ".trace");
  std::string why;
  const bool grey = tracing::lttng_available(&why);
  if (!grey) o.tracing.mode = harness::RunMode::kBlack;
  const harness::RunResult r = run_on_cuda("a1", o);
  std::filesystem::remove_all(o.tracing.trace_dir);
  expect_cpus_answers_on_the_emulation("a1 device-resident", r);
  ASSERT_EQ(r.device_resident.size(), 1u);
  EXPECT_EQ(r.device_resident[0].topic, "/rectify/image_rect");
  EXPECT_EQ(r.device_resident[0].from, "rectify");
  EXPECT_EQ(r.device_resident[0].to, std::vector<std::string>{"resize"});
  EXPECT_EQ(r.device_resident[0].backend, "cuda");
  if (!grey) GTEST_SKIP() << "answers checked; no device stages without LTTng: " << why;
  test_support::expect_device_stages_inside_kernel(r, "rectify", "image_proc/rectify",
                                                   {"upload", "compute"});
  test_support::expect_device_stages_inside_kernel(r, "resize", "image_proc/resize",
                                                   {"compute", "download"});
}

// The emulated block matcher takes 0.7 s a pair alone, 1.6 s under the sanitizers (and more than
// the 3.3 s period of 0.3 Hz beside another test there): a3 at a rate it keeps up with on a busy
// machine, too few messages for a valid measurement (30) in a test's time.
TEST(CudaEmulatedRun, StereoGivesTheCpusDisparity) {
  harness::RunOptions o;
  o.load.count = 8;
  o.load.warmup = 2;
  o.load.rate_hz = test_rate(0.3, 0.1);
  // There a pair's callback outlasts the benchmark's drain: the last one is waited for.
  if (kSanitizedBuild) o.load.drain_s = 30.0;
  expect_cpus_answers_on_the_emulation("a3", run_on_cuda("a3", o), true);
}

// A grey-box run: the kernel's time splits into its upload, compute and download on the node's
// stream, each a hop of every measured message inside the kernel's (what bench_backends reports).
TEST(CudaEmulatedRun, GreyBoxShowsTheTransfersAndComputation) {
  std::string why;
  if (!tracing::lttng_available(&why)) GTEST_SKIP() << why;
  harness::RunOptions o;
  o.load.count = 35;
  o.load.rate_hz = test_rate(5, 1);  // as the image benchmarks above
  o.tracing.mode = harness::RunMode::kGrey;
  o.tracing.trace_dir = std::filesystem::temp_directory_path() /
                        ("cuda-emulated-a5-" + std::to_string(getpid()) + ".trace");
  const harness::RunResult g = run_on_cuda("a5", o);
  std::filesystem::remove_all(o.tracing.trace_dir);
  ASSERT_TRUE(g.grey.has_value());
  expect_cpus_answers_on_the_emulation("a5 grey", g);
  test_support::expect_device_stages_inside_kernel(g, "resize", "image_proc/resize");
}

}  // namespace
}  // namespace robotperf
