#include "robotperf/plugin/content_hash.hpp"

#include <bit>
#include <cstdio>

namespace robotperf::plugin {
namespace {

template <class T>
void add_little_endian(Fnv1a64& hash, T value) {
  uint8_t bytes[sizeof(T)];
  for (size_t i = 0; i < sizeof(T); ++i) {
    bytes[i] = static_cast<uint8_t>(value >> (8 * i));
  }
  hash.add_raw(bytes);
}

}  // namespace

Fnv1a64& Fnv1a64::add_raw(std::span<const uint8_t> bytes) {
  uint64_t state = state_;
  for (const uint8_t byte : bytes) {
    state = (state ^ byte) * kPrime;
  }
  state_ = state;
  return *this;
}

Fnv1a64& Fnv1a64::add_u8(uint8_t value) {
  return add_raw({&value, 1});
}

Fnv1a64& Fnv1a64::add_u32(uint32_t value) {
  add_little_endian(*this, value);
  return *this;
}

Fnv1a64& Fnv1a64::add_i32(int32_t value) {
  return add_u32(static_cast<uint32_t>(value));
}

Fnv1a64& Fnv1a64::add_u64(uint64_t value) {
  add_little_endian(*this, value);
  return *this;
}

Fnv1a64& Fnv1a64::add_f64(double value) {
  return add_u64(std::bit_cast<uint64_t>(value));
}

Fnv1a64& Fnv1a64::add_bytes(std::span<const uint8_t> bytes) {
  add_u64(bytes.size());
  return add_raw(bytes);
}

Fnv1a64& Fnv1a64::add_string(std::string_view text) {
  return add_bytes({reinterpret_cast<const uint8_t*>(text.data()), text.size()});
}

std::string Fnv1a64::hex_digest() const {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "fnv1a64:%016llx", static_cast<unsigned long long>(state_));
  return buffer;
}

}  // namespace robotperf::plugin
