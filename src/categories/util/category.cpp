// The util category: kernels for checking the harness itself against a graph whose behaviour is
// known exactly.
#include "robotperf/plugin.hpp"

namespace robotperf::util {

void register_relay_kernel(plugin::Registrar& registrar);

void register_category(plugin::Registrar& registrar) {
  register_relay_kernel(registrar);
}

}  // namespace robotperf::util
