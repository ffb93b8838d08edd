// run_benchmark as a pipeline of stages (RunStage): the plan resolves a run without starting
// anything, the stages begin in their order, and an interrupt at any stage boundary releases what
// the stages before it acquired: no thread of the run left in this process, no node process left.
#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <ostream>
#include <string>
#include <thread>
#include <vector>

#include "process_table.hpp"
#include "robotperf/harness/run.hpp"
#include "run_plan.hpp"
#include "test_package.hpp"

namespace robotperf::harness {

// For the names of the tests of each stage.
void PrintTo(RunStage stage, std::ostream* out) {
  *out << to_string(stage);
}

namespace {

using testing::relay_graph;
using testing::TestPackage;

constexpr RunStage kAllStages[] = {
    RunStage::kPlan,      RunStage::kPrepare,   RunStage::kStartGraph,
    RunStage::kConnect,   RunStage::kMeasure,   RunStage::kDrain,
    RunStage::kStopGraph, RunStage::kSummarise, RunStage::kCheck};

std::size_t threads_of_this_process() {
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& task : std::filesystem::directory_iterator("/proc/self/task"))
    ++n;
  return n;
}

// The threads of this process once those already joined have left /proc/self/task. pthread_join
// returns when the kernel clears the thread's id, which comes before the kernel removes the task,
// so on a loaded machine a joined thread is listed for a moment more. The kernel announces the
// removal to no one, so this looks again until the count is down to `expected` or 5 s have
// passed: a thread that still runs stays listed, and the count stays above.
std::size_t threads_once_the_joined_have_left(std::size_t expected) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  std::size_t n = threads_of_this_process();
  while (n > expected && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    n = threads_of_this_process();
  }
  return n;
}

// The processes this one started that have not been reaped (zombies included).
std::vector<pid_t> children_of_this_process() {
  std::vector<pid_t> out;
  for (const auto& p : list_processes()) {
    if (p.ppid == getpid()) out.push_back(p.pid);
  }
  return out;
}

RunOptions small_fast_run() {
  RunOptions o;
  o.load.count = 20;
  o.load.rate_hz = 200;
  return o;
}

TEST(RunPlan, ResolvesTheRunWithoutStartingIt) {
  TestPackage p("plan", relay_graph(""));
  const BenchmarkSpec spec = load_benchmark(p.dir());
  RunOptions o;
  o.load.duration_s = 0.5;
  o.load.rate_hz = 40;
  o.load.drain_s = 0.25;
  o.transport.domain_id = 7;
  // Loading a dataset the first time may start a library's worker pool, which stays.
  plan_run(spec, o);
  const std::size_t threads_before = threads_of_this_process();
  const RunPlan plan = plan_run(spec, o);
  EXPECT_EQ(threads_of_this_process(), threads_before) << "the plan started a thread";
  EXPECT_EQ(&plan.spec(), &spec) << "without overrides, the package is run as it is";
  EXPECT_EQ(plan.result.benchmark_id, "t1");
  EXPECT_DOUBLE_EQ(plan.result.rate_hz, 40.0);
  EXPECT_EQ(plan.result.count, 20u) << "0.5 s at 40 Hz";
  EXPECT_EQ(plan.result.warmup, 0u) << "graph.yaml's";
  EXPECT_DOUBLE_EQ(plan.result.drain_s, 0.25);
  EXPECT_EQ(plan.result.timeline, "fixed");
  EXPECT_EQ(plan.result.processes, "single");
  EXPECT_EQ(plan.result.domain_id, 7);
  EXPECT_EQ(plan.period_ns, 25'000'000);
  EXPECT_GT(plan.result.dataset_frames, 0u);
  EXPECT_EQ(plan.result.dataset_frames, plan.dataset.frames);
}

TEST(RunPlan, AnOverrideAppliesToACopyOfThePackage) {
  TestPackage p("plan_backend", relay_graph(""));
  const BenchmarkSpec spec = load_benchmark(p.dir());
  RunOptions o;
  o.nodes.backend = "cpu";
  const RunPlan plan = plan_run(spec, o);
  ASSERT_TRUE(plan.overridden.has_value());
  EXPECT_EQ(&plan.spec(), &*plan.overridden);
  EXPECT_EQ(plan.spec().nodes.size(), spec.nodes.size());
}

TEST(RunPlan, RefusesWhatTheRunCannotDo) {
  TestPackage p("plan_refused", relay_graph(""));
  const BenchmarkSpec spec = load_benchmark(p.dir());
  RunOptions per_node_intra;
  per_node_intra.processes.layout = ProcessLayout::kPerNode;
  EXPECT_THROW(plan_run(spec, per_node_intra), std::invalid_argument);
  RunOptions all_warmup;
  all_warmup.load.count = 5;
  all_warmup.load.warmup = 5;
  EXPECT_THROW(plan_run(spec, all_warmup), std::invalid_argument);
  RunOptions no_rate;
  no_rate.load.rate_hz = 0;
  EXPECT_THROW(plan_run(spec, no_rate), std::invalid_argument);
}

TEST(RunStages, BeginInTheirOrderOnce) {
  TestPackage p("stage_order", relay_graph(""));
  RunOptions o = small_fast_run();
  std::vector<RunStage> begun;
  o.on_stage = [&](RunStage stage) { begun.push_back(stage); };
  const RunResult r = run_benchmark(load_benchmark(p.dir()), o);
  EXPECT_TRUE(r.completed);
  EXPECT_EQ(begun, std::vector<RunStage>(std::begin(kAllStages), std::end(kAllStages)));
}

// What an interrupt at the beginning of `stage` makes of a run: before timing, no result; during
// the drain or the stop, the result as measured, marked interrupted; after, the whole run.
void expect_outcome_of_interrupt_at(RunStage stage, const BenchmarkSpec& spec, RunOptions o) {
  std::atomic<int> interrupted{0};
  o.interrupted = &interrupted;
  o.on_stage = [&](RunStage begun) {
    if (begun == stage) interrupted = SIGINT;
  };
  if (stage <= RunStage::kMeasure) {
    try {
      run_benchmark(spec, o);
      ADD_FAILURE() << "an interrupt before timing gave a result";
    } catch (const RunInterrupted& e) {
      const std::string what = e.what();
      EXPECT_TRUE(what.starts_with("interrupted by SIGINT before")) << what;
      EXPECT_TRUE(what.ends_with(": nothing was measured")) << what;
    }
    return;
  }
  const RunResult r = run_benchmark(spec, o);
  EXPECT_EQ(r.sent, *o.load.count);
  if (stage <= RunStage::kStopGraph) {
    EXPECT_TRUE(r.interrupted);
    EXPECT_FALSE(r.completed);
    ASSERT_FALSE(r.errors.empty());
    EXPECT_EQ(r.errors.front(), "interrupted by SIGINT");
  } else {
    EXPECT_FALSE(r.interrupted) << "timing was over";
    EXPECT_TRUE(r.errors.empty()) << r.errors.front();
  }
}

class InterruptInOneProcess : public ::testing::TestWithParam<RunStage> {
 protected:
  // A first run makes what a process makes once (and keeps) for its first run.
  static void SetUpTestSuite() {
    TestPackage p("first_run", relay_graph(""));
    run_benchmark(load_benchmark(p.dir()), small_fast_run());
  }
};

TEST_P(InterruptInOneProcess, ReleasesWhatTheStagesBeforeAcquired) {
  TestPackage p("interrupt_" + to_string(GetParam()), relay_graph(""));
  const BenchmarkSpec spec = load_benchmark(p.dir());
  const std::size_t threads_before = threads_of_this_process();
  expect_outcome_of_interrupt_at(GetParam(), spec, small_fast_run());
  EXPECT_EQ(threads_once_the_joined_have_left(threads_before), threads_before)
      << "a thread of the run (an executor's, the power sampler's) still runs";
}

INSTANTIATE_TEST_SUITE_P(EveryStage, InterruptInOneProcess, ::testing::ValuesIn(kAllStages),
                         [](const auto& info) { return to_string(info.param); });

class InterruptPerNode : public ::testing::TestWithParam<RunStage> {};

TEST_P(InterruptPerNode, LeavesNoNodeProcess) {
  TestPackage p("per_node_" + to_string(GetParam()), relay_graph(""));
  const BenchmarkSpec spec = load_benchmark(p.dir());
  ASSERT_TRUE(children_of_this_process().empty());
  RunOptions o = small_fast_run();
  o.transport.rmw = "fastdds";
  o.processes.layout = ProcessLayout::kPerNode;
  o.transport.domain_id = rmw::reserved_domain();
  o.processes.node_command = {ROBOTPERF_EXECUTABLE, "node"};
  expect_outcome_of_interrupt_at(GetParam(), spec, o);
  EXPECT_TRUE(children_of_this_process().empty()) << "a node process of the run is left";
}

INSTANTIATE_TEST_SUITE_P(EveryStage, InterruptPerNode, ::testing::ValuesIn(kAllStages),
                         [](const auto& info) { return to_string(info.param); });

}  // namespace
}  // namespace robotperf::harness
