// Private to the rmw library: the Cyclone DDS transport's factory.
#pragma once

#include <memory>

#include "robotperf/rmw/transport.hpp"

namespace robotperf::rmw {

std::unique_ptr<Transport> make_cyclonedds_transport(const TransportOptions& options);

}  // namespace robotperf::rmw
