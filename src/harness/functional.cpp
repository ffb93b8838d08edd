#include "robotperf/harness/functional.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "robotperf/plugin/registry.hpp"

namespace robotperf::harness {
namespace {

std::string number(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

const plugin::EvaluatorEntry& evaluator_entry(const std::string& name) {
  const plugin::EvaluatorEntry* entry = plugin::registry().find_evaluator(name);
  if (entry == nullptr) {
    throw std::invalid_argument("unknown functional evaluator '" + name + "' (registered: " +
                                plugin::names_of(plugin::registry().evaluators()) + ")");
  }
  return *entry;
}

plugin::TruthStreams truth_streams(const FunctionalSpec& spec, const Dataset& dataset) {
  std::map<std::string, const DatasetStream*> by_role;
  for (const auto& [role, stream] : spec.truth) by_role[role] = &dataset.stream(stream);
  return plugin::TruthStreams(spec.evaluator, std::move(by_role));
}

}  // namespace

std::unique_ptr<plugin::FunctionalEvaluator> make_evaluator(const FunctionalSpec& spec,
                                                            const Dataset& dataset) {
  const plugin::EvaluatorEntry& entry = evaluator_entry(spec.evaluator);
  const plugin::TruthStreams truth = truth_streams(spec, dataset);
  for (const auto& role : entry.info.truth_roles) {
    const DatasetStream& s = truth[role];
    if (s.messages.empty()) {
      throw std::invalid_argument("evaluator " + spec.evaluator + ": truth stream '" + s.name +
                                  "' is empty");
    }
  }
  const plugin::Parameters parameters(entry.info.parameters, spec.parameters,
                                      "evaluator " + spec.evaluator);
  auto evaluator = entry.make(truth, parameters);
  if (!evaluator)
    throw std::runtime_error("evaluator " + spec.evaluator + " (" + entry.origin +
                             ") made nothing");
  return evaluator;
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

std::size_t truth_frames(const FunctionalSpec& spec, const Dataset& dataset) {
  const plugin::EvaluatorInfo& info = evaluator_entry(spec.evaluator).info;
  return truth_streams(spec, dataset)[info.truth_roles.front()].messages.size();
}

FunctionalResult evaluate_functional(const FunctionalSpec& spec, const Dataset& dataset,
                                     const std::vector<std::pair<uint64_t, rmw::MessagePtr>>& kept,
                                     std::size_t requested,
                                     const std::map<uint64_t, rmw::MessagePtr>& observed_truth) {
  const auto evaluator = make_evaluator(spec, dataset);
  const plugin::EvaluatorInfo& info = evaluator_entry(spec.evaluator).info;
  const std::size_t frames = truth_frames(spec, dataset);
  for (const auto& [id, msg] : kept) {
    if (info.observed_truth_type.empty()) {
      evaluator->add(msg.get(), static_cast<std::size_t>(id % frames));
    } else {
      auto truth = observed_truth.find(id);
      evaluator->add_observed(msg.get(),
                              truth == observed_truth.end() ? nullptr : truth->second.get(),
                              static_cast<std::size_t>(id % frames));
    }
  }
  return judge_functional(spec, *evaluator, kept.size(), requested);
}

FunctionalResult functional_failure(const FunctionalSpec& spec, std::size_t requested,
                                    std::size_t evaluated, std::string why) {
  FunctionalResult r;
  r.evaluator = spec.evaluator;
  r.on_arrival = evaluator_entry(spec.evaluator).info.on_arrival;
  r.requested = requested;
  r.evaluated = evaluated;
  r.reasons.push_back(std::move(why));
  return r;
}

FunctionalResult judge_functional(const FunctionalSpec& spec,
                                  const plugin::FunctionalEvaluator& evaluator,
                                  std::size_t evaluated, std::size_t requested) {
  FunctionalResult r;
  r.evaluator = spec.evaluator;
  r.requested = requested;
  r.evaluated = evaluated;
  const plugin::EvaluatorInfo& info = evaluator_entry(spec.evaluator).info;
  r.on_arrival = info.on_arrival;
  const auto values = evaluator.metrics();
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
  for (const auto& p : evaluator.problems()) r.reasons.push_back(p);
  if (r.evaluated == 0) {
    r.reasons.insert(r.reasons.begin(), "no output could be evaluated (none of the " +
                                            std::to_string(requested) + " chosen outputs arrived)");
  }
  r.valid = r.reasons.empty();
  return r;
}

}  // namespace robotperf::harness
