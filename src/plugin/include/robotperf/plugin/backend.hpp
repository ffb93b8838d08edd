// Backends: where a kernel computes. A kernel lists the backends it has (KernelInfo::backends);
// each backend other than the host CPU is registered once, by the category or plug-in that brings
// it, with what robotperf asks of it without building a node: the devices of this machine it could
// run on (`robotperf sysinfo` lists them as <name>_devices) and, for a backend this robotperf
// cannot run at all, why (the one line `run --backend <name>` is refused with).
//
// `cpu` is implicit: the host CPU, always there and the reference every other backend's answers
// are compared with (robotperf/plugin/output_comparison.hpp). It is not registered; registering
// it is an error.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "robotperf/plugin/kernel.hpp"

namespace robotperf::plugin {

// The backend every kernel may run on without registering it.
inline constexpr const char* kHostBackend = "cpu";

struct BackendInfo {
  std::string name{};         // "opencl": as kernels list it in KernelInfo::backends
  std::string description{};  // one line
};

// Each hook may be left empty: a backend that lists no devices, or one that can always run.
struct BackendHooks {
  // Every device of this machine the backend could run on, described as results record the one a
  // node took (DeviceInfo); none where its driver or hardware is missing.
  std::function<std::vector<DeviceInfo>()> devices{};
  // Why this robotperf cannot run the backend on any machine (it was built without it), in one
  // line; empty when it can. A missing device is for the kernel to say when it builds its node,
  // since which device a backend takes is the kernel's choice.
  std::function<std::string()> unavailable_reason{};
};

}  // namespace robotperf::plugin
