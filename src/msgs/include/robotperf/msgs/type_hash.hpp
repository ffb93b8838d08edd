// ROS 2's type hash (REP 2011): the "RIHS01_" version prefix and the SHA-256, in hex, of a JSON
// text of the type's description (its fields, then every type it refers to, sorted by name;
// constants and default values left out). Iron and later put it in every endpoint's USER_DATA
// ("typehash=RIHS01_...;") and tools show it (`ros2 topic info -v`).
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "robotperf/msgs/dynamic.hpp"

namespace robotperf::msgs {

// The JSON text REP 2011 hashes for `type` (as rosidl writes it: Python's json.dumps with ", " and
// ": " separators). Throws dynamic::DefinitionError when a type it needs is unknown.
std::string type_description_json(const dynamic::TypeRegistry& registry, const std::string& type);

// "RIHS01_<64 hex digits>" for `type`. Throws dynamic::DefinitionError as above.
std::string type_hash(const dynamic::TypeRegistry& registry, const std::string& type);

// The type hash of a message type robotperf has the definition of (ros2msg_schema); nullopt for
// others. Computed once per type.
std::optional<std::string> builtin_type_hash(std::string_view ros_type);

}  // namespace robotperf::msgs
