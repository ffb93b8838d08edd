#include "robotperf/harness/functional.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "evaluators.hpp"

namespace robotperf::harness {
namespace {

using Factory = std::unique_ptr<FunctionalEvaluator> (*)(const TruthStreams&);

struct Entry {
  EvaluatorInfo info;
  Factory factory;
};

const std::vector<Entry>& entries() {
  static const std::vector<Entry> table{
      {stereo_disparity_info(), make_stereo_disparity_evaluator},
      {depth_point_cloud_info(), make_depth_point_cloud_evaluator},
      {joint_trajectory_goals_info(), make_joint_trajectory_goals_evaluator},
      {diff_drive_odometry_info(), make_diff_drive_odometry_evaluator},
      {forward_kinematics_info(), make_forward_kinematics_evaluator},
      {inverse_kinematics_info(), make_inverse_kinematics_evaluator},
      {collision_info(), make_collision_evaluator},
      {plan_execution_info(), make_plan_execution_evaluator},
  };
  return table;
}

std::string number(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

}  // namespace

const DatasetStream& TruthStreams::operator[](const std::string& role) const {
  auto it = spec->truth.find(role);
  if (it == spec->truth.end()) {
    throw std::invalid_argument("evaluator " + spec->evaluator + ": no truth stream given for '" +
                                role + "'");
  }
  return dataset->stream(it->second);
}

const std::vector<EvaluatorInfo>& evaluator_infos() {
  static const std::vector<EvaluatorInfo> infos = [] {
    std::vector<EvaluatorInfo> out;
    for (const auto& e : entries()) out.push_back(e.info);
    return out;
  }();
  return infos;
}

const EvaluatorInfo* find_evaluator(const std::string& name) {
  for (const auto& info : evaluator_infos()) {
    if (info.name == name) return &info;
  }
  return nullptr;
}

std::unique_ptr<FunctionalEvaluator> make_evaluator(const FunctionalSpec& spec,
                                                    const Dataset& dataset) {
  for (const auto& e : entries()) {
    if (e.info.name != spec.evaluator) continue;
    const TruthStreams truth{&spec, &dataset};
    for (const auto& role : e.info.truth_roles) {
      const DatasetStream& s = truth[role];
      if (s.messages.empty()) {
        throw std::invalid_argument("evaluator " + spec.evaluator + ": truth stream '" + s.name +
                                    "' is empty");
      }
    }
    return e.factory(truth);
  }
  std::string known;
  for (const auto& e : entries()) known += (known.empty() ? "" : ", ") + e.info.name;
  throw std::invalid_argument("unknown functional evaluator '" + spec.evaluator +
                              "' (known: " + known + ")");
}

std::vector<uint64_t> functional_sample_ids(std::size_t count, std::size_t warmup,
                                            std::size_t sample) {
  std::vector<uint64_t> ids;
  if (warmup >= count) return ids;
  const std::size_t measured = count - warmup;
  const std::size_t n = (sample == 0 || sample >= measured) ? measured : sample;
  for (std::size_t j = 0; j < n; ++j) ids.push_back(warmup + j * measured / n);
  return ids;
}

FunctionalResult evaluate_functional(const FunctionalSpec& spec, const Dataset& dataset,
                                     const std::vector<std::pair<uint64_t, rmw::MessagePtr>>& kept,
                                     std::size_t requested,
                                     const std::map<uint64_t, rmw::MessagePtr>& observed_truth) {
  FunctionalResult r;
  r.evaluator = spec.evaluator;
  r.requested = requested;
  const auto evaluator = make_evaluator(spec, dataset);
  const EvaluatorInfo& info = *find_evaluator(spec.evaluator);
  const std::size_t frames =
      TruthStreams{&spec, &dataset}[info.truth_roles.front()].messages.size();
  for (const auto& [id, msg] : kept) {
    if (info.observed_truth_type.empty()) {
      evaluator->add(msg.get(), static_cast<std::size_t>(id % frames));
    } else {
      auto truth = observed_truth.find(id);
      evaluator->add_observed(msg.get(),
                              truth == observed_truth.end() ? nullptr : truth->second.get(),
                              static_cast<std::size_t>(id % frames));
    }
    ++r.evaluated;
  }
  const auto values = evaluator->metrics();
  for (const auto& m : info.metrics) {
    FunctionalMetric metric{m.name, m.unit, std::nan(""), {}, true};
    if (auto it = values.find(m.name); it != values.end()) metric.value = it->second;
    if (auto it = spec.thresholds.find(m.name); it != spec.thresholds.end()) {
      metric.threshold = it->second;
      const double v = metric.value;
      const auto& t = metric.threshold;
      if (std::isnan(v)) {
        metric.passed = false;
        r.reasons.push_back(m.name + " could not be computed");
      } else if (t.min && v < *t.min) {
        metric.passed = false;
        r.reasons.push_back(m.name + " " + number(v) + " " + m.unit + " is below the minimum " +
                            number(*t.min));
      } else if (t.max && v > *t.max) {
        metric.passed = false;
        r.reasons.push_back(m.name + " " + number(v) + " " + m.unit + " is above the maximum " +
                            number(*t.max));
      }
    }
    r.metrics.push_back(std::move(metric));
  }
  for (const auto& p : evaluator->problems()) r.reasons.push_back(p);
  if (r.evaluated == 0) {
    r.reasons.insert(r.reasons.begin(), "no output could be evaluated (none of the " +
                                            std::to_string(requested) +
                                            " sampled outputs arrived)");
  }
  r.valid = r.reasons.empty();
  return r;
}

}  // namespace robotperf::harness
