// Golden CDR bytes, derived by hand from the XCDR1 rules ROS 2 uses
// (docs/design.md §2): 4-byte encapsulation header 00 01 00 00; alignment counts
// from the byte after the header; each primitive aligned to its own size;
// string = uint32 length including the NUL, the bytes, the NUL; sequence =
// uint32 count then the elements; fixed array = the elements only; nested
// structs inline; bool and uint8 one byte. Offsets in the comments are body
// offsets (counted from the byte after the header).
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "robotperf/msgs/builtin_interfaces.hpp"
#include "robotperf/msgs/cdr.hpp"
#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/msgs/std_msgs.hpp"
#include "robotperf/msgs/stereo_msgs.hpp"
#include "robotperf/msgs/type_support.hpp"

namespace robotperf::msgs {
namespace {

using Bytes = std::vector<uint8_t>;

// Encodes `msg`, checks it against `expected`, checks that CdrSizer predicted
// the size, that the span writer produces the same bytes, and that decoding
// gives the message back.
template <class T>
void ExpectGolden(const T& msg, const Bytes& expected) {
  const Bytes got = to_cdr(msg);
  EXPECT_EQ(got, expected);

  CdrSizer sizer;
  sizer(msg);
  EXPECT_EQ(sizer.size(), expected.size());

  Bytes span_out(expected.size(), 0xAA);
  CdrWriter w{std::span<uint8_t>(span_out)};
  w(msg);
  EXPECT_EQ(w.size(), expected.size());
  EXPECT_EQ(span_out, expected);

  EXPECT_EQ(from_cdr<T>(expected), msg);
}

TEST(CdrGolden, Time) {
  const Time t{-2, 500'000'000};
  const Bytes expected = {
      0x00, 0x01, 0x00, 0x00,  // encapsulation: CDR_LE, options 0
      0xFE, 0xFF, 0xFF, 0xFF,  // @0 int32 sec = -2
      0x00, 0x65, 0xCD, 0x1D,  // @4 uint32 nanosec = 500000000 = 0x1DCD6500
  };
  ExpectGolden(t, expected);
}

TEST(CdrGolden, Duration) {
  const Duration d{7, 1};
  const Bytes expected = {
      0x00, 0x01, 0x00, 0x00,  // header
      0x07, 0x00, 0x00, 0x00,  // @0 sec = 7
      0x01, 0x00, 0x00, 0x00,  // @4 nanosec = 1
  };
  ExpectGolden(d, expected);
}

TEST(CdrGolden, Header) {
  const Header h{{1, 2}, "cam"};
  const Bytes expected = {
      0x00, 0x01, 0x00, 0x00,  // header
      0x01, 0x00, 0x00, 0x00,  // @0 stamp.sec = 1
      0x02, 0x00, 0x00, 0x00,  // @4 stamp.nanosec = 2
      0x04, 0x00, 0x00, 0x00,  // @8 frame_id length = 3 chars + NUL = 4
      'c',  'a',  'm',  0x00,  // @12 "cam" NUL
  };
  ExpectGolden(h, expected);
}

TEST(CdrGolden, HeaderWithEmptyFrameId) {
  const Header h{{0, 0}, ""};
  const Bytes expected = {
      0x00, 0x01, 0x00, 0x00,  // header
      0x00, 0x00, 0x00, 0x00,  // @0 sec
      0x00, 0x00, 0x00, 0x00,  // @4 nanosec
      0x01, 0x00, 0x00, 0x00,  // @8 length 1: an empty string is just its NUL
      0x00,                    // @12 NUL; no trailing padding is written
  };
  ExpectGolden(h, expected);
}

TEST(CdrGolden, RegionOfInterest) {
  const RegionOfInterest roi{1, 2, 3, 4, true};
  const Bytes expected = {
      0x00, 0x01, 0x00, 0x00,  // header
      0x01, 0x00, 0x00, 0x00,  // @0 x_offset
      0x02, 0x00, 0x00, 0x00,  // @4 y_offset
      0x03, 0x00, 0x00, 0x00,  // @8 height
      0x04, 0x00, 0x00, 0x00,  // @12 width
      0x01,                    // @16 do_rectify: bool is one byte
  };
  ExpectGolden(roi, expected);
}

Image SmallImage() {
  Image img;
  img.header = Header{{10, 20}, "camera"};
  img.height = 1;
  img.width = 2;
  img.encoding = "rgb8";
  img.is_bigendian = 0;
  img.step = 6;
  img.data = {1, 2, 3, 4, 5, 6};
  return img;
}

// A 2x1 rgb8 image.
const Bytes kSmallImageCdr = {
    0x00, 0x01, 0x00, 0x00,                    // header
    0x0A, 0x00, 0x00, 0x00,                    // @0 header.stamp.sec = 10
    0x14, 0x00, 0x00, 0x00,                    // @4 header.stamp.nanosec = 20
    0x07, 0x00, 0x00, 0x00,                    // @8 frame_id length = 6 + NUL
    'c',  'a',  'm',  'e',  'r',  'a',  0x00,  // @12..18 "camera" NUL
    0x00,                                      // @19 pad: uint32 height aligned to 4
    0x01, 0x00, 0x00, 0x00,                    // @20 height = 1
    0x02, 0x00, 0x00, 0x00,                    // @24 width = 2
    0x05, 0x00, 0x00, 0x00,                    // @28 encoding length = 4 + NUL
    'r',  'g',  'b',  '8',  0x00,              // @32..36 "rgb8" NUL
    0x00,                                      // @37 is_bigendian (uint8, no alignment)
    0x00, 0x00,                                // @38..39 pad: uint32 step aligned to 4
    0x06, 0x00, 0x00, 0x00,                    // @40 step = 6
    0x06, 0x00, 0x00, 0x00,                    // @44 data count = 6
    0x01, 0x02, 0x03, 0x04, 0x05, 0x06,        // @48..53 data (uint8[], no padding)
};

TEST(CdrGolden, Image2x1Rgb8) {
  ExpectGolden(SmallImage(), kSmallImageCdr);
}

CameraInfo SmallCameraInfo() {
  CameraInfo ci;
  ci.header = Header{{1, 2}, "cam"};
  ci.height = 480;
  ci.width = 640;
  ci.distortion_model = "plumb_bob";
  ci.d = {0.5, -0.25};
  ci.k = {500, 0, 320, 0, 500, 240, 0, 0, 1};
  ci.r = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  ci.p = {500, 0, 320, 0, 0, 500, 240, 0, 0, 0, 1, 0};
  ci.binning_x = 2;
  ci.binning_y = 3;
  ci.roi = RegionOfInterest{10, 20, 30, 40, true};
  return ci;
}

// float64 little-endian encodings used below:
//   0.0   = 00 00 00 00 00 00 00 00     1.0   = 00 00 00 00 00 00 F0 3F
//   0.5   = 00 00 00 00 00 00 E0 3F     -0.25 = 00 00 00 00 00 00 D0 BF
//   500.0 = 1.953125 * 2^8 = 0x407F400000000000 = 00 00 00 00 00 40 7F 40
//   320.0 = 1.25 * 2^8     = 0x4074000000000000 = 00 00 00 00 00 00 74 40
//   240.0 = 1.875 * 2^7    = 0x406E000000000000 = 00 00 00 00 00 00 6E 40
#define F64_0 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00
#define F64_1 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xF0, 0x3F
#define F64_500 0x00, 0x00, 0x00, 0x00, 0x00, 0x40, 0x7F, 0x40
#define F64_320 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x74, 0x40
#define F64_240 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x6E, 0x40

const Bytes kSmallCameraInfoCdr = {
    0x00, 0x01, 0x00, 0x00,                             // header
    0x01, 0x00, 0x00, 0x00,                             // @0 header.stamp.sec = 1
    0x02, 0x00, 0x00, 0x00,                             // @4 header.stamp.nanosec = 2
    0x04, 0x00, 0x00, 0x00,                             // @8 frame_id length 4
    'c', 'a', 'm', 0x00,                                // @12 "cam" NUL
    0xE0, 0x01, 0x00, 0x00,                             // @16 height = 480 = 0x1E0
    0x80, 0x02, 0x00, 0x00,                             // @20 width = 640 = 0x280
    0x0A, 0x00, 0x00, 0x00,                             // @24 distortion_model length = 9 + NUL
    'p', 'l', 'u', 'm', 'b', '_', 'b', 'o', 'b', 0x00,  // @28..37 "plumb_bob" NUL
    0x00, 0x00,                                         // @38..39 pad to 4
    0x02, 0x00, 0x00, 0x00,                             // @40 d count = 2
    0x00, 0x00, 0x00, 0x00,  // @44..47 pad: float64 aligned to 8 counting from after the
                             // header (counting from the buffer start would need no pad)
    0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xE0, 0x3F,  // @48 d[0] = 0.5
    0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xD0, 0xBF,  // @56 d[1] = -0.25
    // @64 k[9], a fixed array: no count, elements only.
    F64_500, F64_0, F64_320,  //
    F64_0, F64_500, F64_240,  //
    F64_0, F64_0, F64_1,      //
    // @136 r[9]
    F64_1, F64_0, F64_0,  //
    F64_0, F64_1, F64_0,  //
    F64_0, F64_0, F64_1,  //
    // @208 p[12]
    F64_500, F64_0, F64_320, F64_0,  //
    F64_0, F64_500, F64_240, F64_0,  //
    F64_0, F64_0, F64_1, F64_0,      //
    0x02, 0x00, 0x00, 0x00,          // @304 binning_x = 2
    0x03, 0x00, 0x00, 0x00,          // @308 binning_y = 3
    0x0A, 0x00, 0x00, 0x00,          // @312 roi.x_offset = 10
    0x14, 0x00, 0x00, 0x00,          // @316 roi.y_offset = 20
    0x1E, 0x00, 0x00, 0x00,          // @320 roi.height = 30
    0x28, 0x00, 0x00, 0x00,          // @324 roi.width = 40
    0x01,                            // @328 roi.do_rectify = true; 329 body bytes in all
};

TEST(CdrGolden, CameraInfo) {
  ASSERT_EQ(kSmallCameraInfoCdr.size(), 4u + 329u);
  ExpectGolden(SmallCameraInfo(), kSmallCameraInfoCdr);
}

TEST(CdrGolden, CameraInfoEmptyDistortionStillAlignsK) {
  // d empty: its count ends at @44; k's first float64 is still aligned to @48
  // (and an empty sequence writes no alignment of its own).
  CameraInfo ci = SmallCameraInfo();
  ci.d.clear();
  const Bytes got = to_cdr(ci);
  ASSERT_EQ(got.size(), kSmallCameraInfoCdr.size() - 16);
  const Bytes count_and_pad = {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00};
  EXPECT_EQ(Bytes(got.begin() + 4 + 40, got.begin() + 4 + 48), count_and_pad);
  const Bytes k500 = {F64_500};
  EXPECT_EQ(Bytes(got.begin() + 4 + 48, got.begin() + 4 + 56), k500);
  EXPECT_EQ(from_cdr<CameraInfo>(got), ci);
}

#undef F64_0
#undef F64_1
#undef F64_500
#undef F64_320
#undef F64_240

TEST(CdrGolden, PointCloud2) {
  PointCloud2 cloud;
  cloud.header = Header{{1, 2}, "cam"};
  cloud.height = 1;
  cloud.width = 2;
  cloud.fields = {PointField{"x", 0, PointField::kFloat32, 1}};
  cloud.point_step = 4;
  cloud.row_step = 8;
  cloud.data = {0x00, 0x00, 0xC0, 0x3F, 0x00, 0x00, 0x80, 0xBF};  // 1.5f, -1.0f
  cloud.is_dense = true;
  const Bytes expected = {
      0x00, 0x01, 0x00, 0x00,                          // header
      0x01, 0x00, 0x00, 0x00,                          // @0 header.stamp.sec = 1
      0x02, 0x00, 0x00, 0x00,                          // @4 header.stamp.nanosec = 2
      0x04, 0x00, 0x00, 0x00,                          // @8 frame_id length 4
      'c',  'a',  'm',  0x00,                          // @12 "cam" NUL
      0x01, 0x00, 0x00, 0x00,                          // @16 height = 1
      0x02, 0x00, 0x00, 0x00,                          // @20 width = 2
      0x01, 0x00, 0x00, 0x00,                          // @24 fields count = 1
      0x02, 0x00, 0x00, 0x00,                          // @28 fields[0].name length = 1 + NUL
      'x',  0x00,                                      // @32 "x" NUL
      0x00, 0x00,                                      // @34 pad: uint32 offset aligned to 4
      0x00, 0x00, 0x00, 0x00,                          // @36 offset = 0
      0x07,                                            // @40 datatype = FLOAT32
      0x00, 0x00, 0x00,                                // @41 pad
      0x01, 0x00, 0x00, 0x00,                          // @44 count = 1
      0x00,                                            // @48 is_bigendian
      0x00, 0x00, 0x00,                                // @49 pad
      0x04, 0x00, 0x00, 0x00,                          // @52 point_step = 4
      0x08, 0x00, 0x00, 0x00,                          // @56 row_step = 8
      0x08, 0x00, 0x00, 0x00,                          // @60 data count = 8
      0x00, 0x00, 0xC0, 0x3F, 0x00, 0x00, 0x80, 0xBF,  // @64 data
      0x01,                                            // @72 is_dense
  };
  ExpectGolden(cloud, expected);
}

TEST(CdrGolden, DisparityImage) {
  DisparityImage d;
  d.header = Header{{1, 2}, "cam"};
  d.image.header = d.header;
  d.image.height = 1;
  d.image.width = 2;
  d.image.encoding = "32FC1";
  d.image.step = 8;
  d.image.data = {0x00, 0x00, 0xC0, 0x3F, 0x00, 0x00, 0x80, 0xBF};  // 1.5f, -1.0f
  d.f = 500.0f;
  d.t = 0.1f;
  d.valid_window = RegionOfInterest{70, 7, 466, 563, false};
  d.min_disparity = 0.0f;
  d.max_disparity = 63.0f;
  d.delta_d = 0.0625f;
  const Bytes expected = {
      0x00, 0x01, 0x00, 0x00,                          // header
      0x01, 0x00, 0x00, 0x00,                          // @0 header.stamp.sec = 1
      0x02, 0x00, 0x00, 0x00,                          // @4 header.stamp.nanosec = 2
      0x04, 0x00, 0x00, 0x00,                          // @8 frame_id length 4
      'c',  'a',  'm',  0x00,                          // @12 "cam" NUL
      0x01, 0x00, 0x00, 0x00,                          // @16 image.header.stamp.sec
      0x02, 0x00, 0x00, 0x00,                          // @20 image.header.stamp.nanosec
      0x04, 0x00, 0x00, 0x00,                          // @24 image.header.frame_id length 4
      'c',  'a',  'm',  0x00,                          // @28 "cam" NUL
      0x01, 0x00, 0x00, 0x00,                          // @32 image.height = 1
      0x02, 0x00, 0x00, 0x00,                          // @36 image.width = 2
      0x06, 0x00, 0x00, 0x00,                          // @40 encoding length = 5 + NUL
      '3',  '2',  'F',  'C',  '1',  0x00,              // @44 "32FC1" NUL
      0x00,                                            // @50 image.is_bigendian
      0x00,                                            // @51 pad
      0x08, 0x00, 0x00, 0x00,                          // @52 image.step = 8
      0x08, 0x00, 0x00, 0x00,                          // @56 image.data count = 8
      0x00, 0x00, 0xC0, 0x3F, 0x00, 0x00, 0x80, 0xBF,  // @60 image.data
      0x00, 0x00, 0xFA, 0x43,                          // @68 f = 500.0f
      0xCD, 0xCC, 0xCC, 0x3D,                          // @72 t = 0.1f
      0x46, 0x00, 0x00, 0x00,                          // @76 valid_window.x_offset = 70
      0x07, 0x00, 0x00, 0x00,                          // @80 y_offset = 7
      0xD2, 0x01, 0x00, 0x00,                          // @84 height = 466
      0x33, 0x02, 0x00, 0x00,                          // @88 width = 563
      0x00,                                            // @92 do_rectify
      0x00, 0x00, 0x00,                                // @93 pad: float32 aligned to 4
      0x00, 0x00, 0x00, 0x00,                          // @96 min_disparity = 0
      0x00, 0x00, 0x7C, 0x42,                          // @100 max_disparity = 63
      0x00, 0x00, 0x80, 0x3D,                          // @104 delta_d = 1/16
  };
  ExpectGolden(d, expected);
  EXPECT_EQ(type_support<DisparityImage>().dds_type, "stereo_msgs::msg::dds_::DisparityImage_");
  EXPECT_EQ(type_support<PointCloud2>().dds_type, "sensor_msgs::msg::dds_::PointCloud2_");
}

TEST(CdrRoundTrip, LargerImage) {
  Image img;
  img.header = Header{{123456, 999'999'999}, "some/longer_frame"};
  img.height = 48;
  img.width = 64;
  img.encoding = "bgr8";
  img.step = 64 * 3;
  img.data.resize(size_t{img.step} * img.height);
  for (size_t i = 0; i < img.data.size(); ++i) img.data[i] = static_cast<uint8_t>(i * 31 + 7);
  const Bytes cdr = to_cdr(img);
  CdrSizer sizer;
  sizer(img);
  EXPECT_EQ(sizer.size(), cdr.size());
  EXPECT_EQ(from_cdr<Image>(cdr), img);
}

TEST(CdrRoundTrip, CameraInfoWithOddStringLengths) {
  // Vary the string lengths so that every alignment case of d is exercised.
  for (size_t frame_len = 0; frame_len < 9; ++frame_len) {
    for (size_t model_len = 0; model_len < 9; ++model_len) {
      CameraInfo ci = SmallCameraInfo();
      ci.header.frame_id = std::string(frame_len, 'f');
      ci.distortion_model = std::string(model_len, 'm');
      ci.d = {1.5, -2.5, 3.25, 0.0, 1e-9};
      const Bytes cdr = to_cdr(ci);
      CdrSizer sizer;
      sizer(ci);
      ASSERT_EQ(sizer.size(), cdr.size());
      ASSERT_EQ(from_cdr<CameraInfo>(cdr), ci) << frame_len << " " << model_len;
      // The float64 d[0] must sit at a multiple of 8 from the body start: find it.
      auto align = [](size_t at, size_t a) { return (at + a - 1) / a * a; };
      const size_t height_at = align(12 + frame_len + 1, 4);       // after stamp + frame_id
      const size_t model_end = height_at + 8 + 4 + model_len + 1;  // height, width, model
      const size_t count_at = align(model_end, 4);
      const size_t d0_at = align(count_at + 4, 8);
      double d0;
      std::memcpy(&d0, cdr.data() + 4 + d0_at, sizeof d0);
      EXPECT_EQ(d0, 1.5) << frame_len << " " << model_len;
    }
  }
}

TEST(TypeSupport, ImageThroughTypeErasedFunctions) {
  const TypeSupport& ts = type_support<Image>();
  EXPECT_EQ(ts.ros_type, "sensor_msgs/msg/Image");
  EXPECT_EQ(ts.dds_type, "sensor_msgs::msg::dds_::Image_");

  const Image img = SmallImage();
  ASSERT_EQ(ts.serialized_size(&img), kSmallImageCdr.size());
  Bytes out(ts.serialized_size(&img));
  ts.serialize(&img, out);
  EXPECT_EQ(out, kSmallImageCdr);

  std::shared_ptr<void> created = ts.create();
  ASSERT_NE(created, nullptr);
  EXPECT_EQ(*static_cast<Image*>(created.get()), Image{});
  ts.deserialize(out, created.get());
  EXPECT_EQ(*static_cast<Image*>(created.get()), img);

  // Deserializing replaces the previous contents (sequences are not appended to).
  ts.deserialize(out, created.get());
  EXPECT_EQ(static_cast<Image*>(created.get())->data.size(), 6u);

  // A buffer one byte too small is refused, not overrun.
  Bytes small(out.size() - 1);
  EXPECT_THROW(ts.serialize(&img, small), CdrError);
  // Malformed input through the type-erased path throws CdrError too.
  EXPECT_THROW(ts.deserialize(std::span<const uint8_t>(out).first(20), created.get()), CdrError);
}

TEST(TypeSupport, CameraInfoAndOthers) {
  const TypeSupport& ts = type_support<CameraInfo>();
  EXPECT_EQ(ts.dds_type, "sensor_msgs::msg::dds_::CameraInfo_");
  const CameraInfo ci = SmallCameraInfo();
  Bytes out(ts.serialized_size(&ci));
  ts.serialize(&ci, out);
  EXPECT_EQ(out, kSmallCameraInfoCdr);
  CameraInfo back;
  ts.deserialize(out, &back);
  EXPECT_EQ(back, ci);

  EXPECT_EQ(type_support<Header>().dds_type, "std_msgs::msg::dds_::Header_");
  EXPECT_EQ(type_support<Time>().dds_type, "builtin_interfaces::msg::dds_::Time_");
  EXPECT_EQ(type_support<RegionOfInterest>().dds_type, "sensor_msgs::msg::dds_::RegionOfInterest_");
  // The same object every time.
  EXPECT_EQ(&type_support<Image>(), &type_support<Image>());
}

TEST(TypeSupport, DdsTypeName) {
  EXPECT_EQ(dds_type_name("sensor_msgs/msg/Image"), "sensor_msgs::msg::dds_::Image_");
  EXPECT_EQ(dds_type_name("std_msgs/msg/String"), "std_msgs::msg::dds_::String_");
  EXPECT_EQ(dds_type_name("example_interfaces/srv/AddTwoInts_Request"),
            "example_interfaces::srv::dds_::AddTwoInts_Request_");
  EXPECT_THROW(dds_type_name("Image"), std::invalid_argument);
  EXPECT_THROW(dds_type_name("sensor_msgs/Image"), std::invalid_argument);
  EXPECT_THROW(dds_type_name(""), std::invalid_argument);
}

TEST(TypeSupport, RosTypeNameInvertsDdsTypeName) {
  for (const char* type : {"sensor_msgs/msg/Image", "example_interfaces/srv/AddTwoInts_Request",
                           "rmw_dds_common/msg/ParticipantEntitiesInfo"}) {
    EXPECT_EQ(ros_type_name(dds_type_name(type)), type);
  }
  EXPECT_EQ(ros_type_name("HelloWorld"), "HelloWorld") << "plain DDS types stay as they are";
  EXPECT_EQ(ros_type_name("a::dds_::B"), "a::dds_::B");
}

TEST(Time, NanosecondConversion) {
  EXPECT_EQ(Time::from_ns(1'500'000'000), (Time{1, 500'000'000}));
  EXPECT_EQ(Time::from_ns(1'500'000'000).to_ns(), 1'500'000'000);
  EXPECT_EQ((Time{2, 3}).to_ns(), 2'000'000'003);
  // Negative stamps: nanosec stays in [0, 1e9), as builtin_interfaces requires
  // and rclcpp does (-1 ns = sec -1 + 999999999 ns).
  EXPECT_EQ(Time::from_ns(-1), (Time{-1, 999'999'999}));
  EXPECT_EQ(Time::from_ns(-1'000'000'000), (Time{-1, 0}));
  EXPECT_EQ(Time::from_ns(-1'500'000'000), (Time{-2, 500'000'000}));
  for (int64_t ns : {int64_t{-3'000'000'001}, int64_t{-1}, int64_t{0}, int64_t{7},
                     int64_t{1'700'000'000'123'456'789}}) {
    EXPECT_EQ(Time::from_ns(ns).to_ns(), ns) << ns;
  }
}

}  // namespace
}  // namespace robotperf::msgs
