// The manipulation kernels without the graph: robot model, FK, IK, collision, planning.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <atomic>
#include <cmath>
#include <latch>
#include <random>
#include <thread>

#include "../shared_data.hpp"
#include "robotperf/manipulation/collision.hpp"
#include "robotperf/manipulation/kinematics.hpp"
#include "robotperf/manipulation/manipulation_requests.hpp"
#include "robotperf/manipulation/planning.hpp"

namespace robotperf::manipulation {
namespace {

const RobotModel& arm() {
  return RobotModel::xarm6();
}

std::vector<double> random_state(std::mt19937_64& rng) {
  std::vector<double> q;
  for (const auto& l : arm().limits())
    q.push_back(std::uniform_real_distribution<double>(l.lower, l.upper)(rng));
  return q;
}

TEST(RobotModel, MatchesThePublishedXarm6Description) {
  const YAML::Node yaml = YAML::LoadFile(shared_data("xarm6/xarm6_kinematics.yaml").string());
  ASSERT_EQ(arm().dof(), 6u);
  EXPECT_EQ(arm().links().size(), 7u);
  EXPECT_EQ(arm().tip_link(), "link6");
  for (std::size_t i = 0; i < 6; ++i) {
    const std::string name = "joint" + std::to_string(i + 1);
    EXPECT_EQ(arm().joint_names()[i], name);
    EXPECT_NEAR(arm().limits()[i].lower, yaml["joint_limits"][name][0].as<double>(), 1e-9);
    EXPECT_NEAR(arm().limits()[i].upper, yaml["joint_limits"][name][1].as<double>(), 1e-9);
    EXPECT_DOUBLE_EQ(arm().limits()[i].max_velocity, yaml["max_velocity"].as<double>());
    EXPECT_DOUBLE_EQ(arm().limits()[i].max_acceleration, yaml["max_acceleration"].as<double>());
  }
  // Adjacent links may touch, others not.
  EXPECT_TRUE(arm().collision_allowed(2, 3));
  EXPECT_FALSE(arm().collision_allowed(2, 4));
  EXPECT_FALSE(arm().collision_allowed(0, 6));
}

TEST(RobotModel, BadUrdfIsOneClearError) {
  EXPECT_THROW(RobotModel::from_urdf("<robot", "a", "b", 1.0), std::invalid_argument);
  try {
    RobotModel::from_urdf("<robot name='r'><link name='a'/></robot>", "a", "b", 1.0);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("no tip link 'b'"), std::string::npos) << e.what();
  }
}

// Fixed joints before the first moving joint (a base mount), between two and after the last (a
// tool): each counts once in the KDL chain, as in the transform chain.
TEST(RobotModel, FixedJointsCountOnceInTheKdlChain) {
  const char* const urdf = R"(<robot name="mounted">
    <link name="base"/><link name="mount"/><link name="l1"/><link name="wrist"/><link name="l2"/>
    <link name="tool"/>
    <joint name="base_mount" type="fixed"><parent link="base"/><child link="mount"/>
      <origin xyz="0 0 0.1" rpy="0 0 0.3"/></joint>
    <joint name="j1" type="revolute"><parent link="mount"/><child link="l1"/>
      <origin xyz="0.2 0 0"/><axis xyz="0 0 1"/>
      <limit lower="-3" upper="3" velocity="1" effort="1"/></joint>
    <joint name="wrist_mount" type="fixed"><parent link="l1"/><child link="wrist"/>
      <origin xyz="0 0.05 0.1" rpy="0.4 0 0"/></joint>
    <joint name="j2" type="revolute"><parent link="wrist"/><child link="l2"/>
      <origin xyz="0.3 0 0" rpy="0 0.2 0"/><axis xyz="0 1 0"/>
      <limit lower="-3" upper="3" velocity="1" effort="1"/></joint>
    <joint name="tool_mount" type="fixed"><parent link="l2"/><child link="tool"/>
      <origin xyz="0.1 0 0" rpy="0 0 0.5"/></joint>
  </robot>)";
  const RobotModel m = RobotModel::from_urdf(urdf, "base", "tool", 1.0);
  ASSERT_EQ(m.dof(), 2u);
  ForwardKinematics fk(m);
  std::mt19937_64 rng(5);
  for (int i = 0; i < 50; ++i) {
    const double q[2] = {std::uniform_real_distribution<double>(-3, 3)(rng),
                         std::uniform_real_distribution<double>(-3, 3)(rng)};
    const Eigen::Isometry3d kdl = fk.tip_pose(q), eigen = m.tip_pose(q);
    ASSERT_LT((kdl.matrix() - eigen.matrix()).cwiseAbs().maxCoeff(), 1e-12) << "state " << i;
  }
}

TEST(RobotModel, InModelOrderMapsJointsByName) {
  const auto& names = arm().joint_names();
  const std::vector<double> q{0.1, 0.2, 0.3, 0.4, 0.5, 0.6};
  EXPECT_EQ(in_model_order(arm(), {}, q, "positions"), q);
  // Another order, and a joint the arm does not have (a gripper's), which is ignored.
  const std::vector<std::string> shuffled{names[5], names[4], "gripper", names[3],
                                          names[2], names[1], names[0]};
  EXPECT_EQ(in_model_order(arm(), shuffled, {0.6, 0.5, 9.0, 0.4, 0.3, 0.2, 0.1}, "positions"), q);
  EXPECT_THROW(in_model_order(arm(), {}, {0.1, 0.2}, "positions"), std::invalid_argument);
  EXPECT_THROW(in_model_order(arm(), shuffled, q, "positions"), std::invalid_argument);
  std::vector<std::string> missing = names;
  missing[2] = "elbow";
  EXPECT_THROW(in_model_order(arm(), missing, q, "positions"), std::invalid_argument);
  std::vector<double> nan = q;
  nan[3] = std::nan("");
  EXPECT_THROW(in_model_order(arm(), names, nan, "positions"), std::invalid_argument);
  nan[3] = INFINITY;
  EXPECT_THROW(in_model_order(arm(), {}, nan, "velocities"), std::invalid_argument);
}

TEST(ForwardKinematics, HandComputedPoses) {
  ForwardKinematics fk(arm());
  // q = 0: joint2..6 offsets along the published origins put the flange at x = 0.0535 + 0.0775
  // + 0.076, z = 0.267 + 0.2845 - 0.3425 - 0.097, pointing straight down (z_tip = -Z, y_tip = -Y).
  const std::vector<double> zero(6, 0.0);
  const Eigen::Isometry3d p0 = fk.tip_pose(zero.data());
  EXPECT_NEAR(p0.translation().x(), 0.207, 1e-9);
  // (The published roll angles are 1.5708, not pi/2: 6e-7 m off the ideal figures.)
  EXPECT_NEAR(p0.translation().y(), 0.0, 1e-6);
  EXPECT_NEAR(p0.translation().z(), 0.112, 1e-9);
  EXPECT_TRUE(p0.linear().col(2).isApprox(Eigen::Vector3d(0, 0, -1), 1e-4));
  EXPECT_TRUE(p0.linear().col(1).isApprox(Eigen::Vector3d(0, -1, 0), 1e-4));
  // joint1 turns the whole arm about the base's z.
  std::vector<double> q(6, 0.0);
  q[0] = M_PI / 2;
  const Eigen::Isometry3d p1 = fk.tip_pose(q.data());
  EXPECT_NEAR(p1.translation().x(), 0.0, 1e-6);
  EXPECT_NEAR(p1.translation().y(), 0.207, 1e-9);
  EXPECT_NEAR(p1.translation().z(), 0.112, 1e-9);
  // joint6 spins the flange about its own axis: position unchanged, x axis turned.
  q.assign(6, 0.0);
  q[5] = M_PI / 2;
  const Eigen::Isometry3d p6 = fk.tip_pose(q.data());
  EXPECT_TRUE(p6.translation().isApprox(p0.translation(), 1e-9));
  EXPECT_TRUE(p6.linear().col(0).isApprox(p0.linear().col(1), 1e-4));
}

TEST(ForwardKinematics, KdlAgreesWithTheIndependentTransformChain) {
  ForwardKinematics fk(arm());
  std::mt19937_64 rng(7);
  for (int i = 0; i < 200; ++i) {
    const auto q = random_state(rng);
    double dp, dr;
    pose_error(fk.tip_pose(q.data()), arm().tip_pose(q.data()), dp, dr);
    EXPECT_LT(dp, 1e-12);
    EXPECT_LT(dr, 1e-6);
  }
}

// Two nodes of one process run their solvers in two threads: each solver on its own copy of the
// chain (KDL's joints cache their last pose), so neither sees the other's joint angles.
TEST(ForwardKinematics, SolversInTwoThreadsAgreeWithTheTransformChain) {
  std::atomic<int> mismatches{0}, wrong_solutions{0}, solved{0};
  std::latch ready(2);  // both solvers built, then both run at once
  auto work = [&](uint64_t seed) {
    ForwardKinematics fk(arm());
    IkOptions options;
    options.seed = seed;
    InverseKinematics ik(arm(), options);
    std::mt19937_64 rng(seed);
    const std::vector<double> zero(6, 0.0);
    ready.arrive_and_wait();
    for (int i = 0; i < 100000; ++i) {
      const auto q = random_state(rng);
      double dp, dr;
      pose_error(fk.tip_pose(q.data()), arm().tip_pose(q.data()), dp, dr);
      mismatches += dp > 1e-12 || dr > 1e-6;
      if (i % 1000 != 0) continue;
      const IkResult r = ik.solve(arm().tip_pose(q.data()), zero);
      if (!r.success) continue;
      ++solved;
      pose_error(arm().tip_pose(r.q.data()), arm().tip_pose(q.data()), dp, dr);
      wrong_solutions += dp > 1e-4 || dr > 1e-4;
    }
  };
  std::thread a(work, 1), b(work, 2);
  a.join();
  b.join();
  EXPECT_EQ(mismatches.load(), 0);
  EXPECT_EQ(wrong_solutions.load(), 0);
  EXPECT_GT(solved.load(), 150);
}

// LMA's eps bounds the weighted error with KDL's default weights (orientation 0.01), so its
// orientation error may be up to 100 eps.
void ik_round_trip(IkSolver solver, double min_success_rate, double orientation_tolerance) {
  IkOptions options;
  options.solver = solver;
  options.seed = 11;
  InverseKinematics ik(arm(), options);
  ForwardKinematics fk(arm());
  std::mt19937_64 rng(42);
  const int targets = 200;
  int solved = 0;
  double worst_position = 0, worst_orientation = 0;
  const std::vector<double> seed(6, 0.0);
  for (int i = 0; i < targets; ++i) {
    const auto q = random_state(rng);
    const Eigen::Isometry3d target = fk.tip_pose(q.data());
    const IkResult r = ik.solve(target, seed);
    if (!r.success) continue;
    ++solved;
    ASSERT_TRUE(arm().within_limits(r.q.data(), 1e-9));
    double dp, dr;
    pose_error(fk.tip_pose(r.q.data()), target, dp, dr);
    EXPECT_NEAR(dp, r.position_error, 1e-12);
    worst_position = std::max(worst_position, dp);
    worst_orientation = std::max(worst_orientation, dr);
  }
  const double rate = static_cast<double>(solved) / targets;
  ::testing::Test::RecordProperty("success_rate", std::to_string(rate));
  std::printf("IK %s: success %.3f over %d targets, worst error %.3g m %.3g rad\n",
              solver == IkSolver::kNewtonRaphsonJL ? "NR_JL" : "LMA", rate, targets, worst_position,
              worst_orientation);
  EXPECT_GE(rate, min_success_rate);
  EXPECT_LT(worst_position, 1e-4);
  EXPECT_LT(worst_orientation, orientation_tolerance);
}

// Both solve over 99 % of the targets here (NR-JL in about 0.3 ms each); the bound leaves room
// for timeouts on a loaded machine.
TEST(InverseKinematics, NewtonRaphsonRoundTrip) {
  ik_round_trip(IkSolver::kNewtonRaphsonJL, 0.9, 1e-4);
}
TEST(InverseKinematics, LevenbergMarquardtRoundTrip) {
  ik_round_trip(IkSolver::kLevenbergMarquardt, 0.9, 2e-3);
}

// Steps that cross +-pi on the nearly continuous joints are wrapped, not clamped: a target whose
// joint 1 and 4 angles lie just across pi from the seed is solved from that seed alone.
TEST(InverseKinematics, NewtonRaphsonWrapsNearlyContinuousJoints) {
  IkOptions options;
  options.timeout_s = 10;  // the first attempt decides; the timeout only must not cut it
  InverseKinematics ik(arm(), options);
  ForwardKinematics fk(arm());
  const std::vector<double> target_q{-3.0, 0.3, -0.8, 3.0, 1.0, -3.0};
  const std::vector<double> seed{3.0, 0.3, -0.8, -3.0, 1.0, 3.0};
  const IkResult r = ik.solve(fk.tip_pose(target_q.data()), seed);
  ASSERT_TRUE(r.success);
  EXPECT_EQ(r.attempts, 1u);
  EXPECT_TRUE(arm().within_limits(r.q.data()));
}

TEST(Collision, ConstructedStates) {
  const Scene scene = default_scene();
  for (auto backend : {CollisionBackend::kFcl, CollisionBackend::kBullet}) {
    auto checker = make_collision_checker(backend, arm(), scene);
    SCOPED_TRACE(checker->backend());
    const std::vector<double> zero(6, 0.0);
    EXPECT_FALSE(checker->check(zero.data()).in_collision);
    // Reaching forward and down into the pillar at x = 0.35..0.55.
    std::vector<double> reach{0, 0.6, -0.8, 0, 0.8, 0};
    const CollisionAnswer a = checker->check(reach.data());
    EXPECT_TRUE(a.in_collision);
    EXPECT_TRUE(a.with_scene);
    // Leaning back until the wrist meets the base.
    std::vector<double> folded{0, 1.6, -0.2, 0, 0, 0};
    const CollisionAnswer f = checker->check(folded.data());
    EXPECT_TRUE(f.in_collision);
    EXPECT_FALSE(f.with_scene);
    EXPECT_EQ(sampled_ground_truth(arm(), scene, reach.data()).truth, GroundTruth::kColliding);
    EXPECT_EQ(sampled_ground_truth(arm(), scene, folded.data()).truth, GroundTruth::kColliding);
    EXPECT_EQ(sampled_ground_truth(arm(), scene, zero.data()).truth, GroundTruth::kFree);
  }
}

TEST(Collision, FclAndBulletAgreeWithSampledGroundTruth) {
  const Scene scene = default_scene();
  auto fcl = make_fcl_checker(arm(), scene);
  auto bullet = make_bullet_checker(arm(), scene);
  std::mt19937_64 rng(3);
  int free = 0, scene_hits = 0, self_hits = 0;
  for (int i = 0; i < 300; ++i) {
    const auto q = random_state(rng);
    const GroundTruth truth = sampled_ground_truth(arm(), scene, q.data()).truth;
    if (truth == GroundTruth::kUncertain) continue;
    const CollisionAnswer a = fcl->check(q.data());
    const CollisionAnswer b = bullet->check(q.data());
    EXPECT_EQ(a.in_collision, truth == GroundTruth::kColliding) << "fcl, state " << i;
    EXPECT_EQ(b.in_collision, truth == GroundTruth::kColliding) << "bullet, state " << i;
    EXPECT_EQ(a.with_scene, b.with_scene) << "state " << i;
    free += !a.in_collision;
    scene_hits += a.in_collision && a.with_scene;
    self_hits += a.in_collision && !a.with_scene;
  }
  EXPECT_GT(free, 30);
  EXPECT_GT(scene_hits, 5);
  EXPECT_GT(self_hits, 5);
}

TEST(Planning, PathAroundTheBoxIsValidAtAFineStep) {
  const Scene scene = default_scene();
  PlanOptions options;
  options.planning_time_s = 5.0;
  // As d1 plans: links padded by more than any state between two motion checks is from the
  // nearer of them (0.0005 of the extent, 0.0065 rad, moves a point up to about 7 mm: 3.5 mm).
  options.longest_valid_segment_fraction = 0.0005;
  Planner planner(arm(), make_fcl_checker(arm(), scene, 0.005), options);
  // Either side of the pillar, the flange low: the straight joint-space line goes through it.
  const std::vector<double> start{0.9, 0.7, -0.9, 0, 1.4, 0};
  const std::vector<double> goal{-0.9, 0.7, -0.9, 0, 1.4, 0};
  auto checker = make_bullet_checker(arm(), scene);
  ASSERT_FALSE(checker->check(start.data()).in_collision);
  ASSERT_FALSE(checker->check(goal.data()).in_collision);
  ASSERT_FALSE(path_valid(arm(), *checker, {start, goal}, 0.005));
  const PlanResult r = planner.plan(start, goal);
  ASSERT_TRUE(r.success);
  EXPECT_EQ(r.path.front(), start);
  EXPECT_EQ(r.path.back(), goal);
  std::vector<double> bad;
  EXPECT_TRUE(path_valid(arm(), *checker, r.path, 0.002, &bad));
  EXPECT_TRUE(path_valid(arm(), *make_fcl_checker(arm(), scene), r.path, 0.002, &bad));
  // The padded model the planner checked with holds at its waypoints; between motion checks only
  // the unpadded arm is guaranteed clear (the padding covers how far it moves between them).
  for (const auto& state : r.path) EXPECT_FALSE(planner.checker().check(state.data()).in_collision);
  EXPECT_GT(path_length(r.path), 1.8);

  const auto trajectory = time_parameterize(r.path, arm().limits(), 0.01);
  ASSERT_GE(trajectory.size(), r.path.size());
  for (std::size_t k = 0; k < trajectory.size(); ++k) {
    for (std::size_t j = 0; j < 6; ++j) {
      EXPECT_LE(std::abs(trajectory[k].velocity[j]), arm().limits()[j].max_velocity + 1e-9);
      EXPECT_LE(std::abs(trajectory[k].acceleration[j]), arm().limits()[j].max_acceleration + 1e-9);
    }
    if (k > 0) {
      EXPECT_GT(trajectory[k].time_s, trajectory[k - 1].time_s);
    }
  }
  EXPECT_EQ(trajectory.back().position, goal);
  std::size_t steps = 0;
  const ExecutionResult e =
      execute(trajectory, ExecutionOptions{}, [&](const ExecutionStep&) { ++steps; });
  EXPECT_EQ(steps, e.steps);
  EXPECT_GT(e.steps, 10u);
  EXPECT_GT(e.max_tracking_error, 0.0);
  EXPECT_LT(e.max_tracking_error, 0.1);
  EXPECT_LT(e.final_error, 1e-3);
}

// Near and far states alternate in the share asked for, so that a run of fewer frames than the
// dataset (--count) measures the same mix.
TEST(ManipulationRequests, CollisionStatesInterleaveNearAndFar) {
  ManipulationWorkload w;
  w.requests = 40;
  w.near_fraction = 0.25;
  const CollisionRequests r = generate_collision_requests(w);
  ASSERT_EQ(r.states.size(), 40u);
  const auto scene = default_scene();  // kept: the box is a reference into it
  const Shape& box = scene.objects.front().shape;
  std::size_t near = 0;
  for (std::size_t k = 0; k < r.states.size(); ++k) {
    const Eigen::Vector3d tip = arm().tip_pose(r.states[k].position.data()).translation();
    near += signed_distance(box, box.origin.inverse() * tip) < 0.15;
    EXPECT_EQ(near, (k + 1 + 3) / 4) << "the first " << k + 1 << " states";
  }
}

}  // namespace
}  // namespace robotperf::manipulation
