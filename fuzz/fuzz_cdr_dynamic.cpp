// The .msg-driven decoder on arbitrary payloads of a type with every kind of
// field: decode or throw CdrError; what decodes encodes to bytes that decode
// and encode to the same bytes.
#include <cstdint>
#include <span>
#include <stdexcept>

#include "robotperf/msgs/cdr.hpp"
#include "robotperf/msgs/definitions.hpp"
#include "robotperf/msgs/dynamic.hpp"

namespace {

namespace dyn = robotperf::msgs::dynamic;

const dyn::TypeRegistry& registry() {
  static const dyn::TypeRegistry r = [] {
    dyn::TypeRegistry reg;
    reg.add_ros2msg("sensor_msgs/msg/CameraInfo",
                    *robotperf::msgs::ros2msg_schema("sensor_msgs/msg/CameraInfo"));
    reg.add_msg("fuzz_msgs/msg/Inner", "int8 a\nfloat64 b\nstring c\n");
    reg.add_msg("fuzz_msgs/msg/Everything",
                "bool f_bool\nbyte f_byte\nchar f_char\nint16 f_i16\nuint64 f_u64\n"
                "float32 f_f32\nwstring f_wstring\nstring<=5 f_bounded_string\n"
                "int32[3] f_fixed\nuint8[] f_bytes\nfloat64[<=4] f_bounded\n"
                "string[] f_strings\nInner f_inner\nInner[2] f_inners\nInner[] f_inner_seq\n"
                "wstring[<=2] f_wstrings\nbool[] f_bools\n");
    return reg;
  }();
  return r;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const char* type = data[0] % 2 ? "fuzz_msgs/msg/Everything" : "sensor_msgs/msg/CameraInfo";
  dyn::Value value;
  try {
    value = dyn::decode(registry(), type, std::span<const uint8_t>(data + 1, size - 1));
  } catch (const robotperf::msgs::CdrError&) {
    return 0;
  }
  (void)dyn::to_yaml(value, 8);
  const auto first = dyn::encode(registry(), type, value);
  const auto second = dyn::encode(registry(), type, dyn::decode(registry(), type, first));
  if (first != second) throw std::logic_error("re-encoding is not stable");
  return 0;
}
