#include "robotperf/msgs/serialized_message.hpp"

#include <algorithm>
#include <cstring>
#include <map>
#include <memory>
#include <mutex>

namespace robotperf::msgs {
namespace {

std::size_t verbatim_size(const void* msg) {
  return static_cast<const SerializedMessage*>(msg)->cdr.size();
}

void verbatim_serialize(const void* msg, std::span<uint8_t> out) {
  const auto& cdr = static_cast<const SerializedMessage*>(msg)->cdr;
  std::memcpy(out.data(), cdr.data(), std::min(cdr.size(), out.size()));
}

std::shared_ptr<void> create_serialized() {
  return std::make_shared<SerializedMessage>();
}

void keep_payload(std::span<const uint8_t> payload, void* msg) {
  static_cast<SerializedMessage*>(msg)->cdr.assign(payload.begin(), payload.end());
}

// Byte order of the body from the encapsulation header: 00 01 is
// little-endian plain CDR, 00 00 big-endian.
bool little_endian_body(std::span<const uint8_t> payload) {
  if (payload.size() < 12) {
    throw CdrError("payload of " + std::to_string(payload.size()) +
                   " bytes is too short to hold a std_msgs/Header stamp");
  }
  if (payload[0] != 0 || payload[1] > 1) {
    throw CdrError("payload is not plain CDR (encapsulation " + std::to_string(payload[0]) + " " +
                   std::to_string(payload[1]) + ")");
  }
  return payload[1] == 1;
}

uint32_t load_u32(const uint8_t* p, bool little) {
  uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v |= uint32_t{p[little ? i : 3 - i]} << (8 * i);
  return v;
}

void store_u32(uint8_t* p, uint32_t v, bool little) {
  for (int i = 0; i < 4; ++i) p[little ? i : 3 - i] = static_cast<uint8_t>(v >> (8 * i));
}

}  // namespace

const TypeSupport& serialized_type_support(const std::string& ros_type) {
  static std::mutex mutex;
  static std::map<std::string, std::unique_ptr<TypeSupport>> supports;
  std::lock_guard lock(mutex);
  auto& slot = supports[ros_type];
  if (!slot) {
    slot = std::make_unique<TypeSupport>(
        TypeSupport{ros_type, dds_type_name(ros_type), &verbatim_size, &verbatim_serialize,
                    &create_serialized, &keep_payload, nullptr, nullptr});
  }
  return *slot;
}

bool is_serialized_type_support(const TypeSupport& type) {
  return type.serialize == &verbatim_serialize;
}

int64_t read_header_stamp_ns(std::span<const uint8_t> payload) {
  const bool little = little_endian_body(payload);
  const auto sec = static_cast<int32_t>(load_u32(payload.data() + 4, little));
  const uint32_t nanosec = load_u32(payload.data() + 8, little);
  return int64_t{sec} * 1'000'000'000 + nanosec;
}

void write_header_stamp_ns(std::span<uint8_t> payload, int64_t stamp_ns) {
  const bool little = little_endian_body(payload);
  // Floor division, so stamps before 1970 keep nanosec in [0, 1e9).
  int64_t sec = stamp_ns / 1'000'000'000;
  int64_t nanosec = stamp_ns % 1'000'000'000;
  if (nanosec < 0) {
    nanosec += 1'000'000'000;
    --sec;
  }
  store_u32(payload.data() + 4, static_cast<uint32_t>(static_cast<int32_t>(sec)), little);
  store_u32(payload.data() + 8, static_cast<uint32_t>(nanosec), little);
}

}  // namespace robotperf::msgs
