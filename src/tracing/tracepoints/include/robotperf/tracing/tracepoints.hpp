// The robotperf and ros2 tracepoints for C++ code. Use
//   lttng_ust_tracepoint(robotperf, publish, ...)         when the arguments are cheap
//   if (lttng_ust_tracepoint_enabled(robotperf, publish)) // when they cost something
//     lttng_ust_do_tracepoint(robotperf, publish, ...);
// Either way nothing is computed while no session enables the event.
#pragma once

#include <cstdint>

#include "robotperf/tracing/tp_robotperf.h"
#include "robotperf/tracing/tp_ros2.h"

namespace robotperf::tracing {

// The message ID of a message without a header: such messages are not matched.
inline constexpr int64_t kNoMessageId = -1;

}  // namespace robotperf::tracing
