// The manipulation kernels as graph nodes and their evaluators: what they accept, reject and
// answer, and how the evaluators judge answers.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "../node_test_support.hpp"
#include "category.hpp"
#include "robotperf/manipulation/collision.hpp"
#include "robotperf/manipulation/kinematics.hpp"
#include "robotperf/manipulation/manipulation_requests.hpp"
#include "robotperf/manipulation/planning.hpp"
#include "robotperf/msgs/eigen_geometry.hpp"
#include "robotperf/msgs/geometry_msgs.hpp"
#include "robotperf/msgs/robotperf_msgs.hpp"
#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/msgs/tf2_msgs.hpp"
#include "robotperf/msgs/trajectory_msgs.hpp"
#include "robotperf/rmw/transport.hpp"

namespace robotperf::manipulation {
namespace {

const RobotModel& arm() {
  return RobotModel::xarm6();
}

// The category's kernels and evaluators, registered here without the other categories.
const testing::CategoryUnderTest& category() {
  static const testing::CategoryUnderTest c{register_kernels, register_evaluators};
  return c;
}

template <class Answer>
struct NodeRun {
  std::vector<Answer> answers;
  std::map<std::string, uint64_t> counters;
};

// Sends `requests` in order to a node of `kernel` (input port `in`) and collects its answers
// (port `out`) and counters. The last request must be one the node answers: its answer shows
// that every request before it was handled (one subscription delivers in order).
template <class Answer, class Request>
NodeRun<Answer> run_node(const std::string& kernel,
                         const std::map<std::string, std::string>& parameters,
                         const std::string& in, const std::string& out,
                         std::vector<Request> requests) {
  testing::NodeUnderTest node(category(), kernel, parameters);
  auto& answers = node.output<Answer>(out);
  auto input = node.input<Request>(in);
  node.start();
  const auto last_id = static_cast<int32_t>(requests.size() - 1);
  for (std::size_t i = 0; i < requests.size(); ++i) {
    requests[i].header.stamp.sec = static_cast<int32_t>(i);
    input->publish(std::move(requests[i]));
  }
  EXPECT_TRUE(answers.wait([&](const std::vector<Answer>& so_far) {
    return std::any_of(so_far.begin(), so_far.end(),
                       [&](const Answer& a) { return a.header.stamp.sec == last_id; });
  })) << "no answer to the last request";
  node.stop();
  return {answers.messages(), node.counters()};
}

msgs::Duration duration_of(double seconds) {
  const auto ns = static_cast<int64_t>(std::llround(seconds * 1e9));
  msgs::Duration d;
  d.sec = static_cast<int32_t>(ns / 1000000000);
  d.nanosec = static_cast<uint32_t>(ns % 1000000000);
  return d;
}

// Two collision-free states whose straight joint-space line is collision-free.
const std::vector<double> kStart{0.9, 0.7, -0.9, 0, 1.4, 0};
const std::vector<double> kGoal{0.5, 0.5, -0.7, 0.3, 1.2, 0.4};

// The time-parameterised straight motion from kStart to kGoal, as the planner node sends it.
msgs::JointTrajectory straight_trajectory(double velocity_scaling = 1.0,
                                          double acceleration_scaling = 1.0) {
  msgs::JointTrajectory t;
  t.header.frame_id = arm().base_link();
  t.joint_names = arm().joint_names();
  for (const auto& s : time_parameterize({kStart, kGoal}, arm().limits(), 0.02, velocity_scaling,
                                         acceleration_scaling)) {
    msgs::JointTrajectoryPoint p;
    p.positions = s.position;
    p.velocities = s.velocity;
    p.accelerations = s.acceleration;
    p.time_from_start = duration_of(s.time_s);
    t.points.push_back(std::move(p));
  }
  return t;
}

// The same trajectory with its joints in the opposite order.
msgs::JointTrajectory reversed(msgs::JointTrajectory t) {
  std::reverse(t.joint_names.begin(), t.joint_names.end());
  for (auto& p : t.points) {
    std::reverse(p.positions.begin(), p.positions.end());
    std::reverse(p.velocities.begin(), p.velocities.end());
    std::reverse(p.accelerations.begin(), p.accelerations.end());
  }
  return t;
}

// d1's queries: start and goal.
plugin::DatasetStream query_stream() {
  msgs::JointTrajectory query;
  query.joint_names = arm().joint_names();
  query.points.resize(2);
  query.points[0].positions = kStart;
  query.points[1].positions = kGoal;
  auto queries = plugin::make_stream<msgs::JointTrajectory>("queries", "/plan/query");
  plugin::append(queries, std::move(query));
  return queries;
}

struct Verdict {
  std::map<std::string, double> metrics;
  std::set<std::string> problems;
};

Verdict judge_plan(const msgs::PlanExecutionResult& result) {
  const plugin::DatasetStream queries = query_stream();
  auto e = category().evaluator("plan_execution", {{"query", &queries}});
  e->add(&result, 0);
  return {e->metrics(), e->problems()};
}

msgs::PlanExecutionResult result_of(msgs::JointTrajectory trajectory) {
  msgs::PlanExecutionResult r;
  r.success = true;
  r.trajectory = std::move(trajectory);
  return r;
}

TEST(PlanExecution, TestMotionIsCollisionFree) {
  auto fcl = make_fcl_checker(arm(), default_scene());
  auto bullet = make_bullet_checker(arm(), default_scene());
  EXPECT_TRUE(path_valid(arm(), *fcl, {kStart, kGoal}, 0.002));
  EXPECT_TRUE(path_valid(arm(), *bullet, {kStart, kGoal}, 0.002));
}

// The executor and the evaluator take the trajectory's joints by name: the same motion with its
// joints in another order executes and is judged the same.
TEST(PlanExecution, ReversedJointOrderExecutesAndIsJudgedTheSame) {
  const auto run = run_node<msgs::PlanExecutionResult>(
      "manipulation/execute", {}, "trajectory", "result",
      std::vector<msgs::JointTrajectory>{reversed(straight_trajectory()), straight_trajectory()});
  ASSERT_EQ(run.answers.size(), 2u);
  const auto &turned = run.answers[0], &straight = run.answers[1];
  EXPECT_TRUE(turned.success);
  EXPECT_TRUE(straight.success);
  EXPECT_EQ(turned.execution_steps, straight.execution_steps);
  EXPECT_EQ(turned.max_tracking_error, straight.max_tracking_error);
  EXPECT_EQ(turned.final_error, straight.final_error);
  EXPECT_EQ(turned.path_length, straight.path_length);
  EXPECT_EQ(turned.planning_time, 0.0);  // not measured (docs/benchmarks/manipulation.md)
  EXPECT_LT(straight.final_error, 1e-3);
  const Verdict a = judge_plan(turned), b = judge_plan(straight);
  EXPECT_EQ(a.metrics, b.metrics);
  EXPECT_EQ(a.problems, b.problems);
  EXPECT_TRUE(b.problems.empty()) << *b.problems.begin();
  EXPECT_EQ(b.metrics.at("valid_fraction"), 1.0);
}

// The evaluator computes joint speeds from the trajectory's positions and times, and its path
// length, rather than trusting the figures reported with them.
TEST(PlanExecution, EvaluatorJudgesTheMotionByItsPositionsAndTimes) {
  auto honest = result_of(straight_trajectory());
  honest.path_length = 99;  // a wrong figure reported beside the trajectory
  const Verdict good = judge_plan(honest);
  EXPECT_TRUE(good.problems.empty()) << *good.problems.begin();
  EXPECT_EQ(good.metrics.at("valid_fraction"), 1.0);
  EXPECT_NEAR(good.metrics.at("path_length_mean_rad"), path_length({kStart, kGoal}), 1e-9);

  // Twice as fast as the limits allow, velocities reported as before.
  auto compress = [](msgs::JointTrajectory t) {
    for (auto& p : t.points) {
      const int64_t ns =
          (int64_t{p.time_from_start.sec} * 1000000000 + p.time_from_start.nanosec) / 2;
      p.time_from_start.sec = static_cast<int32_t>(ns / 1000000000);
      p.time_from_start.nanosec = static_cast<uint32_t>(ns % 1000000000);
    }
    return result_of(std::move(t));
  };
  const Verdict fast = judge_plan(compress(straight_trajectory()));
  EXPECT_TRUE(fast.problems.contains("a trajectory exceeds the velocity or acceleration limits"));
  EXPECT_EQ(fast.metrics.at("valid_fraction"), 0.0);

  // Planned at 40 % of the limits, run twice as fast: within the limits, but not at the
  // velocities it reports.
  const Verdict quicker = judge_plan(compress(straight_trajectory(0.4, 0.16)));
  EXPECT_FALSE(
      quicker.problems.contains("a trajectory exceeds the velocity or acceleration limits"));
  EXPECT_TRUE(
      quicker.problems.contains("a trajectory's velocities do not match its positions and times"));
  EXPECT_EQ(quicker.metrics.at("valid_fraction"), 0.0);
}

TEST(PlanExecution, ExecutorBoundsItsWork) {
  auto executor_settling = [](const std::string& settle_s) {
    graph::Context context(rmw::make_transport("intra"));
    category().build(context, "manipulation/execute",
                     category().config_of("manipulation/execute", {{"settle_s", settle_s}}));
  };
  EXPECT_NO_THROW(executor_settling("0.5"));
  EXPECT_THROW(executor_settling("inf"), std::invalid_argument);
  EXPECT_THROW(executor_settling("-1"), std::invalid_argument);
  // A trajectory that ends 68 years from now is rejected, not simulated step by step.
  msgs::JointTrajectory endless = straight_trajectory();
  endless.points.back().time_from_start.sec = INT32_MAX;
  msgs::JointTrajectory nan = straight_trajectory();
  nan.points[3].positions[2] = std::nan("");
  const auto run = run_node<msgs::PlanExecutionResult>(
      "manipulation/execute", {}, "trajectory", "result",
      std::vector<msgs::JointTrajectory>{endless, nan, straight_trajectory()});
  ASSERT_EQ(run.answers.size(), 1u);
  EXPECT_TRUE(run.answers[0].success);
  EXPECT_EQ(run.counters.at("requests_rejected"), 2u);
}

msgs::JointState joint_state(std::vector<std::string> names, std::vector<double> position) {
  msgs::JointState s;
  s.name = std::move(names);
  s.position = std::move(position);
  return s;
}

TEST(CollisionNode, RejectsNonFiniteStates) {
  const auto run = run_node<msgs::CollisionResult>(
      "manipulation/collision_fcl", {}, "joint_states", "collision",
      std::vector<msgs::JointState>{joint_state({}, {std::nan(""), 0, 0, 0, 0, 0}),
                                    joint_state({}, std::vector<double>(6, 0.0))});
  ASSERT_EQ(run.answers.size(), 1u);
  EXPECT_FALSE(run.answers[0].in_collision);
  EXPECT_EQ(run.counters.at("requests_rejected"), 1u);
}

// A state the evaluator cannot use is a problem of the dataset, not a crash; a state with a joint
// the arm does not have is mapped by name, as the nodes map it.
TEST(CollisionEvaluator, StatesMapByNameAndUnusableOnesAreProblems) {
  auto states = plugin::make_stream<msgs::JointState>("joint_states", "/collision/joint_states");
  std::vector<std::string> names = arm().joint_names();
  names.push_back("gripper");
  plugin::append(states, joint_state(names, {0, 0, 0, 0, 0, 0, 0.5}));
  plugin::append(states, joint_state({}, {0, 0, 0, 0, 0}));
  auto truth = plugin::make_stream<msgs::CollisionResult>("truth", "/ground_truth/collision");
  plugin::append(truth, msgs::CollisionResult{});
  plugin::append(truth, msgs::CollisionResult{});
  auto e = category().evaluator("collision", {{"truth", &truth}, {"state", &states}});
  const msgs::CollisionResult free;
  e->add(&free, 0);
  EXPECT_TRUE(e->problems().empty()) << *e->problems().begin();
  e->add(&free, 1);
  ASSERT_EQ(e->problems().size(), 1u);
  EXPECT_NE(e->problems().begin()->find("not a state of the arm"), std::string::npos);
  EXPECT_EQ(e->metrics().at("kernel_backends_agreement"), 1.0);
}

TEST(InverseKinematicsEvaluator, SolutionsMapByName) {
  const std::vector<double> q{0.3, 0.2, -0.5, 0.1, 0.9, -0.4};
  msgs::PoseStamped target;
  target.header.frame_id = arm().base_link();
  target.pose = msgs::pose_msg_of(arm().tip_pose(q.data()));
  auto targets = plugin::make_stream<msgs::PoseStamped>("poses", "/ik/target_pose");
  plugin::append(targets, target);
  auto e = category().evaluator("inverse_kinematics", {{"target", &targets}});
  std::vector<std::string> names = arm().joint_names();
  std::vector<double> position = q;
  std::reverse(names.begin(), names.end());
  std::reverse(position.begin(), position.end());
  names.push_back("gripper");
  position.push_back(0.02);
  const msgs::JointState solution = joint_state(names, position);
  e->add(&solution, 0);
  EXPECT_TRUE(e->problems().empty()) << *e->problems().begin();
  EXPECT_EQ(e->metrics().at("success_rate"), 1.0);
  EXPECT_LT(e->metrics().at("position_error_max_m"), 1e-12);
}

// Targets in another frame than the arm's base cannot be solved here (no transforms): rejected,
// as are targets whose position is not finite.
TEST(InverseKinematicsNode, RejectsTargetsInAnotherFrameOrNotFinite) {
  const std::vector<double> q{0.3, 0.2, -0.5, 0.1, 0.9, -0.4};
  msgs::PoseStamped target;
  target.pose = msgs::pose_msg_of(arm().tip_pose(q.data()));
  auto in_frame = [&](const std::string& frame) {
    msgs::PoseStamped t = target;
    t.header.frame_id = frame;
    return t;
  };
  msgs::PoseStamped nan = in_frame(arm().base_link());
  nan.pose.position.x = std::nan("");
  const auto run = run_node<msgs::JointState>(
      "manipulation/ik_kdl", {{"timeout_s", "1"}}, "pose", "joint_states",
      std::vector<msgs::PoseStamped>{in_frame("world"), nan, in_frame(""),
                                     in_frame(arm().base_link())});
  ASSERT_EQ(run.answers.size(), 2u);
  EXPECT_EQ(run.counters.at("requests_rejected"), 2u);
  EXPECT_EQ(run.counters.at("requests_answered"), 2u);
  for (const auto& answer : run.answers) {
    ASSERT_EQ(answer.position.size(), 6u);
    double dp, dr;
    pose_error(arm().tip_pose(answer.position.data()), arm().tip_pose(q.data()), dp, dr);
    EXPECT_LT(dp, 1e-4);
  }
}

// use_tf2 (RobotPerf m2-m7): the answers through the tf2 buffer equal the direct ones. At most 10
// requests a run: the subscription keeps the last 10 that wait.
const std::map<std::string, std::string> kUseTf2{{"use_tf2", "true"}};

TEST(Tf2Mode, ForwardKinematicsThroughTf2EqualsKdlAndBroadcastsTheLinks) {
  const KinematicsRequests requests = generate_kinematics_requests({.seed = 3, .requests = 10});
  const auto direct = run_node<msgs::PoseStamped>("manipulation/forward_kinematics", {},
                                                  "joint_states", "pose", requests.states);
  const auto via_tf2 = run_node<msgs::PoseStamped>("manipulation/forward_kinematics", kUseTf2,
                                                   "joint_states", "pose", requests.states);
  ASSERT_EQ(direct.answers.size(), requests.states.size());
  ASSERT_EQ(via_tf2.answers.size(), requests.states.size());
  for (std::size_t i = 0; i < requests.states.size(); ++i) {
    EXPECT_EQ(via_tf2.answers[i].header.frame_id, arm().base_link());
    double dp, dr;
    pose_error(msgs::isometry_of(via_tf2.answers[i].pose),
               msgs::isometry_of(direct.answers[i].pose), dp, dr);
    EXPECT_LT(dp, 1e-12) << "request " << i;
    EXPECT_LT(dr, 1e-9) << "request " << i;
  }

  // What a tf2 listener of the node sees on /tf: each state's links, at its stamp (the mount, on
  // /tf_static, is looked up in the world-frame test below).
  testing::NodeUnderTest node(category(), "manipulation/forward_kinematics", kUseTf2);
  auto& tf = node.output<msgs::TFMessage>("tf");
  auto& poses = node.output<msgs::PoseStamped>("pose");
  auto input = node.input<msgs::JointState>("joint_states");
  node.start();
  msgs::JointState state = requests.states[0];
  state.header.stamp = msgs::Time::from_ns(5'000'000'000);
  input->publish(std::move(state));
  ASSERT_TRUE(poses.wait([](const auto& m) { return !m.empty(); }));
  ASSERT_TRUE(tf.wait([](const auto& m) { return !m.empty(); }));
  node.stop();
  const auto links = tf.messages().at(0).transforms;
  ASSERT_EQ(links.size(), arm().links().size() - 1);
  EXPECT_EQ(links.front().header.frame_id, arm().base_link());
  EXPECT_EQ(links.back().child_frame_id, arm().tip_link());
  EXPECT_EQ(links.back().header.stamp.to_ns(), 5'000'000'000);
}

TEST(Tf2Mode, CollisionThroughTf2EqualsTheDirectAnswerWithBothBackends) {
  const CollisionRequests requests = generate_collision_requests({.seed = 5, .requests = 10});
  for (const char* kernel : {"manipulation/collision_fcl", "manipulation/collision_bullet"}) {
    const auto direct =
        run_node<msgs::CollisionResult>(kernel, {}, "joint_states", "collision", requests.states);
    const auto via_tf2 = run_node<msgs::CollisionResult>(kernel, kUseTf2, "joint_states",
                                                         "collision", requests.states);
    ASSERT_EQ(via_tf2.answers.size(), requests.states.size()) << kernel;
    ASSERT_EQ(direct.answers.size(), requests.states.size()) << kernel;
    std::size_t colliding = 0;
    for (std::size_t i = 0; i < requests.states.size(); ++i) {
      EXPECT_EQ(via_tf2.answers[i].in_collision, direct.answers[i].in_collision) << kernel << i;
      EXPECT_EQ(via_tf2.answers[i].with_scene, direct.answers[i].with_scene) << kernel << i;
      EXPECT_EQ(via_tf2.answers[i].first, direct.answers[i].first) << kernel << i;
      EXPECT_EQ(via_tf2.answers[i].second, direct.answers[i].second) << kernel << i;
      colliding += requests.truth[i].in_collision;
    }
    // Both answers occur: the comparison is not of "free" alone.
    EXPECT_GT(colliding, 0u);
    EXPECT_LT(colliding, requests.states.size());
  }
}

// With tf2 the target's frame is looked up: a target in the world frame (the arm's mount) is
// solved as the same target in the base; without tf2 it is rejected.
TEST(Tf2Mode, InverseKinematicsSolvesTargetsOfTheWorldFrame) {
  const KinematicsRequests requests = generate_kinematics_requests({.seed = 4, .requests = 6});
  std::vector<msgs::PoseStamped> targets;
  for (std::size_t i = 0; i < requests.poses.size(); ++i) {
    targets.push_back(requests.poses[i]);
    if (i % 2 == 0) targets.back().header.frame_id = "world";  // the last one: the base
  }
  for (const char* kernel : {"manipulation/ik_kdl", "manipulation/ik_lma"}) {
    std::map<std::string, std::string> parameters = kUseTf2;
    parameters["timeout_s"] = "1";
    const auto via_tf2 =
        run_node<msgs::JointState>(kernel, parameters, "pose", "joint_states", targets);
    ASSERT_EQ(via_tf2.answers.size(), targets.size()) << kernel;
    for (std::size_t i = 0; i < targets.size(); ++i) {
      ASSERT_EQ(via_tf2.answers[i].position.size(), 6u) << kernel << " target " << i;
      double dp, dr;
      pose_error(arm().tip_pose(via_tf2.answers[i].position.data()),
                 msgs::isometry_of(requests.poses[i].pose), dp, dr);
      EXPECT_LT(dp, 1e-4) << kernel << " target " << i;
      EXPECT_LT(dr, 1e-3) << kernel << " target " << i;
    }
  }
  const auto direct = run_node<msgs::JointState>("manipulation/ik_kdl", {{"timeout_s", "1"}},
                                                 "pose", "joint_states", targets);
  EXPECT_EQ(direct.counters.at("requests_rejected"), targets.size() / 2);
}

// The planner's start state goes through tf2 and is checked before planning: a start in
// collision fails the plan (no points), a free one plans as without tf2.
TEST(Tf2Mode, PlannerChecksItsStartStateThroughTf2) {
  const CollisionRequests states = generate_collision_requests({.seed = 2, .requests = 40});
  const auto colliding = std::ranges::find_if(
      states.truth, [](const msgs::CollisionResult& r) { return r.in_collision; });
  ASSERT_NE(colliding, states.truth.end());
  const msgs::JointState& start =
      states.states[static_cast<std::size_t>(colliding - states.truth.begin())];
  msgs::JointTrajectory blocked;
  blocked.joint_names = arm().joint_names();
  blocked.points.resize(2);
  blocked.points[0].positions = in_model_order(arm(), start.name, start.position, "positions");
  blocked.points[1].positions = kGoal;
  const msgs::JointTrajectory free_query =
      *static_cast<const msgs::JointTrajectory*>(query_stream().messages[0].get());
  const auto run = run_node<msgs::JointTrajectory>(
      "manipulation/plan", {{"use_tf2", "true"}, {"seed", "1"}}, "query", "trajectory",
      std::vector<msgs::JointTrajectory>{blocked, free_query});
  ASSERT_EQ(run.answers.size(), 2u);
  EXPECT_TRUE(run.answers[0].points.empty());
  ASSERT_FALSE(run.answers[1].points.empty());
  EXPECT_EQ(run.answers[1].points.front().positions, kStart);
  EXPECT_EQ(run.answers[1].points.back().positions, kGoal);
}

TEST(Tf2Mode, RefusesAWorldFrameThatIsALinkOfTheArm) {
  EXPECT_THROW(testing::NodeUnderTest(category(), "manipulation/forward_kinematics",
                                      {{"use_tf2", "true"}, {"world_frame", "link3"}}),
               std::invalid_argument);
}

}  // namespace
}  // namespace robotperf::manipulation
