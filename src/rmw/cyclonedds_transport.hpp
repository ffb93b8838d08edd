// Private to the rmw library: the Cyclone DDS transport's factory.
#pragma once

#include <memory>

#include "robotperf/rmw/transport.hpp"

namespace robotperf::rmw {

std::unique_ptr<Transport> make_cyclonedds_transport(const TransportOptions& options);

// Holds domain `domain_id` configured as the transport configures its domains, until the handle is
// released: a plain Cyclone DDS baseline (bench_transport) then runs under the same settings.
std::shared_ptr<void> use_cyclonedds_domain(int domain_id);

}  // namespace robotperf::rmw
