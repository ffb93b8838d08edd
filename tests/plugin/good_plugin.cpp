// A plug-in built against the plug-in API as a user's would be: a kernel that scales joint
// positions, a seeded dataset of joint states with the scaled truth, and an evaluator comparing
// the two. The loader, harness and CLI tests load it.
#include <cmath>
#include <random>

#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/plugin.hpp"

namespace {

using namespace robotperf;

class ScaleNode final : public graph::Node, public plugin::NodeCounters {
 public:
  ScaleNode(graph::Context& context, const plugin::KernelConfig& config)
      : Node(context, config.node_name), factor_(config.parameters.get_double("factor")) {
    output_ = create_publisher<msgs::JointState>(config.topic("output"), config.qos);
    input_ = create_subscription<msgs::JointState>(
        config.topic("input"), config.qos, [this](std::shared_ptr<const msgs::JointState> in) {
          plugin::trace_kernel_init(*this, "test_plugin/scale", in->header.stamp.to_ns(), *in);
          msgs::JointState out = *in;
          for (double& p : out.position) p *= factor_;
          plugin::trace_kernel_fini(*this, "test_plugin/scale", out);
          ++scaled_;
          output_->publish(std::move(out));
        });
  }
  std::map<std::string, uint64_t> counters() const override { return {{"scaled", scaled_}}; }

 private:
  double factor_;
  uint64_t scaled_ = 0;
  std::shared_ptr<graph::Publisher<msgs::JointState>> output_;
  std::shared_ptr<graph::GenericSubscription> input_;
};

// Positions uniform in [-1, 1] from the workload seed, and the same scaled by `factor`.
std::vector<plugin::DatasetStream> joint_streams(const plugin::Parameters& workload) {
  std::mt19937_64 random(static_cast<uint64_t>(workload.get_int("seed")));
  std::uniform_real_distribution<double> position(-1.0, 1.0);
  const double factor = workload.get_double("factor");
  auto states = plugin::make_stream<msgs::JointState>("states", "/test_plugin/states");
  auto truth = plugin::make_stream<msgs::JointState>("scaled", "/test_plugin/scaled");
  for (int64_t k = 0; k < workload.get_int("frames"); ++k) {
    msgs::JointState s;
    s.name = {"a", "b"};
    s.position = {position(random), position(random)};
    msgs::JointState t = s;
    for (double& p : t.position) p *= factor;
    plugin::append(states, std::move(s));
    plugin::append(truth, std::move(t));
  }
  return {std::move(states), std::move(truth)};
}

class ScaledEvaluator final : public plugin::FunctionalEvaluator {
 public:
  ScaledEvaluator(const plugin::DatasetStream& truth, double tolerance)
      : truth_(truth), tolerance_(tolerance) {
    plugin::require_type<msgs::JointState>(truth, "test_plugin/scaled");
  }
  void add(const void* output, std::size_t frame) override {
    const auto& out = *static_cast<const msgs::JointState*>(output);
    const auto& truth = *static_cast<const msgs::JointState*>(truth_.messages[frame].get());
    if (out.position.size() != truth.position.size()) {
      problem("output has " + std::to_string(out.position.size()) + " positions");
      return;
    }
    ++n_;
    bool ok = true;
    for (std::size_t i = 0; i < out.position.size(); ++i)
      ok &= std::abs(out.position[i] - truth.position[i]) <= tolerance_;
    matched_ += ok;
  }
  std::map<std::string, double> metrics() const override {
    return {{"match_fraction", n_ ? static_cast<double>(matched_) / n_ : std::nan("")}};
  }

 private:
  const plugin::DatasetStream& truth_;
  double tolerance_;
  uint64_t n_ = 0, matched_ = 0;
};

}  // namespace

ROBOTPERF_PLUGIN(registrar) {
  registrar.add_kernel({.name = "test_plugin/scale",
                        .description = "scale joint positions",
                        .backends = {"cpu", "test_backend"},
                        .inputs = {{"input", "sensor_msgs/msg/JointState"}},
                        .outputs = {{"output", "sensor_msgs/msg/JointState"}},
                        .parameters = {plugin::double_parameter("factor", 2.0, "scale factor")}},
                       [](graph::Context& context, const plugin::KernelConfig& config) {
                         return std::make_shared<ScaleNode>(context, config);
                       });
  registrar.add_dataset(
      {.name = "test_plugin/joints",
       .description = "seeded joint states and their scaled truth",
       .rate_hz = 50,
       .frames = 40,
       .streams = {{"states", "/test_plugin/states", "sensor_msgs/msg/JointState", false, "inputs"},
                   {"scaled", "/test_plugin/scaled", "sensor_msgs/msg/JointState", true,
                    "scaled inputs"}},
       .workload = {plugin::int_parameter("seed", 7, "random seed"),
                    plugin::int_parameter("frames", 40, "frames"),
                    plugin::double_parameter("factor", 2.0, "truth scale")}},
      joint_streams);
  registrar.add_evaluator(
      {.name = "test_plugin/scaled",
       .description = "outputs against the scaled truth",
       .output_type = "sensor_msgs/msg/JointState",
       .truth_roles = {"scaled"},
       .metrics = {{"match_fraction", "fraction", "outputs within tolerance of the truth"}},
       .parameters = {plugin::double_parameter("tolerance", 1e-12, "largest difference")}},
      [](const plugin::TruthStreams& truth, const plugin::Parameters& p) {
        return std::make_unique<ScaledEvaluator>(truth["scaled"], p.get_double("tolerance"));
      });
}
