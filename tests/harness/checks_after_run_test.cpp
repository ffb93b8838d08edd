// The checks made after the run (a functional evaluator, the answers of another backend against
// the cpu's) run a plug-in's code: one that cannot be made leaves the measured result as it is,
// saying what was not checked.
#include <gtest/gtest.h>

#include <chrono>
#include <future>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>

#include "robotperf/harness/run.hpp"
#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/plugin/registry.hpp"
#include "test_package.hpp"

namespace robotperf::harness {
namespace {

using testing::TestPackage;

// Copies each image to its output.
class CopyNode final : public graph::Node {
 public:
  CopyNode(graph::Context& context, const plugin::KernelConfig& config)
      : Node(context, config.node_name) {
    output_ = create_publisher<msgs::Image>(config.topic("output"), config.qos);
    input_ = create_subscription<msgs::Image>(
        config.topic("input"), config.qos,
        [this](std::shared_ptr<const msgs::Image> in) { output_->publish(msgs::Image(*in)); });
  }

 private:
  std::shared_ptr<graph::Publisher<msgs::Image>> output_;
  std::shared_ptr<graph::GenericSubscription> input_;
};

class ThrowingEvaluator final : public plugin::FunctionalEvaluator {
 public:
  void add(const void*, std::size_t) override { throw std::runtime_error("evaluator bug"); }
  std::map<std::string, double> metrics() const override { return {}; }
};

// "test/vendor_copy": a kernel on a vendor's backend alone, as a plug-in may bring one;
// "test/throwing" and "test/throwing_on_arrival": evaluators that throw on every output.
void register_test_plug_in() {
  static const bool registered = [] {
    plugin::registry().add("checks_after_run_test", [](plugin::Registrar& r) {
      r.add_kernel({.name = "test/vendor_copy",
                    .description = "copies images on a vendor's accelerator",
                    .backends = {"test_only"},
                    .inputs = {{"input", "sensor_msgs/msg/Image"}},
                    .outputs = {{"output", "sensor_msgs/msg/Image"}}},
                   [](graph::Context& c, const plugin::KernelConfig& config) {
                     return std::make_shared<CopyNode>(c, config);
                   });
      for (const bool on_arrival : {false, true}) {
        r.add_evaluator({.name = on_arrival ? "test/throwing_on_arrival" : "test/throwing",
                         .description = "throws on every output",
                         .output_type = "sensor_msgs/msg/Image",
                         .truth_roles = {"image"},
                         .metrics = {{"n", "outputs", "outputs"}},
                         .on_arrival = on_arrival},
                        [](const plugin::TruthStreams&, const plugin::Parameters&) {
                          return std::make_unique<ThrowingEvaluator>();
                        });
      }
    });
    return true;
  }();
  static_cast<void>(registered);
}

std::string graph_yaml(const std::string& node, const std::string& extra = "") {
  return "dataset: perception/image\n"
         "rate_hz: 100\n"
         "warmup: 0\n"
         "drain_s: 2.0\n"
         "validity: {min_samples: 5, max_loss_percent: 0.0}\n"
         "inputs:\n"
         "  - {topic: /in, type: sensor_msgs/msg/Image, stream: image}\n"
         "output: {topic: /out, type: sensor_msgs/msg/Image}\n"
         "nodes:\n" +
         node + extra;
}

// Runs in a thread of its own, so that a run that never ends fails the test instead of hanging
// it: nullopt when it did not end within a minute.
std::optional<RunResult> run_within_a_minute(const BenchmarkSpec& spec, const RunOptions& options) {
  auto result = std::make_shared<std::promise<RunResult>>();
  std::future<RunResult> done = result->get_future();
  std::thread([spec, options, result] {
    try {
      result->set_value(run_benchmark(spec, options));
    } catch (...) {
      result->set_exception(std::current_exception());
    }
  }).detach();
  if (done.wait_for(std::chrono::minutes(1)) != std::future_status::ready) return std::nullopt;
  return done.get();
}

RunOptions quick() {
  RunOptions o;
  o.load.count = 20;
  o.load.rate_hz = 100;
  return o;
}

// A kernel with no cpu backend has no reference to compare its answers with: the check is left
// out, saying why, and what was measured stands.
TEST(ChecksAfterTheRun, AKernelWithoutACpuBackendIsMeasuredAndItsAnswersLeftUnchecked) {
  register_test_plug_in();
  TestPackage p("vendor_only", graph_yaml("  - name: copy\n"
                                          "    kernel: test/vendor_copy\n"
                                          "    backend: test_only\n"
                                          "    topics: {input: /in, output: /out}\n"));
  const RunResult r = run_benchmark(load_benchmark(p.dir()), quick());
  EXPECT_EQ(r.matched, 20u);
  EXPECT_TRUE(r.valid) << (r.invalid_reasons.empty() ? "" : r.invalid_reasons[0]);
  EXPECT_FALSE(r.backend_check.has_value());
  EXPECT_FALSE(r.functional.has_value()) << "nothing says its answers are wrong";
  const auto warning = std::ranges::find(r.warnings, "backend_check", &sysinfo::RunWarning::rule);
  ASSERT_NE(warning, r.warnings.end()) << "the check left out is not said";
  EXPECT_NE(warning->message.find("node 'copy' (kernel test/vendor_copy) has no cpu backend"),
            std::string::npos)
      << warning->message;
}

// An evaluator that throws, checking after the run or as outputs arrive: the result is written
// with what was measured and is functionally invalid, saying why.
TEST(ChecksAfterTheRun, AnEvaluatorThatThrowsLeavesTheResultMeasuredAndFunctionallyInvalid) {
  register_test_plug_in();
  for (const std::string evaluator : {"test/throwing", "test/throwing_on_arrival"}) {
    SCOPED_TRACE(evaluator);
    TestPackage p("throwing_evaluator", graph_yaml("  - name: relay\n"
                                                   "    kernel: util/relay\n"
                                                   "    topics: {input: /in, output: /out}\n",
                                                   "functional: {evaluator: " + evaluator +
                                                       ", truth: {image: image}, sample: 4}\n"));
    const std::optional<RunResult> r = run_within_a_minute(load_benchmark(p.dir()), quick());
    ASSERT_TRUE(r.has_value()) << "the run did not end";
    EXPECT_EQ(r->matched, 20u);
    EXPECT_TRUE(r->errors.empty()) << r->errors.front();
    EXPECT_TRUE(r->valid) << "the measurement itself is sound";
    ASSERT_TRUE(r->functional.has_value());
    EXPECT_FALSE(r->functional->valid);
    ASSERT_FALSE(r->functional->reasons.empty());
    EXPECT_EQ(r->functional->reasons[0], "the evaluator failed: evaluator bug");
    const auto warning = std::ranges::find(r->warnings, "functional", &sysinfo::RunWarning::rule);
    ASSERT_NE(warning, r->warnings.end());
    EXPECT_NE(warning->message.find("its evaluator failed: evaluator bug"), std::string::npos)
        << warning->message;
  }
}

}  // namespace
}  // namespace robotperf::harness
