// The .msg definitions of the message types compiled into robotperf, in the
// "ros2msg" schema form that bags carry (the type's fields, then each type it
// depends on after a separator line and "MSG: pkg/msg/Type").
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace robotperf::msgs {

// Empty when robotperf has no definition of `ros_type`.
std::optional<std::string> ros2msg_schema(std::string_view ros_type);

// Every type ros2msg_schema() knows, sorted.
std::vector<std::string_view> builtin_message_types();

}  // namespace robotperf::msgs
