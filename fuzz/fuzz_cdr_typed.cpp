// The compiled-in CDR decoders on arbitrary payloads: decode or throw CdrError;
// what decodes re-encodes to bytes that decode to the same encoding.
#include <cstdint>
#include <span>
#include <stdexcept>
#include <vector>

#include "robotperf/msgs/known_types.hpp"
#include "robotperf/msgs/serialized_message.hpp"

namespace {

template <class T>
void check(std::span<const uint8_t> payload) {
  const auto& ts = robotperf::msgs::type_support<T>();
  T msg;
  try {
    ts.deserialize(payload, &msg);
  } catch (const robotperf::msgs::CdrError&) {
    return;
  }
  std::vector<uint8_t> first(ts.serialized_size(&msg));
  ts.serialize(&msg, first);
  T again;
  ts.deserialize(first, &again);
  std::vector<uint8_t> second(ts.serialized_size(&again));
  ts.serialize(&again, second);
  if (first != second) throw std::logic_error("re-encoding is not stable");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const std::span<const uint8_t> payload(data + 1, size - 1);
  switch (data[0] % 4) {
    case 0:
      check<robotperf::msgs::Image>(payload);
      break;
    case 1:
      check<robotperf::msgs::CameraInfo>(payload);
      break;
    case 2:
      try {
        (void)robotperf::msgs::read_header_stamp_ns(payload);
      } catch (const robotperf::msgs::CdrError&) {
      }
      break;
    default:
      check<robotperf::msgs::Header>(payload);
  }
  return 0;
}
