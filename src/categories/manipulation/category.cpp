// The manipulation category (RobotPerf d1-d6): the xArm6 model, FK and IK on orocos-kdl,
// collision checks on FCL and Bullet, OMPL planning and simulated execution, the seeded request
// datasets, and their evaluators.
#include "category.hpp"

namespace robotperf::manipulation {

void register_category(plugin::Registrar& registrar) {
  register_kernels(registrar);
  register_datasets(registrar);
  register_evaluators(registrar);
}

}  // namespace robotperf::manipulation
