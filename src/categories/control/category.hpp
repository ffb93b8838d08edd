// Private to the control category: the parts it registers.
#pragma once

#include "robotperf/plugin.hpp"

namespace robotperf::control {

void register_kernels(plugin::Registrar& registrar);
void register_datasets(plugin::Registrar& registrar);
void register_evaluators(plugin::Registrar& registrar);

}  // namespace robotperf::control
