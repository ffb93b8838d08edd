// MCAP's CRC-32 on every path (folded with VPCLMULQDQ where the CPU has it, else libdeflate's)
// against a plain bit-by-bit CRC-32.
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "mcap_format.hpp"

namespace robotperf::bag::mcap {
namespace {

uint32_t bitwise_crc32(const std::vector<uint8_t>& bytes, std::size_t from, std::size_t to,
                       uint32_t crc) {
  uint32_t r = ~crc;
  for (std::size_t i = from; i < to; ++i) {
    r ^= bytes[i];
    for (int b = 0; b < 8; ++b) r = (r >> 1) ^ (0xEDB88320u & (0u - (r & 1u)));
  }
  return ~r;
}

TEST(Crc32, CheckValueOfTheStandard) {
  const std::string nine = "123456789";
  EXPECT_EQ(crc32({reinterpret_cast<const uint8_t*>(nine.data()), nine.size()}), 0xCBF43926u);
}

TEST(Crc32, EveryLengthAndSplitMatchesTheBitwiseCrc) {
  std::mt19937 random(47);
  std::vector<uint8_t> data(5000);
  for (auto& b : data) b = static_cast<uint8_t>(random());
  // Lengths around the 256-byte blocks of the folded path, and large ones.
  for (std::size_t n : {0, 1, 15, 16, 255, 256, 257, 511, 512, 513, 767, 1024, 1500, 4096, 5000}) {
    const std::span<const uint8_t> bytes(data.data(), n);
    EXPECT_EQ(crc32(bytes), bitwise_crc32(data, 0, n, 0)) << n << " bytes";
    // Continued from a running CRC, as chunks are checked piece by piece.
    const std::size_t split = n / 3;
    const uint32_t first = crc32(bytes.first(split));
    EXPECT_EQ(crc32(bytes.subspan(split), first), bitwise_crc32(data, 0, n, 0))
        << n << " bytes split at " << split;
  }
}

}  // namespace
}  // namespace robotperf::bag::mcap
