// Private to the perception category: how a kernel registers its implementations, one per
// backend, and what its node records about the device the implementation runs on.
#pragma once

#include <span>
#include <string>
#include <string_view>
#include <utility>

#include "device_stage.hpp"
#include "robotperf/perception/cuda_device.hpp"
#include "robotperf/perception/image_proc.hpp"
#include "robotperf/plugin/registry.hpp"

namespace robotperf::perception {

// Whether this robotperf has `backend`'s implementations: cuda only in a build with the CUDA
// toolkit, so that a run asking for it elsewhere is refused, with the backend's line, before any
// node is built.
inline bool implementation_built(std::string_view backend) {
  return backend != "cuda" || cuda_backend_built();
}

// Registers a kernel on the backends of its processor's `table`: on the first (cpu) with
// add_kernel, on each other with add_kernel_backend, so that each backend's node is built with its
// own implementation. `make_node(context, config, implementation)` builds the node.
template <class I, class MakeNode>
void register_implementations(plugin::Registrar& registrar, plugin::KernelInfo info,
                              std::span<const I> table, MakeNode make_node) {
  const auto factory = [make_node](const I& implementation) -> plugin::KernelFactory {
    return
        [make_node, &implementation](graph::Context& context, const plugin::KernelConfig& config) {
          return make_node(context, config, implementation);
        };
  };
  const std::string kernel = info.name;
  info.backends = {table.front().backend};
  registrar.add_kernel(std::move(info), factory(table.front()));
  for (const I& implementation : table.subspan(1)) {
    if (!implementation_built(implementation.backend)) continue;
    registrar.add_kernel_backend({.kernel = kernel,
                                  .backend = implementation.backend,
                                  .device_resident = implementation.image_resident},
                                 factory(implementation));
  }
}

// A node whose implementation computes on the device `device` gives (none on the host).
class ImageDeviceNode : public plugin::DeviceNode {
 public:
  explicit ImageDeviceNode(const plugin::DeviceInfo& (*device)()) : device_(device) {}
  plugin::DeviceInfo device() const override {
    return device_ != nullptr ? device_() : plugin::DeviceInfo{};
  }

 private:
  const plugin::DeviceInfo& (*device_)();
};

}  // namespace robotperf::perception
