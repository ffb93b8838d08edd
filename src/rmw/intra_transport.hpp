// Private to the rmw library: the in-process transport's factory.
#pragma once

#include <memory>

#include "robotperf/rmw/transport.hpp"

namespace robotperf::rmw {

std::unique_ptr<Transport> make_intra_transport();

}  // namespace robotperf::rmw
