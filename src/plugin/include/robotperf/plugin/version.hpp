// The version of the plug-in API. A plug-in records the version it was built against
// (ROBOTPERF_PLUGIN in plugin.hpp); robotperf refuses a plug-in built against another one,
// because the types it registers would not be laid out as robotperf expects.
#pragma once

// Raised whenever a type or function a plug-in sees changes incompatibly.
// 2: EvaluatorInfo::on_arrival; 3: PortInfo::device_resident,
// KernelInfo::device_resident_backends, KernelConfig::device_resident_outputs;
// 4: Registrar::add_output_comparison and add_backend; 5: Registrar::add_kernel_backend,
// KernelEntry::implementations.
#define ROBOTPERF_PLUGIN_API_VERSION 5

// The ELF section in which ROBOTPERF_PLUGIN records the version (an int), read from the file
// before it is loaded.
#define ROBOTPERF_PLUGIN_API_SECTION "robotperf_plugin_api"
