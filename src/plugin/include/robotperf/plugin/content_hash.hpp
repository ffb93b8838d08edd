#pragma once

// A content hash for datasets, so that a result can record exactly which data it ran on.

#include <cstdint>
#include <span>
#include <string>
#include <string_view>

namespace robotperf::plugin {

// 64-bit FNV-1a, fed with fields in a fixed, platform-independent framing: integers and
// doubles as little-endian bytes of fixed width, strings and byte blocks length-prefixed.
// Not cryptographic: it identifies data, it does not protect it.
class Fnv1a64 {
 public:
  static constexpr uint64_t kOffsetBasis = 0xcbf29ce484222325ULL;
  static constexpr uint64_t kPrime = 0x100000001b3ULL;

  // Raw bytes, no framing (use this to hash a plain byte string).
  Fnv1a64& add_raw(std::span<const uint8_t> bytes);
  Fnv1a64& add_u8(uint8_t value);
  Fnv1a64& add_u32(uint32_t value);
  Fnv1a64& add_i32(int32_t value);
  Fnv1a64& add_u64(uint64_t value);
  // The IEEE-754 bit pattern, so that -0.0 and 0.0 differ and NaNs hash consistently.
  Fnv1a64& add_f64(double value);
  // u64 length, then the bytes.
  Fnv1a64& add_bytes(std::span<const uint8_t> bytes);
  Fnv1a64& add_string(std::string_view text);

  uint64_t digest() const { return state_; }
  // "fnv1a64:" followed by 16 lower-case hex digits.
  std::string hex_digest() const;

 private:
  uint64_t state_ = kOffsetBasis;
};

}  // namespace robotperf::plugin
