// Private to the perception category: the parts it registers.
#pragma once

#include "robotperf/plugin.hpp"

namespace robotperf::perception {

void register_image_proc_kernels(plugin::Registrar& registrar);
void register_stereo_depth_kernels(plugin::Registrar& registrar);
void register_laser_scan_kernels(plugin::Registrar& registrar);
void register_datasets(plugin::Registrar& registrar);
void register_evaluators(plugin::Registrar& registrar);
void register_output_comparisons(plugin::Registrar& registrar);
void register_backends(plugin::Registrar& registrar);

}  // namespace robotperf::perception
