// Malformed CDR input must be rejected with CdrError: never a crash, never a
// read past the end of the payload (this suite runs under ASan in CI, and every
// payload here lives in a heap buffer of exactly its own size so that an
// over-read is caught), never an allocation sized by a bogus length field.
#include <gtest/gtest.h>

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "allocation_limit.hpp"
#include "robotperf/msgs/cdr.hpp"
#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/msgs/std_msgs.hpp"
#include "robotperf/msgs/tf2_msgs.hpp"

namespace robotperf::msgs {
namespace {

using Bytes = std::vector<uint8_t>;

Image SampleImage() {
  Image img;
  img.header = Header{{10, 20}, "camera"};
  img.height = 1;
  img.width = 2;
  img.encoding = "rgb8";
  img.step = 6;
  img.data = {1, 2, 3, 4, 5, 6};
  return img;
}

CameraInfo SampleCameraInfo() {
  CameraInfo ci;
  ci.header = Header{{1, 2}, "cam"};
  ci.height = 480;
  ci.width = 640;
  ci.distortion_model = "plumb_bob";
  ci.d = {0.5, -0.25, 0.125};
  ci.k = {500, 0, 320, 0, 500, 240, 0, 0, 1};
  ci.roi = RegionOfInterest{1, 2, 3, 4, true};
  return ci;
}

// Decodes the first `len` bytes of `full`, copied into a heap block of exactly
// `len` bytes (so ASan sees any read past the end).
template <class T>
void DecodePrefix(const Bytes& full, size_t len) {
  std::unique_ptr<uint8_t[]> exact(new uint8_t[len == 0 ? 1 : len]);
  std::copy(full.begin(), full.begin() + static_cast<std::ptrdiff_t>(len), exact.get());
  (void)from_cdr<T>(std::span<const uint8_t>(exact.get(), len));
}

TEST(CdrMalformed, EveryTruncationOfAnImageThrows) {
  const Bytes full = to_cdr(SampleImage());
  ASSERT_EQ(full.size(), 58u);
  ASSERT_NO_THROW(DecodePrefix<Image>(full, full.size()));
  for (size_t len = 0; len < full.size(); ++len) {
    EXPECT_THROW(DecodePrefix<Image>(full, len), CdrError) << "prefix of " << len << " bytes";
  }
}

TEST(CdrMalformed, EveryTruncationOfACameraInfoThrows) {
  const Bytes full = to_cdr(SampleCameraInfo());
  ASSERT_NO_THROW(DecodePrefix<CameraInfo>(full, full.size()));
  for (size_t len = 0; len < full.size(); ++len) {
    EXPECT_THROW(DecodePrefix<CameraInfo>(full, len), CdrError) << "prefix of " << len << " bytes";
  }
}

TEST(CdrMalformed, TrailingBytesAreIgnored) {
  // Cyclone DDS pads samples to a multiple of 4; readers ignore what follows
  // the last field.
  const Image img = SampleImage();
  Bytes padded = to_cdr(img);
  padded.insert(padded.end(), {0x00, 0x00});
  EXPECT_EQ(from_cdr<Image>(padded), img);
}

TEST(CdrMalformed, BigEndianHeaderThrows) {
  Bytes payload = to_cdr(SampleImage());
  payload[1] = 0x00;  // 00 00 = CDR_BE
  EXPECT_THROW(from_cdr<Image>(payload), CdrError);
}

TEST(CdrMalformed, GarbageHeadersThrow) {
  const Bytes good = to_cdr(SampleImage());
  const uint8_t headers[][2] = {
      {0x12, 0x34},  // garbage
      {0x00, 0x02},  // PL_CDR_BE
      {0x00, 0x03},  // PL_CDR_LE (parameter list)
      {0x00, 0x07},  // PLAIN_CDR2_LE (XCDR2), not what ROS 2 sends by default
      {0x01, 0x01},  // first byte must be 0
      {0xFF, 0xFF},
  };
  for (const auto& h : headers) {
    Bytes payload = good;
    payload[0] = h[0];
    payload[1] = h[1];
    EXPECT_THROW(from_cdr<Image>(payload), CdrError) << int{h[0]} << "," << int{h[1]};
  }
  // The options bytes (2 and 3) are ignored.
  Bytes options = good;
  options[2] = 0x00;
  options[3] = 0x02;
  EXPECT_EQ(from_cdr<Image>(options), SampleImage());
}

TEST(CdrMalformed, StringWithoutNulThrows) {
  const Bytes payload = {
      0x00, 0x01, 0x00, 0x00,  // header
      0x01, 0x00, 0x00, 0x00,  // sec
      0x02, 0x00, 0x00, 0x00,  // nanosec
      0x04, 0x00, 0x00, 0x00,  // frame_id length 4
      'c',  'a',  'm',  'X',   // ... but the last byte is not NUL
  };
  EXPECT_THROW(from_cdr<Header>(payload), CdrError);
}

TEST(CdrMalformed, StringLengthBeyondPayloadThrows) {
  for (uint8_t top : {uint8_t{0x00}, uint8_t{0x7F}, uint8_t{0xFF}}) {
    const Bytes payload = {
        0x00, 0x01, 0x00, 0x00,  // header
        0x00, 0x00, 0x00, 0x00,  // sec
        0x00, 0x00, 0x00, 0x00,  // nanosec
        0xF0, 0xFF, 0xFF, top,   // frame_id length: huge (or 0xFFFFF0 for top == 0)
        'c',  'a',  'm',  0x00,
    };
    EXPECT_THROW(from_cdr<Header>(payload), CdrError) << int{top};
  }
  // One byte more than is there.
  const Bytes off_by_one = {
      0x00, 0x01, 0x00, 0x00, 0, 0, 0, 0, 0, 0, 0, 0, 0x05, 0x00, 0x00, 0x00, 'c', 'a', 'm', 0x00,
  };
  EXPECT_THROW(from_cdr<Header>(off_by_one), CdrError);
}

TEST(CdrMalformed, EmptyStringWithZeroLengthIsAccepted) {
  // Some writers encode "" as length 0 with no NUL byte at all.
  const Bytes payload = {
      0x00, 0x01, 0x00, 0x00,  // header
      0x05, 0x00, 0x00, 0x00,  // sec = 5
      0x06, 0x00, 0x00, 0x00,  // nanosec = 6
      0x00, 0x00, 0x00, 0x00,  // frame_id length 0
  };
  const Header h = from_cdr<Header>(payload);
  EXPECT_EQ(h.stamp, (Time{5, 6}));
  EXPECT_EQ(h.frame_id, "");

  // ... also in the middle of a message, where the next field follows at once.
  const Bytes roi_after = {
      0x00, 0x01, 0x00, 0x00,  // header
      0x00, 0x00, 0x00, 0x00,  // @0 stamp.sec
      0x00, 0x00, 0x00, 0x00,  // @4 stamp.nanosec
      0x00, 0x00, 0x00, 0x00,  // @8 frame_id length 0
      0x01, 0x00, 0x00, 0x00,  // @12 height = 1
      0x02, 0x00, 0x00, 0x00,  // @16 width = 2
      0x00, 0x00, 0x00, 0x00,  // @20 encoding length 0
      0x01,                    // @24 is_bigendian = 1
      0x00, 0x00, 0x00,        // pad
      0x09, 0x00, 0x00, 0x00,  // @28 step = 9
      0x00, 0x00, 0x00, 0x00,  // @32 data count 0
  };
  const Image img = from_cdr<Image>(roi_after);
  EXPECT_EQ(img.header.frame_id, "");
  EXPECT_EQ(img.height, 1u);
  EXPECT_EQ(img.width, 2u);
  EXPECT_EQ(img.encoding, "");
  EXPECT_EQ(img.is_bigendian, 1);
  EXPECT_EQ(img.step, 9u);
  EXPECT_TRUE(img.data.empty());
}

// Sets the uint32 at body offset `at` of `payload`.
void PutU32(Bytes& payload, size_t at, uint32_t v) {
  for (int i = 0; i < 4; ++i) payload[4 + at + i] = static_cast<uint8_t>(v >> (8 * i));
}

TEST(CdrMalformed, SequenceLengthBeyondPayloadThrowsWithoutHugeAllocation) {
  const Bytes good = to_cdr(SampleImage());
  // The data count of the sample image sits at body offset 44 (see the golden test).
  ASSERT_EQ(good[4 + 44], 6);
  for (uint32_t n : {7u, 1000u, 0x7FFFFFFFu, 0xFFFFFFFFu}) {
    Bytes payload = good;
    PutU32(payload, 44, n);
    Image img;
    CdrReader reader(payload);
    EXPECT_THROW(reader(img), CdrError) << n;
    // The count was rejected before the vector was sized from it.
    EXPECT_LE(img.data.capacity(), payload.size()) << n;
  }
}

TEST(CdrMalformed, Float64SequenceLengthBeyondPayloadThrows) {
  CameraInfo ci = SampleCameraInfo();
  const Bytes good = to_cdr(ci);
  // header "cam": frame_id ends @16; height @16, width @20, model length @24,
  // "plumb_bob" NUL @28..37, pad, d count @40.
  ASSERT_EQ(good[4 + 40], 3);
  for (uint32_t n : {4u, 40u, 100u, 0x10000000u, 0xFFFFFFFFu}) {
    Bytes payload = good;
    PutU32(payload, 40, n);
    CameraInfo back;
    CdrReader reader(payload);
    EXPECT_THROW(reader(back), CdrError) << n;
    // At most one element per payload byte may have been reserved.
    EXPECT_LE(back.d.capacity(), payload.size()) << n;
  }
}

// A count of elements that take far more memory than their bytes on the wire, as many as the
// payload has bytes: decoded as far as the bytes go, never allocated up front.
TEST(CdrMalformed, ForgedCountOfTransformsAllocatesNoMoreThanAFewTimesThePayload) {
  constexpr uint32_t n = 1 << 20;
  Bytes payload(4 + 4 + n, 0);
  payload[1] = 1;
  PutU32(payload, 0, n);
  const testing::AllocationLimit limit(4 * payload.size());
  EXPECT_THROW(from_cdr<TFMessage>(payload), CdrError);
}

TEST(CdrMalformed, ForgedCountOfDoublesIsRefusedBeforeAllocating) {
  Bytes payload = to_cdr(SampleCameraInfo());
  constexpr uint32_t n = 1 << 20;
  PutU32(payload, 40, n);  // the count of d (see Float64SequenceLengthBeyondPayloadThrows)
  payload.resize(payload.size() + n);
  const testing::AllocationLimit limit(4 * payload.size());
  EXPECT_THROW(from_cdr<CameraInfo>(payload), CdrError);
}

TEST(CdrMalformed, HeaderOnlyAndTinyPayloads) {
  const Bytes header_only = {0x00, 0x01, 0x00, 0x00};
  EXPECT_THROW(from_cdr<Time>(header_only), CdrError);
  EXPECT_THROW(from_cdr<Header>(header_only), CdrError);
  EXPECT_THROW(from_cdr<Time>(Bytes{}), CdrError);
  EXPECT_THROW(from_cdr<Time>(Bytes{0x00, 0x01, 0x00}), CdrError);
}

TEST(CdrMalformed, WriterRefusesTooSmallBuffer) {
  const Image img = SampleImage();
  CdrSizer sizer;
  sizer(img);
  for (size_t cap : {size_t{0}, size_t{3}, size_t{4}, sizer.size() - 1}) {
    std::unique_ptr<uint8_t[]> exact(new uint8_t[cap == 0 ? 1 : cap]);
    EXPECT_THROW(
        {
          CdrWriter w(std::span<uint8_t>(exact.get(), cap));
          w(img);
        },
        CdrError)
        << cap;
  }
}

}  // namespace
}  // namespace robotperf::msgs
