#include <gtest/gtest.h>

#include <string_view>

#include "robotperf/plugin/content_hash.hpp"

namespace robotperf::plugin {
namespace {

uint64_t hash_raw(std::string_view text) {
  return Fnv1a64().add_raw({reinterpret_cast<const uint8_t*>(text.data()), text.size()}).digest();
}

TEST(Fnv1a64, MatchesReferenceVectors) {
  // From the FNV reference test suite.
  EXPECT_EQ(hash_raw(""), 0xcbf29ce484222325ULL);
  EXPECT_EQ(hash_raw("a"), 0xaf63dc4c8601ec8cULL);
  EXPECT_EQ(hash_raw("foobar"), 0x85944171f73967e8ULL);
}

TEST(Fnv1a64, FramesFieldsUnambiguously) {
  // Length prefixes keep "ab" + "c" apart from "a" + "bc".
  EXPECT_NE(Fnv1a64().add_string("ab").add_string("c").digest(),
            Fnv1a64().add_string("a").add_string("bc").digest());
  EXPECT_NE(Fnv1a64().add_f64(0.0).digest(), Fnv1a64().add_f64(-0.0).digest());
  // Integers are little-endian whatever the host.
  EXPECT_EQ(Fnv1a64().add_u32(0x04030201u).digest(), hash_raw("\x01\x02\x03\x04"));
  EXPECT_EQ(Fnv1a64().add_i32(-1).digest(), Fnv1a64().add_u32(0xffffffffu).digest());
}

TEST(Fnv1a64, HexDigest) {
  EXPECT_EQ(Fnv1a64().hex_digest(), "fnv1a64:cbf29ce484222325");
  EXPECT_EQ(Fnv1a64().add_u8('a').hex_digest(), "fnv1a64:af63dc4c8601ec8c");
}

}  // namespace
}  // namespace robotperf::plugin
