// Private to the manipulation category: the parts it registers.
#pragma once

#include "robotperf/plugin.hpp"

namespace robotperf::manipulation {

void register_kernels(plugin::Registrar& registrar);
void register_datasets(plugin::Registrar& registrar);
void register_evaluators(plugin::Registrar& registrar);

}  // namespace robotperf::manipulation
