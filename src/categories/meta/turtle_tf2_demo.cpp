// The turtle tf2 demo's dataset and evaluator. Two simulated turtles in turtlesim's 11 x 11 m
// world: turtle1 drives a seeded Lissajous curve, turtle2 follows it, moved each frame by the
// follow command computed from the true relative pose (plane trigonometry, no tf2). Their poses
// are the broadcasters' inputs; the commands are the truth the listener's outputs are held to.
#include <cmath>
#include <numbers>
#include <random>

#include "category.hpp"
#include "robotperf/msgs/geometry_msgs.hpp"

namespace robotperf::meta {
namespace {

using plugin::DatasetStream;

constexpr double kRateHz = 62.5;  // turtlesim publishes its poses every 16 ms

struct TurtleWorkload {
  uint64_t seed = 1;
  std::size_t frames = 500;
};
const TurtleWorkload kDefaults;
const plugin::ParameterStruct<TurtleWorkload> kWorkload{
    plugin::field(&TurtleWorkload::seed, "seed", kDefaults.seed,
                  "seed of turtle1's curve and turtle2's start"),
    plugin::field(&TurtleWorkload::frames, "frames", kDefaults.frames,
                  "poses of each turtle generated", {.minimum = 1, .maximum = 1e6})};

// Uniform draws through the raw 64-bit engine, so the stream is the same with every standard
// library (std::uniform_real_distribution is implementation-defined).
double uniform(std::mt19937_64& rng, double lo, double hi) {
  return lo + (hi - lo) * (static_cast<double>(rng() >> 11) * 0x1.0p-53);
}

msgs::PoseStamped pose(double x, double y, double theta) {
  msgs::PoseStamped p;
  p.header.frame_id = "world";
  p.pose.position = {x, y, 0};
  p.pose.orientation = {0, 0, std::sin(theta / 2), std::cos(theta / 2)};
  return p;
}

std::vector<DatasetStream> turtle_streams(const plugin::Parameters& parameters) {
  const TurtleWorkload w = kWorkload.read(parameters);
  std::mt19937_64 rng(w.seed);
  constexpr double kCentre = 5.544, kAmplitude = 3.0, kDt = 1 / kRateHz;
  const double wx = uniform(rng, 0.3, 0.8), wy = uniform(rng, 0.3, 0.8);
  const double phase_x = uniform(rng, 0, 2 * std::numbers::pi);
  const double phase_y = uniform(rng, 0, 2 * std::numbers::pi);
  double x2 = uniform(rng, 1, 10), y2 = uniform(rng, 1, 10);
  double theta2 = uniform(rng, -std::numbers::pi, std::numbers::pi);

  auto turtle1 = plugin::make_stream<msgs::PoseStamped>("turtle1", "/turtle1/pose");
  auto turtle2 = plugin::make_stream<msgs::PoseStamped>("turtle2", "/turtle2/pose");
  auto commands = plugin::make_stream<msgs::TwistStamped>("commands", "/ground_truth/cmd_vel");
  for (std::size_t k = 0; k < w.frames; ++k) {
    const double t = static_cast<double>(k) * kDt;
    const double x1 = kCentre + kAmplitude * std::sin(wx * t + phase_x);
    const double y1 = kCentre + kAmplitude * std::sin(wy * t + phase_y);
    const double theta1 =
        std::atan2(wy * std::cos(wy * t + phase_y), wx * std::cos(wx * t + phase_x));
    plugin::append(turtle1, pose(x1, y1, theta1));
    plugin::append(turtle2, pose(x2, y2, theta2));
    // turtle1 in turtle2's frame.
    const double dx = x1 - x2, dy = y1 - y2;
    const double ahead = std::cos(theta2) * dx + std::sin(theta2) * dy;
    const double left = -std::sin(theta2) * dx + std::cos(theta2) * dy;
    msgs::TwistStamped command;
    command.header.frame_id = "turtle2";
    command.twist = follow_command(ahead, left);
    // turtlesim's step: turn, then drive along the new heading.
    theta2 += command.twist.angular.z * kDt;
    x2 += command.twist.linear.x * std::cos(theta2) * kDt;
    y2 += command.twist.linear.x * std::sin(theta2) * kDt;
    plugin::append(commands, std::move(command));
  }
  return {std::move(turtle1), std::move(turtle2), std::move(commands)};
}

class TurtleFollowEvaluator final : public plugin::FunctionalEvaluator {
 public:
  explicit TurtleFollowEvaluator(const DatasetStream& truth) : truth_(truth) {
    plugin::require_type<msgs::TwistStamped>(truth, "turtle_follow");
  }
  void add(const void* output, std::size_t frame) override {
    const auto& out = *static_cast<const msgs::TwistStamped*>(output);
    const auto& truth = *static_cast<const msgs::TwistStamped*>(truth_.messages[frame].get());
    if (out.header.frame_id != truth.header.frame_id)
      problem("command frame is '" + out.header.frame_id + "', expected '" + truth.header.frame_id +
              "'");
    linear_ = std::max(linear_, std::abs(out.twist.linear.x - truth.twist.linear.x));
    // A bearing straight behind is +pi or -pi by a rounding: the same turn.
    angular_ =
        std::max(angular_, std::abs(std::remainder(out.twist.angular.z - truth.twist.angular.z,
                                                   2 * std::numbers::pi)));
    ++n_;
  }
  std::map<std::string, double> metrics() const override {
    const double nan = std::nan("");
    return {{"linear_error_max_mps", n_ ? linear_ : nan},
            {"angular_error_max_radps", n_ ? angular_ : nan}};
  }

 private:
  const DatasetStream& truth_;
  double linear_ = 0, angular_ = 0;
  std::size_t n_ = 0;
};

}  // namespace

void register_datasets(plugin::Registrar& registrar) {
  registrar.add_dataset(
      {.name = "meta/turtle_tf2_demo",
       .description = "two turtles in turtlesim's world: turtle1 on a seeded Lissajous curve, "
                      "turtle2 following it, and turtle2's true follow commands",
       .rate_hz = kRateHz,
       .frames = kDefaults.frames,
       .streams = {{"turtle1", "/turtle1/pose", "geometry_msgs/msg/PoseStamped", false,
                    "the leader's pose in world"},
                   {"turtle2", "/turtle2/pose", "geometry_msgs/msg/PoseStamped", false,
                    "the follower's pose in world"},
                   {"commands", "/ground_truth/cmd_vel", "geometry_msgs/msg/TwistStamped", true,
                    "turtle2's follow command from the true relative pose"}},
       .workload = kWorkload.declarations()},
      turtle_streams);
}

void register_evaluators(plugin::Registrar& registrar) {
  registrar.add_evaluator(
      {.name = "turtle_follow",
       .description = "follow commands against those of the true relative pose",
       .output_type = "geometry_msgs/msg/TwistStamped",
       .truth_roles = {"command"},
       .metrics = {{"linear_error_max_mps", "m/s", "largest forward speed difference"},
                   {"angular_error_max_radps", "rad/s", "largest turn rate difference"}},
       .on_arrival = true},
      [](const plugin::TruthStreams& t, const plugin::Parameters&) {
        return std::make_unique<TurtleFollowEvaluator>(t["command"]);
      });
}

}  // namespace robotperf::meta
