// CRC-32 (ISO-HDLC, the one MCAP specifies) of chunk records: every chunk read is checked, and at
// a few GB/s the check is a quarter of the time to read an lz4 bag. Where the CPU has AVX-512 with
// carry-less multiplication on 512-bit registers (VPCLMULQDQ), the bulk of a buffer is folded 256
// bytes at a time; everything else, and the last few bytes, goes to libdeflate's CRC-32.
#include <immintrin.h>
#include <libdeflate.h>

#include <array>
#include <cstring>

#include "mcap_format.hpp"

namespace robotperf::bag::mcap {
namespace {

// x^n mod G(x) for the CRC-32 polynomial G = 0x104C11DB7, bit m = coefficient of x^m.
constexpr uint64_t x_pow_mod_g(unsigned n) {
  uint64_t r = 1;
  for (unsigned i = 0; i < n; ++i) {
    r <<= 1;
    if (r & (uint64_t{1} << 32)) r ^= 0x104C11DB7;
  }
  return r;
}

constexpr uint64_t bit_reversed(uint64_t v) {
  uint64_t r = 0;
  for (int i = 0; i < 64; ++i) r |= ((v >> i) & 1) << (63 - i);
  return r;
}

// In the reflected bit order of this CRC, a 128-bit lane of data holds its first 8 bytes (the
// higher-degree half L) in the low quadword and bit j of a quadword is the coefficient of
// x^(63 - j). Moving a lane `bits` further along the message multiplies it by x^bits:
//   L·x^(64+bits) + H·x^bits ≡ L·(x^(64+bits) mod G) + H·(x^bits mod G),
// two carry-less products of 64-bit halves by 32-bit constants. A carry-less product of two
// reflected operands comes out one degree short, hence the constants' x^(n-1).
struct FoldConstants {
  uint64_t low, high;
};
constexpr FoldConstants fold_by(unsigned bits) {
  return {bit_reversed(x_pow_mod_g(64 + bits - 1)), bit_reversed(x_pow_mod_g(bits - 1))};
}

constexpr std::size_t kBlock = 256;  // four 512-bit registers

// Only the functions marked so use AVX-512; crc32() calls them after checking the CPU. (A function
// attribute, not a `#pragma GCC target` region: clang honours only the attribute.)
#define ROBOTPERF_AVX512_CLMUL __attribute__((target("avx512f,avx512vl,vpclmulqdq")))

ROBOTPERF_AVX512_CLMUL __m512i fold(__m512i lanes, __m512i k) {
  return _mm512_xor_si512(_mm512_clmulepi64_epi128(lanes, k, 0x00),
                          _mm512_clmulepi64_epi128(lanes, k, 0x11));
}

// The constants of one fold per lane, the lane-0 ones first.
ROBOTPERF_AVX512_CLMUL __m512i per_lane(FoldConstants k0, FoldConstants k1, FoldConstants k2,
                                        FoldConstants k3) {
  auto q = [](uint64_t v) { return static_cast<long long>(v); };
  return _mm512_set_epi64(q(k3.high), q(k3.low), q(k2.high), q(k2.low), q(k1.high), q(k1.low),
                          q(k0.high), q(k0.low));
}

ROBOTPERF_AVX512_CLMUL __m512i load(const uint8_t* at) {
  return _mm512_loadu_si512(at);
}

// Needs at least kBlock bytes.
ROBOTPERF_AVX512_CLMUL uint32_t crc32_vpclmulqdq(const uint8_t* p, std::size_t n, uint32_t crc) {
  static constexpr FoldConstants k2048 = fold_by(8 * kBlock), k512 = fold_by(512),
                                 k384 = fold_by(384), k256 = fold_by(256), k128 = fold_by(128);
  // The running CRC, inverted as the register of the byte-wise algorithm, enters as the first
  // four message bytes XORed with it.
  __m512i x0 = _mm512_xor_si512(load(p), _mm512_set_epi64(0, 0, 0, 0, 0, 0, 0, ~crc));
  __m512i x1 = load(p + 64);
  __m512i x2 = load(p + 128);
  __m512i x3 = load(p + 192);
  p += kBlock;
  n -= kBlock;
  const __m512i by_block = per_lane(k2048, k2048, k2048, k2048);
  for (; n >= kBlock; p += kBlock, n -= kBlock) {
    x0 = _mm512_xor_si512(fold(x0, by_block), load(p));
    x1 = _mm512_xor_si512(fold(x1, by_block), load(p + 64));
    x2 = _mm512_xor_si512(fold(x2, by_block), load(p + 128));
    x3 = _mm512_xor_si512(fold(x3, by_block), load(p + 192));
  }
  const __m512i by_register = per_lane(k512, k512, k512, k512);
  x1 = _mm512_xor_si512(x1, fold(x0, by_register));
  x2 = _mm512_xor_si512(x2, fold(x1, by_register));
  x3 = _mm512_xor_si512(x3, fold(x2, by_register));
  // Lanes 0-2 of x3 folded onto lane 3: the message so far, reduced to 16 bytes that have the
  // same CRC from a zero register.
  // The fold's lane 3 is zero (so are its constants); lanes 0-2 of x3 are replaced by it.
  const __m512i lane3_only = _mm512_maskz_mov_epi64(0xC0, x3);
  alignas(64) std::array<uint8_t, 64> lanes;
  _mm512_store_si512(lanes.data(),
                     _mm512_xor_si512(lane3_only, fold(x3, per_lane(k384, k256, k128, {}))));
  __m128i last = _mm_load_si128(reinterpret_cast<const __m128i*>(lanes.data()));
  for (int lane = 1; lane < 4; ++lane) {
    last = _mm_xor_si128(
        last, _mm_load_si128(reinterpret_cast<const __m128i*>(lanes.data() + 16 * lane)));
  }
  std::array<uint8_t, 16> bytes;
  _mm_storeu_si128(reinterpret_cast<__m128i*>(bytes.data()), last);
  const uint32_t so_far = libdeflate_crc32(0xFFFFFFFF, bytes.data(), bytes.size());
  return libdeflate_crc32(so_far, p, n);
}

#undef ROBOTPERF_AVX512_CLMUL

bool has_vpclmulqdq() {
  static const bool has = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") &&
                          __builtin_cpu_supports("vpclmulqdq");
  return has;
}

}  // namespace

uint32_t crc32(std::span<const uint8_t> bytes, uint32_t crc) {
  if (bytes.size() >= kBlock && has_vpclmulqdq())
    return crc32_vpclmulqdq(bytes.data(), bytes.size(), crc);
  return libdeflate_crc32(crc, bytes.data(), bytes.size());
}

}  // namespace robotperf::bag::mcap
