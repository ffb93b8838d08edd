// Private to the localization category: the parts it registers.
#pragma once

#include "robotperf/plugin.hpp"

namespace robotperf::localization {

void register_kernels(plugin::Registrar& registrar);
void register_datasets(plugin::Registrar& registrar);
void register_evaluators(plugin::Registrar& registrar);

}  // namespace robotperf::localization
