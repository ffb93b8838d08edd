// Functional accuracy: does the graph under test still compute the right answer?
//
// The Monitor keeps a bounded sample of the outputs it receives (chosen before the run, spread
// evenly over the measured messages); after timing, an evaluator named in graph.yaml compares
// each kept output with the dataset's ground truth for the frame it came from, and the metrics
// are judged against thresholds stated in benchmark.yaml. Evaluators are generic over message
// types: a new benchmark category adds an evaluator and a dataset with ground-truth streams.
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
};

struct FunctionalMetricInfo {
  std::string name;
  std::string unit;
  std::string description;
};

struct EvaluatorInfo {
  std::string name;
  std::string description;
  std::string output_type;               // ROS type of the outputs it reads
  std::vector<std::string> truth_roles;  // the dataset streams it needs
  std::vector<FunctionalMetricInfo> metrics;
  // Non-empty when the truth is observed during the run on a graph topic of this type
  // (functional.observed_truth in graph.yaml) instead of read from the dataset alone.
  std::string observed_truth_type;
};

const std::vector<EvaluatorInfo>& evaluator_infos();
const EvaluatorInfo* find_evaluator(const std::string& name);

class FunctionalEvaluator {
 public:
  virtual ~FunctionalEvaluator() = default;
  // One output message (of the evaluator's output type) produced from dataset frame `frame`.
  virtual void add(const void* output, std::size_t frame) = 0;
  // The same with the truth observed for this output's message ID (evaluators with an
  // observed_truth_type); null when none was received.
  virtual void add_observed(const void* output, const void* observed_truth, std::size_t frame) {
    (void)observed_truth;
    add(output, frame);
  }
  // Every metric of the evaluator's info over the outputs added; NaN when not computable.
  virtual std::map<std::string, double> metrics() const = 0;
  // Defects that make outputs wrong whatever the metrics say (wrong size, encoding, geometry),
  // each described once.
  const std::set<std::string>& problems() const { return problems_; }

 protected:
  void problem(std::string what) { problems_.insert(std::move(what)); }

 private:
  std::set<std::string> problems_;
};

// Throws std::invalid_argument for an unknown evaluator or a truth stream the dataset lacks or
// holds in the wrong type.
std::unique_ptr<FunctionalEvaluator> make_evaluator(const FunctionalSpec& spec,
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
  std::size_t requested = 0;  // outputs chosen for evaluation
  std::size_t evaluated = 0;  // of which the Monitor received and the evaluator read
  std::vector<FunctionalMetric> metrics;
  bool valid = false;
  std::vector<std::string> reasons;  // why not, one line each
};

// Evaluates the kept outputs (message ID, output) against the dataset: output ID k is frame
// k mod (frames of the truth streams).
FunctionalResult evaluate_functional(
    const FunctionalSpec& spec, const Dataset& dataset,
    const std::vector<std::pair<uint64_t, rmw::MessagePtr>>& kept, std::size_t requested,
    const std::map<uint64_t, rmw::MessagePtr>& observed_truth = {});

}  // namespace robotperf::harness
