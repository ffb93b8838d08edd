// Private to the harness: the built-in functional evaluators.
#pragma once

#include <memory>

#include "robotperf/harness/functional.hpp"

namespace robotperf::harness {

// A truth stream of the dataset by role; the spec maps roles to stream names.
struct TruthStreams {
  const FunctionalSpec* spec;
  const Dataset* dataset;
  const DatasetStream& operator[](const std::string& role) const;
};

EvaluatorInfo stereo_disparity_info();
std::unique_ptr<FunctionalEvaluator> make_stereo_disparity_evaluator(const TruthStreams& truth);

EvaluatorInfo depth_point_cloud_info();
std::unique_ptr<FunctionalEvaluator> make_depth_point_cloud_evaluator(const TruthStreams& truth);

EvaluatorInfo joint_trajectory_goals_info();
std::unique_ptr<FunctionalEvaluator> make_joint_trajectory_goals_evaluator(
    const TruthStreams& truth);

EvaluatorInfo diff_drive_odometry_info();
std::unique_ptr<FunctionalEvaluator> make_diff_drive_odometry_evaluator(const TruthStreams& truth);
// Manipulation (functional_manipulation.cpp).
EvaluatorInfo forward_kinematics_info();
std::unique_ptr<FunctionalEvaluator> make_forward_kinematics_evaluator(const TruthStreams& truth);
EvaluatorInfo inverse_kinematics_info();
std::unique_ptr<FunctionalEvaluator> make_inverse_kinematics_evaluator(const TruthStreams& truth);
EvaluatorInfo collision_info();
std::unique_ptr<FunctionalEvaluator> make_collision_evaluator(const TruthStreams& truth);
EvaluatorInfo plan_execution_info();
std::unique_ptr<FunctionalEvaluator> make_plan_execution_evaluator(const TruthStreams& truth);

}  // namespace robotperf::harness
