// Functional evaluators: does the graph under test still compute the right answer? The Monitor
// keeps a sample of the outputs; after timing, the benchmark's evaluator compares each with the
// ground truth of the frame it came from and reports metrics, which benchmark.yaml judges
// against thresholds.
#pragma once

#include <cstddef>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "robotperf/plugin/dataset.hpp"
#include "robotperf/plugin/parameters.hpp"

namespace robotperf::plugin {

struct MetricInfo {
  std::string name{};
  std::string unit{};
  std::string description{};
};

struct EvaluatorInfo {
  std::string name{};
  std::string description{};
  std::string output_type{};               // ROS type of the outputs it reads
  std::vector<std::string> truth_roles{};  // the dataset streams it needs, by role
  std::vector<MetricInfo> metrics{};
  // Non-empty when the evaluator reads, beside each output, the message of the same ID on a second
  // graph topic of this type (add_observed): the truth observed during the run
  // (functional.observed_truth in graph.yaml, e.g. a simulated robot's pose) or a second output
  // of the graph under test (functional.second_output, e.g. the poses of detected tags).
  std::string observed_truth_type{};
  // graph.yaml `functional: parameters:`.
  std::vector<ParameterInfo> parameters{};
  // add() is cheap (a comparison, no accumulation of outputs): the Monitor calls it as each
  // chosen output arrives, one call at a time, instead of holding the outputs until the run ends.
  // Lets a benchmark check every output of a long run or of large messages (graph.yaml
  // `sample: 0`) in bounded memory. Not for evaluators with an observed_truth_type.
  bool on_arrival = false;
};

// The dataset streams an evaluator was given for its truth roles.
class TruthStreams {
 public:
  TruthStreams(std::string evaluator, std::map<std::string, const DatasetStream*> by_role)
      : evaluator_(std::move(evaluator)), by_role_(std::move(by_role)) {}
  // Throws std::invalid_argument when no stream was given for `role`.
  const DatasetStream& operator[](const std::string& role) const;

 private:
  std::string evaluator_;
  std::map<std::string, const DatasetStream*> by_role_;
};

class FunctionalEvaluator {
 public:
  virtual ~FunctionalEvaluator();
  // One output message (of the evaluator's output type) produced from dataset frame `frame`.
  virtual void add(const void* output, std::size_t frame) = 0;
  // The same with the second topic's message of this output's message ID (evaluators with an
  // observed_truth_type); null when none was received.
  virtual void add_observed(const void* output, const void* observed_truth, std::size_t frame);
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

// Builds the evaluator; throws std::invalid_argument when a truth stream holds another type
// than the evaluator reads.
using EvaluatorFactory = std::function<std::unique_ptr<FunctionalEvaluator>(
    const TruthStreams& truth, const Parameters& parameters)>;

// Throws std::invalid_argument (naming `who`) unless `stream` holds messages of type T.
template <class T>
void require_type(const DatasetStream& stream, const std::string& who) {
  const auto& type = msgs::type_support<T>();
  if (stream.type != &type) {
    throw std::invalid_argument(who + ": truth stream '" + stream.name + "' holds " +
                                (stream.type ? stream.type->ros_type : std::string("nothing")) +
                                ", expected " + type.ros_type);
  }
}

}  // namespace robotperf::plugin
