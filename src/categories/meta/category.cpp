// The meta category (RobotPerf m1): tf2's turtle demo as a graph — two broadcasters of simulated
// turtle poses and a listener that follows one turtle with the other through a tf2 buffer.
#include "category.hpp"

namespace robotperf::meta {

void register_category(plugin::Registrar& registrar) {
  register_kernels(registrar);
  register_datasets(registrar);
  register_evaluators(registrar);
}

}  // namespace robotperf::meta
