// The perception category (RobotPerf a1-a8): image_proc, stereo_image_proc and
// depth_image_proc kernels on OpenCV, depthimage_to_laserscan and pointcloud_to_laserscan, the
// synthetic camera, stereo and depth datasets, their evaluators, how their answers on opencl and
// cuda are compared with the cpu's, and those two backends.
#include "category.hpp"

namespace robotperf::perception {

void register_category(plugin::Registrar& registrar) {
  register_image_proc_kernels(registrar);
  register_stereo_depth_kernels(registrar);
  register_laser_scan_kernels(registrar);
  register_datasets(registrar);
  register_evaluators(registrar);
  register_output_comparisons(registrar);
  register_backends(registrar);
}

}  // namespace robotperf::perception
