// The localization category (RobotPerf b1-b3): AprilTag detection on libapriltag, global map
// localization by correlative scan matching, and stereo visual odometry on OpenCV, with datasets
// rendered at known poses and evaluators against that ground truth.
#include "category.hpp"

namespace robotperf::localization {

void register_category(plugin::Registrar& registrar) {
  register_kernels(registrar);
  register_datasets(registrar);
  register_evaluators(registrar);
}

}  // namespace robotperf::localization
