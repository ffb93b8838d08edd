// The manipulation kernels (d1-d6) as graph nodes: one request message in, one answer out, the
// request's header (and so its message ID) copied to the answer.
#include <Eigen/Geometry>
#include <cmath>
#include <stdexcept>
#include <string>

#include "category.hpp"
#include "robot_tf2.hpp"
#include "robotperf/manipulation/collision.hpp"
#include "robotperf/manipulation/kinematics.hpp"
#include "robotperf/manipulation/planning.hpp"
#include "robotperf/msgs/eigen_geometry.hpp"
#include "robotperf/msgs/geometry_msgs.hpp"
#include "robotperf/msgs/robotperf_msgs.hpp"
#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/msgs/trajectory_msgs.hpp"

namespace robotperf::manipulation {
namespace {

using plugin::KernelConfig;

// `v`, the parameter `name`, when it is a positive number.
double positive(const KernelConfig& c, const std::string& name, double v) {
  if (!(v > 0) || !std::isfinite(v))
    throw std::invalid_argument("node '" + c.node_name + "': " + name + " must be > 0");
  return v;
}

// The request's joint positions in the model's joint order (in_model_order): throws
// std::invalid_argument for a state that does not fit or is not finite.
std::vector<double> model_positions(const RobotModel& m, const std::vector<std::string>& names,
                                    const std::vector<double>& position) {
  return in_model_order(m, names, position, "positions");
}

// The node's RobotTf2 when its use_tf2 parameter is set, else null.
std::unique_ptr<RobotTf2> robot_tf2(graph::Node& node, const KernelConfig& config) {
  const Tf2Settings s = kTf2Parameters.read(config.parameters);
  if (!s.use_tf2) return nullptr;
  return std::make_unique<RobotTf2>(node, config, RobotModel::xarm6(), s.world_frame);
}

// A node that answers each request; requests it cannot use are skipped and counted (the frame
// shows as lost at the Monitor), as a ROS node logs and drops them.
template <class Request, class Answer>
class RequestNode : public graph::Node, public plugin::NodeCounters {
 public:
  RequestNode(graph::Context& context, const KernelConfig& config, const char* in, const char* out)
      : graph::Node(context, config.node_name) {
    output_ = create_publisher<Answer>(config.topic(out), config.qos);
    input_ = create_subscription<Request>(
        config.topic(in), config.qos, [this](std::shared_ptr<const Request> request) {
          try {
            auto answer = std::make_shared<Answer>();
            answer->header = request->header;
            respond(*request, *answer);
            ++answered_;
            output_->publish(std::shared_ptr<const Answer>(std::move(answer)));
          } catch (const std::invalid_argument& e) {
            rejected_.note(name(), e.what());
          }
        });
  }
  std::map<std::string, uint64_t> counters() const override {
    return {{"requests_answered", answered_}, {"requests_rejected", rejected_.count()}};
  }

 protected:
  virtual void respond(const Request& request, Answer& answer) = 0;
  std::shared_ptr<graph::Publisher<Answer>> output_;

 private:
  std::shared_ptr<graph::GenericSubscription> input_;
  uint64_t answered_ = 0;
  plugin::SkippedInputs rejected_{"request"};
};

class ForwardKinematicsNode final : public RequestNode<msgs::JointState, msgs::PoseStamped> {
 public:
  ForwardKinematicsNode(graph::Context& context, const KernelConfig& config)
      : RequestNode(context, config, "joint_states", "pose"),
        fk_(RobotModel::xarm6()),
        tf2_(robot_tf2(*this, config)) {}

 private:
  void respond(const msgs::JointState& request, msgs::PoseStamped& answer) override {
    const RobotModel& m = RobotModel::xarm6();
    const auto q = model_positions(m, request.name, request.position);
    answer.header.frame_id = m.base_link();
    if (tf2_) {
      // robot_state_publisher's transforms of the state, then the tip looked up in the base.
      const int64_t stamp = request.header.stamp.to_ns();
      tf2_->set_state(q.data(), stamp);
      answer.pose = msgs::pose_msg_of(tf2_->lookup(m.base_link(), m.tip_link(), stamp));
    } else {
      answer.pose = msgs::pose_msg_of(fk_.tip_pose(q.data()));
    }
  }
  manipulation::ForwardKinematics fk_;
  std::unique_ptr<RobotTf2> tf2_;
};

// As given: checked below before they become IkOptions' unsigned members.
struct IkSettings {
  int64_t max_iterations = 0;
  double eps = 0;
  double timeout_s = 0;
  int64_t seed = 0;
};

const IkOptions kIk;
const plugin::ParameterStruct<IkSettings> kIkParameters{
    plugin::field(&IkSettings::max_iterations, "max_iterations", kIk.max_iterations,
                  "solver iterations per attempt"),
    plugin::field(&IkSettings::eps, "eps", kIk.eps, "the solver's convergence tolerance"),
    plugin::field(&IkSettings::timeout_s, "timeout_s", kIk.timeout_s, "all attempts together, s"),
    plugin::field(&IkSettings::seed, "seed", static_cast<int64_t>(kIk.seed),
                  "seed of the random restarts")};

manipulation::IkOptions ik_options(const KernelConfig& c, manipulation::IkSolver solver) {
  const IkSettings s = kIkParameters.read(c.parameters);
  manipulation::IkOptions o;
  o.solver = solver;
  if (s.max_iterations < 1 || s.max_iterations > 1000000)
    throw std::invalid_argument("node '" + c.node_name + "': max_iterations must be 1..1e6");
  o.max_iterations = static_cast<unsigned>(s.max_iterations);
  o.eps = positive(c, "eps", s.eps);
  o.timeout_s = positive(c, "timeout_s", s.timeout_s);
  o.seed = static_cast<uint64_t>(s.seed);
  return o;
}

// Answers a target pose with a JointState: the solution, or no positions when none was found
// within the timeout (MoveIt's NO_IK_SOLUTION).
class InverseKinematicsNode final : public RequestNode<msgs::PoseStamped, msgs::JointState> {
 public:
  InverseKinematicsNode(graph::Context& context, const KernelConfig& config,
                        manipulation::IkSolver solver)
      : RequestNode(context, config, "pose", "joint_states"),
        ik_(RobotModel::xarm6(), ik_options(config, solver)),
        seed_state_(RobotModel::xarm6().dof(), 0.0),
        tf2_(robot_tf2(*this, config)) {}

 private:
  void respond(const msgs::PoseStamped& request, msgs::JointState& answer) override {
    const RobotModel& m = RobotModel::xarm6();
    const int64_t stamp = request.header.stamp.to_ns();
    const std::string& frame =
        request.header.frame_id.empty() ? m.base_link() : request.header.frame_id;
    // The solver works in the base frame: without tf2 no transforms are known to bring others
    // into it; with tf2 the target's frame is looked up in the base (the world frame, the base).
    if (!tf2_ && frame != m.base_link()) {
      throw std::invalid_argument("target pose is in frame '" + frame + "', not the arm's base '" +
                                  m.base_link() + "'");
    }
    const auto& p = request.pose;
    if (!std::isfinite(p.position.x) || !std::isfinite(p.position.y) ||
        !std::isfinite(p.position.z))
      throw std::invalid_argument("target position is not finite");
    const Eigen::Quaterniond r(p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z);
    if (!(std::abs(r.norm() - 1.0) < 1e-3))
      throw std::invalid_argument("target orientation is not a unit quaternion");
    Eigen::Isometry3d target = msgs::isometry_of(p);
    if (tf2_) target = tf2_->lookup(m.base_link(), frame, stamp) * target;
    const manipulation::IkResult result = ik_.solve(target, seed_state_);
    answer.name = m.joint_names();
    if (!result.success) return;
    answer.position = result.q;
    // The arm's state at the solution, as robot_state_publisher broadcasts it.
    if (tf2_) tf2_->set_state(result.q.data(), stamp);
  }
  manipulation::InverseKinematics ik_;
  std::vector<double> seed_state_;
  std::unique_ptr<RobotTf2> tf2_;
};

class CollisionNode final : public RequestNode<msgs::JointState, msgs::CollisionResult> {
 public:
  CollisionNode(graph::Context& context, const KernelConfig& config,
                manipulation::CollisionBackend backend)
      : RequestNode(context, config, "joint_states", "collision"),
        checker_(manipulation::make_collision_checker(backend, RobotModel::xarm6(),
                                                      manipulation::default_scene())),
        tf2_(robot_tf2(*this, config)) {}

 private:
  void respond(const msgs::JointState& request, msgs::CollisionResult& answer) override {
    const auto q = model_positions(RobotModel::xarm6(), request.name, request.position);
    manipulation::CollisionAnswer a;
    if (tf2_) {
      // The links posed from the state's transforms looked up in the base frame.
      const int64_t stamp = request.header.stamp.to_ns();
      tf2_->set_state(q.data(), stamp);
      tf2_->link_poses(stamp, poses_);
      a = checker_->check_at(poses_);
    } else {
      a = checker_->check(q.data());
    }
    answer.in_collision = a.in_collision;
    answer.with_scene = a.with_scene;
    answer.first = a.first;
    answer.second = a.second;
  }
  std::unique_ptr<manipulation::CollisionChecker> checker_;
  std::unique_ptr<RobotTf2> tf2_;
  std::vector<Eigen::Isometry3d> poses_;
};

msgs::Duration duration_of(double seconds) {
  msgs::Duration d;
  const auto ns = static_cast<int64_t>(std::llround(seconds * 1e9));
  d.sec = static_cast<int32_t>(ns / 1000000000);
  d.nanosec = static_cast<uint32_t>(ns % 1000000000);
  return d;
}

struct PlanSettings {
  double planning_time_s = 0;
  double longest_valid_segment_fraction = 0;
  bool simplify = false;
  std::optional<int64_t> seed;
  double padding_m = 0;
  double sample_period_s = 0;
  double velocity_scaling = 0;
  double acceleration_scaling = 0;
};

const PlanOptions kPlan;
const plugin::ParameterStruct<PlanSettings> kPlanParameters{
    plugin::field(&PlanSettings::planning_time_s, "planning_time_s", kPlan.planning_time_s,
                  "RRTConnect's budget, s (simplification gets what is left)"),
    plugin::field(&PlanSettings::longest_valid_segment_fraction, "longest_valid_segment_fraction",
                  kPlan.longest_valid_segment_fraction,
                  "motion check step as a fraction of the joint space's extent"),
    plugin::field(&PlanSettings::simplify, "simplify", kPlan.simplify,
                  "shortcut and smooth the path"),
    plugin::field(&PlanSettings::seed, "seed",
                  "OMPL's seed, [0, 2^32) (default: the workload seed, else 0: from the clock)"),
    plugin::field(&PlanSettings::padding_m, "padding_m", 0,
                  "link padding of the planner's collision checks, m"),
    plugin::field(&PlanSettings::sample_period_s, "sample_period_s", 0.02,
                  "time between the trajectory's points, s"),
    plugin::field(&PlanSettings::velocity_scaling, "velocity_scaling", 1,
                  "fraction of the joints' velocity limits used"),
    plugin::field(&PlanSettings::acceleration_scaling, "acceleration_scaling", 1,
                  "fraction of the joints' acceleration limits used")};

// A planning query (JointTrajectory: first point start, last point goal) answered with the
// time-parameterised trajectory; no points when planning failed.
class PlanNode final : public RequestNode<msgs::JointTrajectory, msgs::JointTrajectory> {
 public:
  PlanNode(graph::Context& context, const KernelConfig& config)
      : PlanNode(context, config, kPlanParameters.read(config.parameters)) {}

 private:
  PlanNode(graph::Context& context, const KernelConfig& config, const PlanSettings& s)
      : RequestNode(context, config, "query", "trajectory"),
        planner_(RobotModel::xarm6(),
                 manipulation::make_fcl_checker(RobotModel::xarm6(), manipulation::default_scene(),
                                                padding(config, s.padding_m)),
                 plan_options(config, s)),
        sample_period_s_(positive(config, "sample_period_s", s.sample_period_s)),
        velocity_scaling_(positive(config, "velocity_scaling", s.velocity_scaling)),
        acceleration_scaling_(positive(config, "acceleration_scaling", s.acceleration_scaling)),
        tf2_(robot_tf2(*this, config)) {}

  static manipulation::PlanOptions plan_options(const KernelConfig& c, const PlanSettings& s) {
    manipulation::PlanOptions o;
    o.planning_time_s = positive(c, "planning_time_s", s.planning_time_s);
    o.longest_valid_segment_fraction =
        positive(c, "longest_valid_segment_fraction", s.longest_valid_segment_fraction);
    o.simplify = s.simplify;
    const int64_t seed = s.seed.value_or(static_cast<int64_t>(c.workload_seed.value_or(0)));
    if (seed < 0 || seed > static_cast<int64_t>(UINT32_MAX))
      throw std::invalid_argument("node '" + c.node_name + "': seed must be within [0, 2^32)");
    o.seed = static_cast<uint32_t>(seed);
    return o;
  }
  // Link padding of the planner's collision checker (m): motions are checked at discrete states,
  // and the padding keeps the links clear of contact between them.
  static double padding(const KernelConfig& c, double v) {
    if (!(v >= 0) || !std::isfinite(v))
      throw std::invalid_argument("node '" + c.node_name + "': padding_m must be >= 0");
    return v;
  }

  void respond(const msgs::JointTrajectory& query, msgs::JointTrajectory& answer) override {
    const RobotModel& m = RobotModel::xarm6();
    if (query.points.size() < 2) throw std::invalid_argument("a query needs start and goal points");
    const auto start = model_positions(m, query.joint_names, query.points.front().positions);
    const auto goal = model_positions(m, query.joint_names, query.points.back().positions);
    answer.joint_names = m.joint_names();
    if (tf2_) {
      // The start is the arm's current state: its transforms set as robot_state_publisher
      // broadcasts them, its links posed from the buffer and checked before planning (a start in
      // collision fails the plan, as MoveIt's does).
      const int64_t stamp = query.header.stamp.to_ns();
      tf2_->set_state(start.data(), stamp);
      tf2_->link_poses(stamp, poses_);
      if (planner_.checker().check_at(poses_).in_collision) return;
    }
    const manipulation::PlanResult plan = planner_.plan(start, goal);
    if (!plan.success) return;
    for (auto& s : manipulation::time_parameterize(plan.path, m.limits(), sample_period_s_,
                                                   velocity_scaling_, acceleration_scaling_)) {
      msgs::JointTrajectoryPoint p;
      p.positions = std::move(s.position);
      p.velocities = std::move(s.velocity);
      p.accelerations = std::move(s.acceleration);
      p.time_from_start = duration_of(s.time_s);
      answer.points.push_back(std::move(p));
    }
  }
  manipulation::Planner planner_;
  double sample_period_s_, velocity_scaling_, acceleration_scaling_;
  std::unique_ptr<RobotTf2> tf2_;
  std::vector<Eigen::Isometry3d> poses_;
};

const ExecutionOptions kExecution;
const plugin::ParameterStruct<ExecutionOptions> kExecuteParameters{
    plugin::field(&ExecutionOptions::control_rate_hz, "control_rate_hz", kExecution.control_rate_hz,
                  "simulated controller rate, Hz"),
    plugin::field(&ExecutionOptions::lag_s, "lag_s", kExecution.lag_s,
                  "first-order lag of the joints, s"),
    plugin::field(&ExecutionOptions::settle_s, "settle_s", kExecution.settle_s,
                  "control time after the trajectory's end, s")};

// Executes a trajectory on a simulated position-controlled arm in simulated time: publishes the
// arm's JointState every control step on `joint_states`, then the result. The result's
// planning_time stays 0: the trajectory does not say how long planning took.
class ExecuteNode final : public RequestNode<msgs::JointTrajectory, msgs::PlanExecutionResult> {
 public:
  // Bounds the work of one request: a trajectory (or settle_s) whose execution takes more
  // control steps is rejected (at 100 Hz, 10000 s).
  static constexpr double kMaxControlSteps = 1e6;

  ExecuteNode(graph::Context& context, const KernelConfig& config)
      : RequestNode(context, config, "trajectory", "result") {
    options_ = kExecuteParameters.read(config.parameters);
    positive(config, "control_rate_hz", options_.control_rate_hz);
    positive(config, "lag_s", options_.lag_s);
    if (!(options_.settle_s >= 0) ||
        !(options_.settle_s * options_.control_rate_hz <= kMaxControlSteps)) {
      throw std::invalid_argument("node '" + config.node_name +
                                  "': settle_s must be >= 0 and at most 1e6 control steps");
    }
    states_ = create_publisher<msgs::JointState>(config.topic("joint_states"), config.qos);
  }

 private:
  void respond(const msgs::JointTrajectory& trajectory,
               msgs::PlanExecutionResult& answer) override {
    const RobotModel& m = RobotModel::xarm6();
    answer.trajectory = trajectory;
    if (trajectory.points.empty()) return;  // planning failed: nothing to execute
    std::vector<manipulation::TrajectorySample> samples;
    manipulation::JointPath path;
    for (const auto& p : trajectory.points) {
      auto q = model_positions(m, trajectory.joint_names, p.positions);
      if (p.velocities.empty()) throw std::invalid_argument("trajectory points need velocities");
      auto v = in_model_order(m, trajectory.joint_names, p.velocities, "velocities");
      std::vector<double> a;
      if (!p.accelerations.empty())
        a = in_model_order(m, trajectory.joint_names, p.accelerations, "accelerations");
      const double t = p.time_from_start.sec + p.time_from_start.nanosec * 1e-9;
      if (!samples.empty() && !(t > samples.back().time_s))
        throw std::invalid_argument("trajectory times must increase");
      path.push_back(q);
      samples.push_back({t, std::move(q), std::move(v), std::move(a)});
    }
    const double end_s = samples.back().time_s + options_.settle_s;
    if (!(end_s * options_.control_rate_hz <= kMaxControlSteps)) {
      throw std::invalid_argument("trajectory ends at " + std::to_string(samples.back().time_s) +
                                  " s: executing it would take more than 1e6 control steps");
    }
    const auto result = manipulation::execute(samples, options_, [&](const auto& step) {
      auto state = std::make_shared<msgs::JointState>();
      state->header = trajectory.header;
      state->name = m.joint_names();
      state->position = step.position;
      state->velocity = step.velocity;
      states_->publish(std::shared_ptr<const msgs::JointState>(std::move(state)));
    });
    answer.success = true;
    answer.path_length = manipulation::path_length(path);
    answer.execution_steps = static_cast<uint32_t>(result.steps);
    answer.max_tracking_error = result.max_tracking_error;
    answer.final_error = result.final_error;
  }
  manipulation::ExecutionOptions options_;
  std::shared_ptr<graph::Publisher<msgs::JointState>> states_;
};

template <class Node, class... Args>
plugin::KernelFactory factory(Args... args) {
  return [=](graph::Context& context, const KernelConfig& config) {
    return std::make_shared<Node>(context, config, args...);
  };
}

}  // namespace

void register_kernels(plugin::Registrar& registrar) {
  const std::vector<plugin::PortInfo> state_in{{"joint_states", "sensor_msgs/msg/JointState"}};
  const std::vector<plugin::PortInfo> pose{{"pose", "geometry_msgs/msg/PoseStamped"}};
  const std::vector<plugin::PortInfo> state_out{{"joint_states", "sensor_msgs/msg/JointState"}};
  registrar.add_kernel({.name = "manipulation/forward_kinematics",
                        .description = "xArm6 flange pose of a joint state (KDL "
                                       "ChainFkSolverPos_recursive)",
                        .inputs = state_in,
                        .outputs = with_tf2_ports(pose),
                        .parameters = with_tf2({})},
                       factory<ForwardKinematicsNode>());
  registrar.add_kernel(
      {.name = "manipulation/ik_kdl",
       .description = "xArm6 joint state for a target pose: Newton-Raphson with joint limits on "
                      "KDL, random restarts within the timeout (MoveIt's KDL plugin)",
       .inputs = pose,
       .outputs = with_tf2_ports(state_out),
       .parameters = with_tf2(kIkParameters.declarations())},
      factory<InverseKinematicsNode>(IkSolver::kNewtonRaphsonJL));
  registrar.add_kernel(
      {.name = "manipulation/ik_lma",
       .description = "xArm6 joint state for a target pose: KDL ChainIkSolverPos_LMA, random "
                      "restarts within the timeout (MoveIt's LMA plugin)",
       .inputs = pose,
       .outputs = with_tf2_ports(state_out),
       .parameters = with_tf2(kIkParameters.declarations())},
      factory<InverseKinematicsNode>(IkSolver::kLevenbergMarquardt));
  const std::vector<plugin::PortInfo> collision_out{
      {"collision", "robotperf_msgs/msg/CollisionResult"}};
  registrar.add_kernel({.name = "manipulation/collision_fcl",
                        .description = "boolean collision query of an xArm6 joint state vs the "
                                       "box, then self-collision (FCL)",
                        .inputs = state_in,
                        .outputs = with_tf2_ports(collision_out),
                        .parameters = with_tf2({})},
                       factory<CollisionNode>(CollisionBackend::kFcl));
  registrar.add_kernel({.name = "manipulation/collision_bullet",
                        .description = "boolean collision query of an xArm6 joint state vs the "
                                       "box, then self-collision (Bullet)",
                        .inputs = state_in,
                        .outputs = with_tf2_ports(collision_out),
                        .parameters = with_tf2({})},
                       factory<CollisionNode>(CollisionBackend::kBullet));
  const std::vector<plugin::PortInfo> trajectory{
      {"trajectory", "trajectory_msgs/msg/JointTrajectory"}};
  registrar.add_kernel(
      {.name = "manipulation/plan",
       .description = "plan a start -> goal query around the box (OMPL RRTConnect, FCL "
                      "validity), simplify, time-parameterise within the velocity and "
                      "acceleration limits",
       .inputs = {{"query", "trajectory_msgs/msg/JointTrajectory"}},
       .outputs = with_tf2_ports(trajectory),
       .parameters = with_tf2(kPlanParameters.declarations())},
      factory<PlanNode>());
  registrar.add_kernel(
      {.name = "manipulation/execute",
       .description = "execute a trajectory on a simulated position-controlled xArm6, "
                      "publishing its joint states, then the result",
       .inputs = trajectory,
       .outputs = {{"joint_states", "sensor_msgs/msg/JointState"},
                   {"result", "robotperf_msgs/msg/PlanExecutionResult"}},
       .parameters = kExecuteParameters.declarations()},
      factory<ExecuteNode>());
}

}  // namespace robotperf::manipulation
