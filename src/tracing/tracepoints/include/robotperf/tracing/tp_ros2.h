/* The `ros2` LTTng-UST provider: the events of ros2_tracing (tracetools),
 * with the same names and field names and types, emitted by robotperf's node
 * runtime so that ROS 2 trace tooling reads robotperf traces. Handles are the
 * addresses of the runtime's objects: our Node, GenericPublisher and
 * GenericSubscription stand for both the rcl and the rclcpp layer. */
#undef LTTNG_UST_TRACEPOINT_PROVIDER
#define LTTNG_UST_TRACEPOINT_PROVIDER ros2

#undef LTTNG_UST_TRACEPOINT_INCLUDE
#define LTTNG_UST_TRACEPOINT_INCLUDE "robotperf/tracing/tp_ros2.h"

#if !defined(ROBOTPERF_TRACING_TP_ROS2_H) || defined(LTTNG_UST_TRACEPOINT_HEADER_MULTI_READ)
#define ROBOTPERF_TRACING_TP_ROS2_H

/* The event fields have no commas between them, which clang-format would run together. */
/* clang-format off */
#include <lttng/tracepoint.h>
#include <stddef.h>
#include <stdint.h>

/* rmw's RMW_GID_STORAGE_SIZE, as ros2_tracing records gids. */
#define ROBOTPERF_ROS2_GID_STORAGE_SIZE 24u

LTTNG_UST_TRACEPOINT_EVENT(
    ros2, rcl_init,
    LTTNG_UST_TP_ARGS(const void *, context_handle_arg, const char *, version_arg),
    LTTNG_UST_TP_FIELDS(
        lttng_ust_field_integer_hex(const void *, context_handle, context_handle_arg)
        lttng_ust_field_string(version, version_arg)))

LTTNG_UST_TRACEPOINT_EVENT(
    ros2, rcl_node_init,
    LTTNG_UST_TP_ARGS(const void *, node_handle_arg, const void *, rmw_handle_arg, const char *,
                      node_name_arg, const char *, namespace_arg),
    LTTNG_UST_TP_FIELDS(
        lttng_ust_field_integer_hex(const void *, node_handle, node_handle_arg)
        lttng_ust_field_integer_hex(const void *, rmw_handle, rmw_handle_arg)
        lttng_ust_field_string(node_name, node_name_arg)
        lttng_ust_field_string(namespace, namespace_arg)))

LTTNG_UST_TRACEPOINT_EVENT(
    ros2, rmw_publisher_init,
    LTTNG_UST_TP_ARGS(const void *, rmw_publisher_handle_arg, const uint8_t *, gid_arg),
    LTTNG_UST_TP_FIELDS(
        lttng_ust_field_integer_hex(const void *, rmw_publisher_handle, rmw_publisher_handle_arg)
        lttng_ust_field_array(uint8_t, gid, gid_arg, ROBOTPERF_ROS2_GID_STORAGE_SIZE)))

LTTNG_UST_TRACEPOINT_EVENT(
    ros2, rcl_publisher_init,
    LTTNG_UST_TP_ARGS(const void *, publisher_handle_arg, const void *, node_handle_arg,
                      const void *, rmw_publisher_handle_arg, const char *, topic_name_arg,
                      const size_t, queue_depth_arg),
    LTTNG_UST_TP_FIELDS(
        lttng_ust_field_integer_hex(const void *, publisher_handle, publisher_handle_arg)
        lttng_ust_field_integer_hex(const void *, node_handle, node_handle_arg)
        lttng_ust_field_integer_hex(const void *, rmw_publisher_handle, rmw_publisher_handle_arg)
        lttng_ust_field_string(topic_name, topic_name_arg)
        lttng_ust_field_integer(const size_t, queue_depth, queue_depth_arg)))

/* Humble and later record the message only (Galactic also had publisher_handle). */
LTTNG_UST_TRACEPOINT_EVENT(
    ros2, rclcpp_publish,
    LTTNG_UST_TP_ARGS(const void *, message_arg),
    LTTNG_UST_TP_FIELDS(lttng_ust_field_integer_hex(const void *, message, message_arg)))

LTTNG_UST_TRACEPOINT_EVENT(
    ros2, rcl_publish,
    LTTNG_UST_TP_ARGS(const void *, publisher_handle_arg, const void *, message_arg),
    LTTNG_UST_TP_FIELDS(
        lttng_ust_field_integer_hex(const void *, publisher_handle, publisher_handle_arg)
        lttng_ust_field_integer_hex(const void *, message, message_arg)))

LTTNG_UST_TRACEPOINT_EVENT(
    ros2, rmw_publish,
    LTTNG_UST_TP_ARGS(const void *, rmw_publisher_handle_arg, const void *, message_arg, int64_t,
                      timestamp_arg),
    LTTNG_UST_TP_FIELDS(
        lttng_ust_field_integer_hex(const void *, rmw_publisher_handle, rmw_publisher_handle_arg)
        lttng_ust_field_integer_hex(const void *, message, message_arg)
        lttng_ust_field_integer(int64_t, timestamp, timestamp_arg)))

LTTNG_UST_TRACEPOINT_EVENT(
    ros2, rmw_subscription_init,
    LTTNG_UST_TP_ARGS(const void *, rmw_subscription_handle_arg, const uint8_t *, gid_arg),
    LTTNG_UST_TP_FIELDS(
        lttng_ust_field_integer_hex(const void *, rmw_subscription_handle,
                                    rmw_subscription_handle_arg)
        lttng_ust_field_array(uint8_t, gid, gid_arg, ROBOTPERF_ROS2_GID_STORAGE_SIZE)))

LTTNG_UST_TRACEPOINT_EVENT(
    ros2, rcl_subscription_init,
    LTTNG_UST_TP_ARGS(const void *, subscription_handle_arg, const void *, node_handle_arg,
                      const void *, rmw_subscription_handle_arg, const char *, topic_name_arg,
                      const size_t, queue_depth_arg),
    LTTNG_UST_TP_FIELDS(
        lttng_ust_field_integer_hex(const void *, subscription_handle, subscription_handle_arg)
        lttng_ust_field_integer_hex(const void *, node_handle, node_handle_arg)
        lttng_ust_field_integer_hex(const void *, rmw_subscription_handle,
                                    rmw_subscription_handle_arg)
        lttng_ust_field_string(topic_name, topic_name_arg)
        lttng_ust_field_integer(const size_t, queue_depth, queue_depth_arg)))

LTTNG_UST_TRACEPOINT_EVENT(
    ros2, rclcpp_subscription_init,
    LTTNG_UST_TP_ARGS(const void *, subscription_handle_arg, const void *, subscription_arg),
    LTTNG_UST_TP_FIELDS(
        lttng_ust_field_integer_hex(const void *, subscription_handle, subscription_handle_arg)
        lttng_ust_field_integer_hex(const void *, subscription, subscription_arg)))

LTTNG_UST_TRACEPOINT_EVENT(
    ros2, rclcpp_subscription_callback_added,
    LTTNG_UST_TP_ARGS(const void *, subscription_arg, const void *, callback_arg),
    LTTNG_UST_TP_FIELDS(
        lttng_ust_field_integer_hex(const void *, subscription, subscription_arg)
        lttng_ust_field_integer_hex(const void *, callback, callback_arg)))

LTTNG_UST_TRACEPOINT_EVENT(
    ros2, rmw_take,
    LTTNG_UST_TP_ARGS(const void *, rmw_subscription_handle_arg, const void *, message_arg,
                      int64_t, source_timestamp_arg, int, taken_arg),
    LTTNG_UST_TP_FIELDS(
        lttng_ust_field_integer_hex(const void *, rmw_subscription_handle,
                                    rmw_subscription_handle_arg)
        lttng_ust_field_integer_hex(const void *, message, message_arg)
        lttng_ust_field_integer(int64_t, source_timestamp, source_timestamp_arg)
        lttng_ust_field_integer(int, taken, taken_arg)))

LTTNG_UST_TRACEPOINT_EVENT(
    ros2, rcl_take,
    LTTNG_UST_TP_ARGS(const void *, message_arg),
    LTTNG_UST_TP_FIELDS(lttng_ust_field_integer_hex(const void *, message, message_arg)))

LTTNG_UST_TRACEPOINT_EVENT(
    ros2, rclcpp_take,
    LTTNG_UST_TP_ARGS(const void *, message_arg),
    LTTNG_UST_TP_FIELDS(lttng_ust_field_integer_hex(const void *, message, message_arg)))

LTTNG_UST_TRACEPOINT_EVENT(
    ros2, rcl_timer_init,
    LTTNG_UST_TP_ARGS(const void *, timer_handle_arg, int64_t, period_arg),
    LTTNG_UST_TP_FIELDS(
        lttng_ust_field_integer_hex(const void *, timer_handle, timer_handle_arg)
        lttng_ust_field_integer(int64_t, period, period_arg)))

LTTNG_UST_TRACEPOINT_EVENT(
    ros2, rclcpp_timer_callback_added,
    LTTNG_UST_TP_ARGS(const void *, timer_handle_arg, const void *, callback_arg),
    LTTNG_UST_TP_FIELDS(
        lttng_ust_field_integer_hex(const void *, timer_handle, timer_handle_arg)
        lttng_ust_field_integer_hex(const void *, callback, callback_arg)))

LTTNG_UST_TRACEPOINT_EVENT(
    ros2, rclcpp_timer_link_node,
    LTTNG_UST_TP_ARGS(const void *, timer_handle_arg, const void *, node_handle_arg),
    LTTNG_UST_TP_FIELDS(
        lttng_ust_field_integer_hex(const void *, timer_handle, timer_handle_arg)
        lttng_ust_field_integer_hex(const void *, node_handle, node_handle_arg)))

/* The callback's symbol: its demangled type (lambdas and function objects) or function name. */
LTTNG_UST_TRACEPOINT_EVENT(
    ros2, rclcpp_callback_register,
    LTTNG_UST_TP_ARGS(const void *, callback_arg, const char *, symbol_arg),
    LTTNG_UST_TP_FIELDS(
        lttng_ust_field_integer_hex(const void *, callback, callback_arg)
        lttng_ust_field_string(symbol, symbol_arg)))

LTTNG_UST_TRACEPOINT_EVENT(
    ros2, callback_start,
    LTTNG_UST_TP_ARGS(const void *, callback_arg, int, is_intra_process_arg),
    LTTNG_UST_TP_FIELDS(
        lttng_ust_field_integer_hex(const void *, callback, callback_arg)
        lttng_ust_field_integer(int, is_intra_process, is_intra_process_arg)))

LTTNG_UST_TRACEPOINT_EVENT(
    ros2, callback_end,
    LTTNG_UST_TP_ARGS(const void *, callback_arg),
    LTTNG_UST_TP_FIELDS(lttng_ust_field_integer_hex(const void *, callback, callback_arg)))

/* clang-format on */
#endif /* ROBOTPERF_TRACING_TP_ROS2_H */

#include <lttng/tracepoint-event.h>
