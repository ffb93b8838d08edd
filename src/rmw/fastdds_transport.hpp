// Private to the rmw library: the Fast DDS transport's factory.
#pragma once

#include <memory>

#include "robotperf/rmw/transport.hpp"

namespace robotperf::rmw {

std::unique_ptr<Transport> make_fastdds_transport(const TransportOptions& options);

}  // namespace robotperf::rmw
