#include <stdexcept>

#include "robotperf/plugin/dataset.hpp"
#include "robotperf/plugin/evaluator.hpp"

namespace robotperf::plugin {

const DatasetStream& Dataset::stream(const std::string& stream_name) const {
  std::string names;
  for (const auto& s : streams) {
    if (s.name == stream_name) return s;
    names += (names.empty() ? "" : ", ") + s.name;
  }
  throw std::invalid_argument("dataset " + name + " has no stream '" + stream_name + "' (it has " +
                              names + ")");
}

const DatasetStream& TruthStreams::operator[](const std::string& role) const {
  auto it = by_role_.find(role);
  if (it == by_role_.end() || it->second == nullptr) {
    throw std::invalid_argument("evaluator " + evaluator_ + ": no truth stream given for '" + role +
                                "'");
  }
  return *it->second;
}

FunctionalEvaluator::~FunctionalEvaluator() = default;

void FunctionalEvaluator::add_observed(const void* output, const void* observed_truth,
                                       std::size_t frame) {
  (void)observed_truth;
  add(output, frame);
}

}  // namespace robotperf::plugin
