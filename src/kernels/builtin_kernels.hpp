// Private to the kernels library: the factories of the built-in kernels.
#pragma once

#include "robotperf/kernels/registry.hpp"

namespace robotperf::kernels {

std::shared_ptr<graph::Node> make_relay_node(graph::Context& context, const KernelConfig& config);
std::shared_ptr<graph::Node> make_rectify_node(graph::Context& context, const KernelConfig& config);
std::shared_ptr<graph::Node> make_resize_node(graph::Context& context, const KernelConfig& config);
std::shared_ptr<graph::Node> make_disparity_node(graph::Context& context,
                                                 const KernelConfig& config);
std::shared_ptr<graph::Node> make_point_cloud_xyzrgb_node(graph::Context& context,
                                                          const KernelConfig& config);
std::shared_ptr<graph::Node> make_joint_trajectory_controller_node(graph::Context& context,
                                                                   const KernelConfig& config);
std::shared_ptr<graph::Node> make_diff_drive_controller_node(graph::Context& context,
                                                             const KernelConfig& config);
std::shared_ptr<graph::Node> make_forward_command_controller_node(graph::Context& context,
                                                                  const KernelConfig& config);

}  // namespace robotperf::kernels
