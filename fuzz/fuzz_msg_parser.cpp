// The .msg and ros2msg schema parsers on arbitrary text: parse or throw DefinitionError.
#include <cstdint>
#include <string_view>

#include "robotperf/msgs/cdr.hpp"
#include "robotperf/msgs/dynamic.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  namespace dyn = robotperf::msgs::dynamic;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    dyn::TypeRegistry registry;
    registry.add_ros2msg("fuzz_msgs/msg/Root", text);
    registry.check_complete("fuzz_msgs/msg/Root");
    // A complete definition decodes and encodes an empty-ish payload without surprises.
    const uint8_t payload[64] = {0, 1, 0, 0};
    try {
      (void)dyn::encode(registry, "fuzz_msgs/msg/Root",
                        dyn::decode(registry, "fuzz_msgs/msg/Root", payload));
    } catch (const robotperf::msgs::CdrError&) {
    }
  } catch (const dyn::DefinitionError&) {
  }
  return 0;
}
