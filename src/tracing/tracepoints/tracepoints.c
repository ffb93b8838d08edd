/* The tracepoint provider package: the probes of both providers, compiled as
 * C in this one translation unit, and the tracepoint definitions the
 * instrumented C++ code refers to. Linked statically into every robotperf
 * program; with no tracing session a tracepoint is one predicted branch. */
#define LTTNG_UST_TRACEPOINT_CREATE_PROBES
#define LTTNG_UST_TRACEPOINT_DEFINE

#include "robotperf/tracing/tp_robotperf.h"
#include "robotperf/tracing/tp_ros2.h"
