// The robotperf plug-in API: everything a shared library needs to add kernels, dataset
// generators, functional evaluators, output comparisons and backends to robotperf, and nothing
// of the harness.
//
//   #include <robotperf/plugin.hpp>
//
//   ROBOTPERF_PLUGIN(registrar) {
//     registrar.add_kernel(info, factory);
//     registrar.add_dataset(info, generator);
//     registrar.add_evaluator(info, factory);
//     registrar.add_output_comparison(info, compare);
//     registrar.add_backend(info, hooks);
//   }
//
// Build it against an installed robotperf (find_package(robotperf) and link robotperf::plugin)
// and load it with `robotperf --plugin lib.so`, ROBOTPERF_PLUGIN_PATH or a benchmark's
// `plugins:`. The built-in categories (src/categories) register through the same Registrar.
#pragma once

#include "robotperf/graph/node.hpp"
#include "robotperf/msgs/known_types.hpp"
#include "robotperf/plugin/backend.hpp"
#include "robotperf/plugin/content_hash.hpp"
#include "robotperf/plugin/control_loop.hpp"
#include "robotperf/plugin/dataset.hpp"
#include "robotperf/plugin/evaluator.hpp"
#include "robotperf/plugin/kernel.hpp"
#include "robotperf/plugin/message_sync.hpp"
#include "robotperf/plugin/output_comparison.hpp"
#include "robotperf/plugin/parameter_struct.hpp"
#include "robotperf/plugin/parameters.hpp"
#include "robotperf/plugin/registry.hpp"
#include "robotperf/plugin/tf2_buffer.hpp"
#include "robotperf/plugin/version.hpp"

// Defines the plug-in's entry points: the API version it was built against, which robotperf
// checks before anything else, and the registration function, whose body follows the macro.
// The version is also recorded in the file's section ROBOTPERF_PLUGIN_API_SECTION, which robotperf
// reads before loading it: a plug-in of another version may need symbols this robotperf lacks.
#define ROBOTPERF_PLUGIN(registrar)                                                      \
  static void robotperf_plugin_register_body(::robotperf::plugin::Registrar& registrar); \
  extern "C" __attribute__((used, section(ROBOTPERF_PLUGIN_API_SECTION)))                \
  const int robotperf_plugin_api_version_recorded = ROBOTPERF_PLUGIN_API_VERSION;        \
  extern "C" __attribute__((visibility("default"))) int robotperf_plugin_api_version() { \
    return ROBOTPERF_PLUGIN_API_VERSION;                                                 \
  }                                                                                      \
  extern "C" __attribute__((visibility("default"))) void robotperf_plugin_register(      \
      ::robotperf::plugin::Registrar& r) {                                               \
    robotperf_plugin_register_body(r);                                                   \
  }                                                                                      \
  static void robotperf_plugin_register_body(::robotperf::plugin::Registrar& registrar)
