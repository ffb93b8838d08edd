// How a kernel's answers on a backend other than cpu are judged (docs/design.md §6): the run
// feeds a sample of its inputs through the same nodes on cpu and compares each output with the
// cpu's answer to the same input. The comparison is registered per output message type, by the
// category or plug-in that knows what a tolerable difference of that type is; a benchmark whose
// output type has none is not compared.
#pragma once

#include <functional>
#include <string>

namespace robotperf::plugin {

// How one answer agrees with the cpu's: the share of its elements within the type's tolerance,
// the least share that passes, and the tolerance in words, as results record it
// ("|difference| <= 1 on pixel channels").
struct Agreement {
  double share = 0;
  double required = 0;
  std::string criterion;
};

struct OutputComparisonInfo {
  std::string ros_type{};     // "sensor_msgs/msg/Image": a type robotperf knows
  std::string description{};  // one line
};

// `accelerated` and `cpu` point to two messages of the registered type: the other backend's
// answer and the cpu's to the same input. Answers of another size or layout agree nowhere
// (share 0); it does not throw for them.
using OutputComparison = std::function<Agreement(const void* accelerated, const void* cpu)>;

}  // namespace robotperf::plugin
