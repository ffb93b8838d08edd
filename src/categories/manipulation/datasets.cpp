// The manipulation datasets: seeded requests for the xArm6 around the box, with ground truth
// computed independently of the kernels under test.
#include <stdexcept>

#include "category.hpp"
#include "robotperf/manipulation/manipulation_requests.hpp"

namespace robotperf::manipulation {
namespace {

using plugin::append;
using plugin::DatasetStream;
using plugin::make_stream;

constexpr double kRateHz = 100;

ManipulationWorkload workload_of(const plugin::Parameters& p) {
  ManipulationWorkload w;
  w.seed = static_cast<uint64_t>(p.get_int("seed"));
  w.requests = static_cast<std::size_t>(p.get_int("requests"));  // >= 1: its bounds
  return w;
}

std::vector<plugin::ParameterInfo> workload_parameters(bool near_fraction) {
  const ManipulationWorkload w;
  std::vector<plugin::ParameterInfo> p{
      plugin::int_parameter("seed", static_cast<int64_t>(w.seed),
                            "seed of the request generator (and of the planner's OMPL)"),
      plugin::int_parameter("requests", static_cast<int64_t>(w.requests), "requests generated",
                            {.minimum = 1})};
  if (near_fraction) {
    p.push_back(plugin::double_parameter("near_fraction", w.near_fraction,
                                         "share of states with the flange within 0.15 m of the "
                                         "box (the rest anywhere)",
                                         {.minimum = 0, .maximum = 1}));
  }
  return p;
}

std::vector<DatasetStream> kinematics_streams(const plugin::Parameters& p) {
  auto r = generate_kinematics_requests(workload_of(p));
  auto states = make_stream<msgs::JointState>("joint_states", "/fk/joint_states");
  auto poses = make_stream<msgs::PoseStamped>("poses", "/ik/target_pose");
  for (auto& s : r.states) append(states, std::move(s));
  for (auto& q : r.poses) append(poses, std::move(q));
  return {std::move(states), std::move(poses)};
}

std::vector<DatasetStream> collision_streams(const plugin::Parameters& p) {
  ManipulationWorkload w = workload_of(p);
  w.near_fraction = p.get_double("near_fraction");
  auto r = generate_collision_requests(w);
  auto states = make_stream<msgs::JointState>("joint_states", "/collision/joint_states");
  auto truth = make_stream<msgs::CollisionResult>("truth", "/ground_truth/collision");
  for (auto& s : r.states) append(states, std::move(s));
  for (auto& t : r.truth) append(truth, std::move(t));
  return {std::move(states), std::move(truth)};
}

std::vector<DatasetStream> planning_streams(const plugin::Parameters& p) {
  auto queries = make_stream<msgs::JointTrajectory>("queries", "/plan/query");
  for (auto& q : generate_planning_queries(workload_of(p))) append(queries, std::move(q));
  return {std::move(queries)};
}

}  // namespace

void register_datasets(plugin::Registrar& registrar) {
  const std::size_t requests = ManipulationWorkload{}.requests;
  registrar.add_dataset(
      {.name = "manipulation/kinematics",
       .description = "xArm6 joint states uniform within the joint limits and their flange poses "
                      "(URDF transform chain, independent of KDL): FK requests and truth, IK "
                      "targets that have a solution",
       .rate_hz = kRateHz,
       .frames = requests,
       .streams = {{"joint_states", "/fk/joint_states", "sensor_msgs/msg/JointState", false,
                    "FK requests; the IK solutions' truth"},
                   {"poses", "/ik/target_pose", "geometry_msgs/msg/PoseStamped", false,
                    "their flange poses: IK targets and FK truth"}},
       .workload = workload_parameters(false)},
      kinematics_streams);
  registrar.add_dataset(
      {.name = "manipulation/collision",
       .description = "xArm6 joint states near (flange within 0.15 m) and far from a 0.2 x 0.2 x "
                      "0.4 m box at (0.45, 0, 0.2), each with a certain sampled ground-truth "
                      "answer",
       .rate_hz = kRateHz,
       .frames = requests,
       .streams = {{"joint_states", "/collision/joint_states", "sensor_msgs/msg/JointState", false,
                    "the states to check"},
                   {"truth", "/ground_truth/collision", "robotperf_msgs/msg/CollisionResult", true,
                    "the sampled answer of each state"}},
       .workload = workload_parameters(true)},
      collision_streams);
  registrar.add_dataset(
      {.name = "manipulation/planning",
       .description = "xArm6 planning queries around the box: start and goal (a JointTrajectory "
                      "of two points) collision-free with the flange low on either side, the "
                      "straight joint-space line between them blocked",
       .rate_hz = kRateHz,
       .frames = requests,
       .streams = {{"queries", "/plan/query", "trajectory_msgs/msg/JointTrajectory", false,
                    "start and goal"}},
       .workload = workload_parameters(false)},
      planning_streams);
}

}  // namespace robotperf::manipulation
