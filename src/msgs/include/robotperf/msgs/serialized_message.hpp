// A message kept as its CDR bytes: what a bag stores and what goes on the wire.
// Publishing one puts the bytes on the wire verbatim under the DDS type name of
// the real type, so a typed subscriber anywhere decodes it as that type.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "robotperf/msgs/type_support.hpp"

namespace robotperf::msgs {

struct SerializedMessage {
  std::vector<uint8_t> cdr;  // encapsulation header included
};

// The TypeSupport of SerializedMessage under `ros_type`'s names: its
// serialize writes the bytes verbatim, its deserialize keeps the payload's
// bytes. One instance per type name, alive for the whole program.
const TypeSupport& serialized_type_support(const std::string& ros_type);
bool is_serialized_type_support(const TypeSupport& type);

// For payloads of types whose first field is a std_msgs/Header: header.stamp
// is the first thing after the 4-byte encapsulation header (sec int32, then
// nanosec uint32). Both throw CdrError when the payload is too short or its
// encapsulation is not plain CDR.
int64_t read_header_stamp_ns(std::span<const uint8_t> payload);
void write_header_stamp_ns(std::span<uint8_t> payload, int64_t stamp_ns);

}  // namespace robotperf::msgs
