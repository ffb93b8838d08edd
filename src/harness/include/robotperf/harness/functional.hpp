// Functional accuracy: does the graph under test still compute the right answer?
//
// The Monitor keeps a bounded sample of the outputs it receives (chosen before the run, spread
// evenly over the measured messages); after timing, an evaluator named in graph.yaml compares
// each kept output with the dataset's ground truth for the frame it came from, and the metrics
// are judged against thresholds stated in benchmark.yaml. Evaluators are registered through the
// plug-in API (robotperf/plugin/evaluator.hpp) by the categories and by plug-ins.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "robotperf/harness/dataset.hpp"
#include "robotperf/plugin/evaluator.hpp"
#include "robotperf/rmw/transport.hpp"

namespace robotperf::harness {

struct FunctionalThreshold {
  std::optional<double> min;
  std::optional<double> max;
};

// graph.yaml `functional:` plus benchmark.yaml `functional: thresholds:`.
struct FunctionalSpec {
  std::string evaluator;
  // The evaluator's ground-truth roles -> dataset streams (one message per frame).
  std::map<std::string, std::string> truth;
  // Outputs kept for evaluation; 0 keeps every measured output.
  std::size_t sample = 16;
  std::map<std::string, FunctionalThreshold> thresholds;  // by metric name
  // Evaluators with an `observed_truth_type`: the graph topic that carries the truth observed
  // during the run (e.g. a simulator's ground-truth pose), matched to outputs by message ID.
  std::string observed_truth_topic;
  // graph.yaml `functional: parameters:`, checked against the evaluator's declarations.
  std::map<std::string, std::string> parameters;
};

// Throws std::invalid_argument for an unknown evaluator, a parameter it does not take, or a truth
// stream the dataset lacks or holds in the wrong type.
std::unique_ptr<plugin::FunctionalEvaluator> make_evaluator(const FunctionalSpec& spec,
                                                            const Dataset& dataset);

// The message IDs whose outputs are kept: `sample` measured IDs in [warmup, count) spread evenly
// (every measured ID when sample is 0 or not smaller than their number).
std::vector<uint64_t> functional_sample_ids(std::size_t count, std::size_t warmup,
                                            std::size_t sample);

struct FunctionalMetric {
  std::string name;
  std::string unit;
  double value = 0;  // NaN when not computable
  FunctionalThreshold threshold;
  bool passed = true;  // within its threshold (true when it has none)
};

struct FunctionalResult {
  std::string evaluator;
  bool on_arrival = false;    // checked as each output arrived (plugin::EvaluatorInfo)
  std::size_t requested = 0;  // outputs chosen for evaluation
  std::size_t evaluated = 0;  // of which the Monitor received and the evaluator read
  std::vector<FunctionalMetric> metrics;
  bool valid = false;
  std::vector<std::string> reasons;  // why not, one line each
};

// Output ID k is frame k mod truth_frames() of the truth streams.
std::size_t truth_frames(const FunctionalSpec& spec, const Dataset& dataset);

// The evaluator's metrics judged against the thresholds, after it was given `evaluated` of the
// `requested` outputs.
FunctionalResult judge_functional(const FunctionalSpec& spec,
                                  const plugin::FunctionalEvaluator& evaluator,
                                  std::size_t evaluated, std::size_t requested);

// An evaluation that could not be completed (its evaluator threw): invalid for `why`, with no
// metrics, after `evaluated` of the `requested` outputs.
FunctionalResult functional_failure(const FunctionalSpec& spec, std::size_t requested,
                                    std::size_t evaluated, std::string why);

// Evaluates the kept outputs (message ID, output) against the dataset.
FunctionalResult evaluate_functional(
    const FunctionalSpec& spec, const Dataset& dataset,
    const std::vector<std::pair<uint64_t, rmw::MessagePtr>>& kept, std::size_t requested,
    const std::map<uint64_t, rmw::MessagePtr>& observed_truth = {});

}  // namespace robotperf::harness
