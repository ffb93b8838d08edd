// The perception category (RobotPerf a1-a5): image_proc, stereo_image_proc and depth_image_proc
// kernels on OpenCV, the synthetic camera, stereo and depth datasets, and their evaluators.
#include "category.hpp"

namespace robotperf::perception {

void register_category(plugin::Registrar& registrar) {
  register_image_proc_kernels(registrar);
  register_stereo_depth_kernels(registrar);
  register_datasets(registrar);
  register_evaluators(registrar);
}

}  // namespace robotperf::perception
