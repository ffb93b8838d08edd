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

const ManipulationWorkload kDefaults;

// Every manipulation dataset's workload.
const plugin::ParameterStruct<ManipulationWorkload> kWorkload{
    plugin::field(&ManipulationWorkload::seed, "seed", kDefaults.seed,
                  "seed of the request generator (and of the planner's OMPL)"),
    plugin::field(&ManipulationWorkload::requests, "requests", kDefaults.requests,
                  "requests generated", {.minimum = 1})};

// The collision dataset's: its states' mix as well.
const plugin::ParameterStruct<ManipulationWorkload> kCollisionWorkload{
    kWorkload.fields(),
    plugin::field(&ManipulationWorkload::near_fraction, "near_fraction", kDefaults.near_fraction,
                  "share of states with the flange within 0.15 m of the box (the rest anywhere)",
                  {.minimum = 0, .maximum = 1})};

std::vector<DatasetStream> kinematics_streams(const plugin::Parameters& p) {
  auto r = generate_kinematics_requests(kWorkload.read(p));
  auto states = make_stream<msgs::JointState>("joint_states", "/fk/joint_states");
  auto poses = make_stream<msgs::PoseStamped>("poses", "/ik/target_pose");
  for (auto& s : r.states) append(states, std::move(s));
  for (auto& q : r.poses) append(poses, std::move(q));
  return {std::move(states), std::move(poses)};
}

std::vector<DatasetStream> collision_streams(const plugin::Parameters& p) {
  auto r = generate_collision_requests(kCollisionWorkload.read(p));
  auto states = make_stream<msgs::JointState>("joint_states", "/collision/joint_states");
  auto truth = make_stream<msgs::CollisionResult>("truth", "/ground_truth/collision");
  for (auto& s : r.states) append(states, std::move(s));
  for (auto& t : r.truth) append(truth, std::move(t));
  return {std::move(states), std::move(truth)};
}

std::vector<DatasetStream> planning_streams(const plugin::Parameters& p) {
  auto queries = make_stream<msgs::JointTrajectory>("queries", "/plan/query");
  for (auto& q : generate_planning_queries(kWorkload.read(p))) append(queries, std::move(q));
  return {std::move(queries)};
}

}  // namespace

void register_datasets(plugin::Registrar& registrar) {
  const std::size_t requests = kDefaults.requests;
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
       .workload = kWorkload.declarations()},
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
       .workload = kCollisionWorkload.declarations()},
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
       .workload = kWorkload.declarations()},
      planning_streams);
}

}  // namespace robotperf::manipulation
