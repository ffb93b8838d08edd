#include "robotperf/manipulation/manipulation_requests.hpp"

#include <Eigen/Geometry>
#include <random>
#include <stdexcept>

#include "robotperf/manipulation/collision.hpp"
#include "robotperf/manipulation/planning.hpp"
#include "robotperf/msgs/eigen_geometry.hpp"

namespace robotperf::manipulation {
namespace {

// Uniform draws through the raw 64-bit engine, so the stream is the same with every standard
// library (std::uniform_real_distribution is implementation-defined).
double uniform(std::mt19937_64& rng, double lo, double hi) {
  return lo + (hi - lo) * (static_cast<double>(rng() >> 11) * 0x1.0p-53);
}

std::vector<double> random_state(const RobotModel& m, std::mt19937_64& rng) {
  std::vector<double> q;
  for (const auto& l : m.limits()) q.push_back(uniform(rng, l.lower, l.upper));
  return q;
}

msgs::JointState joint_state(const RobotModel& m, std::vector<double> q) {
  msgs::JointState s;
  s.header.frame_id = m.base_link();
  s.name = m.joint_names();
  s.position = std::move(q);
  return s;
}

void check(const ManipulationWorkload& w) {
  if (w.requests == 0) throw std::invalid_argument("workload: requests must be >= 1");
  if (!(w.near_fraction >= 0 && w.near_fraction <= 1))
    throw std::invalid_argument("workload: near_fraction must be within [0, 1]");
}

}  // namespace

KinematicsRequests generate_kinematics_requests(const ManipulationWorkload& w) {
  check(w);
  const RobotModel& m = RobotModel::xarm6();
  std::mt19937_64 rng(w.seed);
  KinematicsRequests out;
  for (std::size_t i = 0; i < w.requests; ++i) {
    auto q = random_state(m, rng);
    const Eigen::Isometry3d t = m.tip_pose(q.data());
    msgs::PoseStamped p;
    p.header.frame_id = m.base_link();
    p.pose = msgs::pose_msg_of(t);
    out.poses.push_back(p);
    out.states.push_back(joint_state(m, std::move(q)));
  }
  return out;
}

CollisionRequests generate_collision_requests(const ManipulationWorkload& w) {
  check(w);
  const RobotModel& m = RobotModel::xarm6();
  const manipulation::Scene scene = manipulation::default_scene();
  const auto& box = scene.objects.front().shape;
  std::mt19937_64 rng(w.seed);
  CollisionRequests out;
  const auto near_wanted =
      static_cast<std::size_t>(w.near_fraction * static_cast<double>(w.requests) + 0.5);
  std::size_t near = 0;
  while (out.states.size() < w.requests) {
    auto q = random_state(m, rng);
    const Eigen::Vector3d tip = m.tip_pose(q.data()).translation();
    const bool is_near = manipulation::signed_distance(box, box.origin.inverse() * tip) < 0.15;
    // Near and far states interleaved, so that every prefix (a run of fewer frames) has about
    // the near share: the next state is near when, were it far, the share of near ones up to it
    // would fall below near_wanted / requests.
    const bool want_near = near * w.requests < near_wanted * (out.states.size() + 1);
    if (want_near != is_near) continue;
    const auto truth = manipulation::sampled_ground_truth(m, scene, q.data());
    if (truth.truth == manipulation::GroundTruth::kUncertain) continue;
    msgs::CollisionResult r;
    r.header.frame_id = m.base_link();
    r.in_collision = truth.truth == manipulation::GroundTruth::kColliding;
    out.truth.push_back(r);
    out.states.push_back(joint_state(m, std::move(q)));
    near += is_near;
  }
  return out;
}

std::vector<msgs::JointTrajectory> generate_planning_queries(const ManipulationWorkload& w) {
  check(w);
  const RobotModel& m = RobotModel::xarm6();
  const manipulation::Scene scene = manipulation::default_scene();
  auto checker = manipulation::make_fcl_checker(m, scene);
  // Start and goal keep clear of the box and the other links by a margin, so that a planner
  // checking with link padding up to kPlanningQueryClearance accepts them.
  auto padded = manipulation::make_fcl_checker(m, scene, kPlanningQueryClearance);
  std::mt19937_64 rng(w.seed);
  // A free state with the flange low in front of the arm, beside the box on the side `side`.
  auto beside = [&](double side) {
    for (;;) {
      auto q = random_state(m, rng);
      const Eigen::Vector3d tip = m.tip_pose(q.data()).translation();
      if (side * tip.y() < 0.15 || side * tip.y() > 0.45 || tip.x() < 0.3 || tip.x() > 0.6 ||
          tip.z() < 0.05 || tip.z() > 0.35)
        continue;
      if (!padded->check(q.data()).in_collision &&
          manipulation::sampled_ground_truth(m, scene, q.data()).truth ==
              manipulation::GroundTruth::kFree)
        return q;
    }
  };
  std::vector<msgs::JointTrajectory> out;
  while (out.size() < w.requests) {
    const double side = out.size() % 2 == 0 ? 1.0 : -1.0;
    auto start = beside(side);
    auto goal = beside(-side);
    if (manipulation::path_valid(m, *checker, {start, goal}, 0.01)) continue;
    msgs::JointTrajectory query;
    query.header.frame_id = m.base_link();
    query.joint_names = m.joint_names();
    query.points.resize(2);
    query.points[0].positions = std::move(start);
    query.points[1].positions = std::move(goal);
    out.push_back(std::move(query));
  }
  return out;
}

}  // namespace robotperf::manipulation
