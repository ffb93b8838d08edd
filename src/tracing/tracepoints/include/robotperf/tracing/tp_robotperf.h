/* The `robotperf` LTTng-UST provider: what grey-box analysis needs from the
 * benchmark's input and output components, the node runtime and the kernels.
 * Every event names its node and carries the message ID (the header stamp in
 * nanoseconds, -1 for types without a header); sizes are CDR sizes computed
 * by a sizing pass, never by serialising. Field names are part of the trace
 * format read by src/tracing/analysis.cpp. */
#undef LTTNG_UST_TRACEPOINT_PROVIDER
#define LTTNG_UST_TRACEPOINT_PROVIDER robotperf

#undef LTTNG_UST_TRACEPOINT_INCLUDE
#define LTTNG_UST_TRACEPOINT_INCLUDE "robotperf/tracing/tp_robotperf.h"

#if !defined(ROBOTPERF_TRACING_TP_ROBOTPERF_H) || defined(LTTNG_UST_TRACEPOINT_HEADER_MULTI_READ)
#define ROBOTPERF_TRACING_TP_ROBOTPERF_H

/* The event fields have no commas between them, which clang-format would run together. */
/* clang-format off */
#include <lttng/tracepoint.h>
#include <stdint.h>

/* Once per run, before the first input: the run's configuration, so that a
 * trace can be analysed on its own with the run's validity rules. state_output
 * is 1 when the output is a state stream (control benchmarks: several outputs
 * carry one ID, and the later ones are repeats, not duplicates). */
LTTNG_UST_TRACEPOINT_EVENT(
    robotperf, run_begin,
    LTTNG_UST_TP_ARGS(const char *, benchmark_arg, const char *, rmw_arg, uint64_t, count_arg,
                      uint64_t, warmup_arg, int64_t, period_ns_arg, uint64_t, min_samples_arg,
                      double, max_loss_percent_arg, int, state_output_arg),
    LTTNG_UST_TP_FIELDS(
        lttng_ust_field_string(benchmark, benchmark_arg)
        lttng_ust_field_string(rmw, rmw_arg)
        lttng_ust_field_integer(uint64_t, count, count_arg)
        lttng_ust_field_integer(uint64_t, warmup, warmup_arg)
        lttng_ust_field_integer(int64_t, period_ns, period_ns_arg)
        lttng_ust_field_integer(uint64_t, min_samples, min_samples_arg)
        lttng_ust_field_float(double, max_loss_percent, max_loss_percent_arg)
        lttng_ust_field_integer(int, state_output, state_output_arg)))

/* A per-node child process of the run of process run_pid starts: the
 * analysis counts its events as part of that run. */
LTTNG_UST_TRACEPOINT_EVENT(
    robotperf, run_join,
    LTTNG_UST_TP_ARGS(int, run_pid_arg),
    LTTNG_UST_TP_FIELDS(lttng_ust_field_integer(int, run_pid, run_pid_arg)))

/* After the last input: how many frames the input component sent. */
LTTNG_UST_TRACEPOINT_EVENT(
    robotperf, run_end,
    LTTNG_UST_TP_ARGS(uint64_t, sent_arg),
    LTTNG_UST_TP_FIELDS(lttng_ust_field_integer(uint64_t, sent, sent_arg)))

/* The input component sends frame `index` (all its topics carry message_id);
 * the event time is the actual send time, scheduled_ns the open-loop deadline
 * on the same clock (CLOCK_MONOTONIC). */
LTTNG_UST_TRACEPOINT_EVENT(
    robotperf, input,
    LTTNG_UST_TP_ARGS(const char *, node_arg, int64_t, message_id_arg, uint64_t, index_arg,
                      int64_t, scheduled_ns_arg),
    LTTNG_UST_TP_FIELDS(
        lttng_ust_field_string(node, node_arg)
        lttng_ust_field_integer(int64_t, message_id, message_id_arg)
        lttng_ust_field_integer(uint64_t, index, index_arg)
        lttng_ust_field_integer(int64_t, scheduled_ns, scheduled_ns_arg)))

/* The output component received message_id. */
LTTNG_UST_TRACEPOINT_EVENT(
    robotperf, output,
    LTTNG_UST_TP_ARGS(const char *, node_arg, const char *, topic_arg, int64_t, message_id_arg,
                      uint64_t, size_arg),
    LTTNG_UST_TP_FIELDS(
        lttng_ust_field_string(node, node_arg)
        lttng_ust_field_string(topic, topic_arg)
        lttng_ust_field_integer(int64_t, message_id, message_id_arg)
        lttng_ust_field_integer(uint64_t, size, size_arg)))

/* A node hands a message to the transport. */
LTTNG_UST_TRACEPOINT_EVENT(
    robotperf, publish,
    LTTNG_UST_TP_ARGS(const char *, node_arg, const char *, topic_arg, int64_t, message_id_arg,
                      uint64_t, size_arg),
    LTTNG_UST_TP_FIELDS(
        lttng_ust_field_string(node, node_arg)
        lttng_ust_field_string(topic, topic_arg)
        lttng_ust_field_integer(int64_t, message_id, message_id_arg)
        lttng_ust_field_integer(uint64_t, size, size_arg)))

/* A subscription callback of a node starts on a taken message ... */
LTTNG_UST_TRACEPOINT_EVENT(
    robotperf, callback_entry,
    LTTNG_UST_TP_ARGS(const char *, node_arg, const char *, topic_arg, int64_t, message_id_arg,
                      uint64_t, size_arg),
    LTTNG_UST_TP_FIELDS(
        lttng_ust_field_string(node, node_arg)
        lttng_ust_field_string(topic, topic_arg)
        lttng_ust_field_integer(int64_t, message_id, message_id_arg)
        lttng_ust_field_integer(uint64_t, size, size_arg)))

/* ... and returns. */
LTTNG_UST_TRACEPOINT_EVENT(
    robotperf, callback_exit,
    LTTNG_UST_TP_ARGS(const char *, node_arg, const char *, topic_arg, int64_t, message_id_arg),
    LTTNG_UST_TP_FIELDS(
        lttng_ust_field_string(node, node_arg)
        lttng_ust_field_string(topic, topic_arg)
        lttng_ust_field_integer(int64_t, message_id, message_id_arg)))

/* A kernel starts its computation on a message (input size) ... */
LTTNG_UST_TRACEPOINT_EVENT(
    robotperf, kernel_init,
    LTTNG_UST_TP_ARGS(const char *, node_arg, const char *, kernel_arg, int64_t, message_id_arg,
                      uint64_t, size_arg),
    LTTNG_UST_TP_FIELDS(
        lttng_ust_field_string(node, node_arg)
        lttng_ust_field_string(kernel, kernel_arg)
        lttng_ust_field_integer(int64_t, message_id, message_id_arg)
        lttng_ust_field_integer(uint64_t, size, size_arg)))

/* ... and finishes it (output size), before publishing. */
LTTNG_UST_TRACEPOINT_EVENT(
    robotperf, kernel_fini,
    LTTNG_UST_TP_ARGS(const char *, node_arg, const char *, kernel_arg, int64_t, message_id_arg,
                      uint64_t, size_arg),
    LTTNG_UST_TP_FIELDS(
        lttng_ust_field_string(node, node_arg)
        lttng_ust_field_string(kernel, kernel_arg)
        lttng_ust_field_integer(int64_t, message_id, message_id_arg)
        lttng_ust_field_integer(uint64_t, size, size_arg)))

/* One stage of a message's computation by a kernel on a device (a backend other than the host
 * CPU): "upload" (host to device), "compute" or "download" (device to host), with the bytes it
 * moved; device_begin when it starts, device_end when it is done. */
LTTNG_UST_TRACEPOINT_EVENT_CLASS(
    robotperf, device_stage,
    LTTNG_UST_TP_ARGS(const char *, node_arg, const char *, stage_arg, int64_t, message_id_arg,
                      uint64_t, size_arg),
    LTTNG_UST_TP_FIELDS(
        lttng_ust_field_string(node, node_arg)
        lttng_ust_field_string(stage, stage_arg)
        lttng_ust_field_integer(int64_t, message_id, message_id_arg)
        lttng_ust_field_integer(uint64_t, size, size_arg)))
LTTNG_UST_TRACEPOINT_EVENT_INSTANCE(
    robotperf, device_stage, robotperf, device_begin,
    LTTNG_UST_TP_ARGS(const char *, node_arg, const char *, stage_arg, int64_t, message_id_arg,
                      uint64_t, size_arg))
LTTNG_UST_TRACEPOINT_EVENT_INSTANCE(
    robotperf, device_stage, robotperf, device_end,
    LTTNG_UST_TP_ARGS(const char *, node_arg, const char *, stage_arg, int64_t, message_id_arg,
                      uint64_t, size_arg))

/* A controller manager's cycle (src/control): one controller's update begins (with the newest
 * command the state it reads reflects) and ends (with the command it took this cycle, -1 when
 * none). `cycle` counts the loop's cycles from 0. */
LTTNG_UST_TRACEPOINT_EVENT(
    robotperf, controller_update_begin,
    LTTNG_UST_TP_ARGS(const char *, node_arg, const char *, controller_arg, uint64_t, cycle_arg,
                      int64_t, message_id_arg),
    LTTNG_UST_TP_FIELDS(
        lttng_ust_field_string(node, node_arg)
        lttng_ust_field_string(controller, controller_arg)
        lttng_ust_field_integer(uint64_t, cycle, cycle_arg)
        lttng_ust_field_integer(int64_t, message_id, message_id_arg)))

LTTNG_UST_TRACEPOINT_EVENT(
    robotperf, controller_update_end,
    LTTNG_UST_TP_ARGS(const char *, node_arg, const char *, controller_arg, uint64_t, cycle_arg,
                      int64_t, message_id_arg),
    LTTNG_UST_TP_FIELDS(
        lttng_ust_field_string(node, node_arg)
        lttng_ust_field_string(controller, controller_arg)
        lttng_ust_field_integer(uint64_t, cycle, cycle_arg)
        lttng_ust_field_integer(int64_t, message_id, message_id_arg)))

/* A tf2 buffer (robotperf/plugin/tf2_buffer.hpp) of node `node` begins and ends an `operation`:
 * "set" (setTransform) or "lookup" (lookupTransform). `call` numbers the buffer's calls, so that
 * a begin pairs with its end when calls of several threads interleave. */
LTTNG_UST_TRACEPOINT_EVENT_CLASS(
    robotperf, tf2_call,
    LTTNG_UST_TP_ARGS(const char *, node_arg, const char *, operation_arg, uint64_t, call_arg),
    LTTNG_UST_TP_FIELDS(
        lttng_ust_field_string(node, node_arg)
        lttng_ust_field_string(operation, operation_arg)
        lttng_ust_field_integer(uint64_t, call, call_arg)))
LTTNG_UST_TRACEPOINT_EVENT_INSTANCE(
    robotperf, tf2_call, robotperf, tf2_begin,
    LTTNG_UST_TP_ARGS(const char *, node_arg, const char *, operation_arg, uint64_t, call_arg))
LTTNG_UST_TRACEPOINT_EVENT_INSTANCE(
    robotperf, tf2_call, robotperf, tf2_end,
    LTTNG_UST_TP_ARGS(const char *, node_arg, const char *, operation_arg, uint64_t, call_arg))

/* clang-format on */
#endif /* ROBOTPERF_TRACING_TP_ROBOTPERF_H */

#include <lttng/tracepoint-event.h>
