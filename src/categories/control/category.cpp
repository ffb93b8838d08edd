// The control category (RobotPerf c1-c5): a controller manager loop with ros2_controllers'
// joint trajectory, diff drive and forward command controllers on simulated hardware, the
// command datasets, and their evaluators.
#include "category.hpp"

namespace robotperf::control {

void register_category(plugin::Registrar& registrar) {
  register_kernels(registrar);
  register_datasets(registrar);
  register_evaluators(registrar);
}

}  // namespace robotperf::control
