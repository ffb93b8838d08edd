// Test-only C++ mirrors of the ROS 2 `test_msgs` messages stored in the
// rosbag2 sqlite3_cdr_test bag (/usr/share/test_interface_files/msg/*.msg).
//
// Type mapping, as rosidl does it for C++ and on the wire:
//   bool -> bool (one byte), byte -> uint8_t, char -> uint8_t (rosidl maps the
//   .msg `char` to uint8: one unsigned byte on the wire, checked against the
//   bag's char defaults 100 and {0, 1, 127}), float32 -> float, float64 ->
//   double, intN/uintN -> intN_t/uintN_t,
//   string -> std::string, T[3] -> std::array<T, 3> (no length prefix).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <type_traits>

#include "robotperf/msgs/cdr.hpp"

namespace test_msgs {

// BasicTypes.msg
struct BasicTypes {
  bool bool_value = false;
  uint8_t byte_value = 0;
  uint8_t char_value = 0;
  float float32_value = 0;
  double float64_value = 0;
  int8_t int8_value = 0;
  uint8_t uint8_value = 0;
  int16_t int16_value = 0;
  uint16_t uint16_value = 0;
  int32_t int32_value = 0;
  uint32_t uint32_value = 0;
  int64_t int64_value = 0;
  uint64_t uint64_value = 0;
  friend bool operator==(const BasicTypes&, const BasicTypes&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, BasicTypes>
void visit_fields(V& v, M& m) {
  v(m.bool_value);
  v(m.byte_value);
  v(m.char_value);
  v(m.float32_value);
  v(m.float64_value);
  v(m.int8_value);
  v(m.uint8_value);
  v(m.int16_value);
  v(m.uint16_value);
  v(m.int32_value);
  v(m.uint32_value);
  v(m.int64_value);
  v(m.uint64_value);
}

// Constants.msg declares only constants, no fields. rosidl gives every
// field-less message one placeholder member, `uint8 structure_needs_at_least_one_member`,
// and the type supports serialize it: such a message is one byte on the wire.
struct Constants {
  static constexpr bool kBoolConst = true;
  static constexpr uint8_t kByteConst = 50;
  static constexpr uint8_t kCharConst = 100;
  static constexpr float kFloat32Const = 1.125f;
  static constexpr double kFloat64Const = 1.125;
  static constexpr int8_t kInt8Const = -50;
  static constexpr uint8_t kUint8Const = 200;
  static constexpr int16_t kInt16Const = -1000;
  static constexpr uint16_t kUint16Const = 2000;
  static constexpr int32_t kInt32Const = -30000;
  static constexpr uint32_t kUint32Const = 60000;
  static constexpr int64_t kInt64Const = -40000000;
  static constexpr uint64_t kUint64Const = 50000000;

  uint8_t structure_needs_at_least_one_member = 0;
  friend bool operator==(const Constants&, const Constants&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, Constants>
void visit_fields(V& v, M& m) {
  v(m.structure_needs_at_least_one_member);
}

// Defaults.msg: same fields as BasicTypes, with the .msg default values.
struct Defaults {
  bool bool_value = true;
  uint8_t byte_value = 50;
  uint8_t char_value = 100;
  float float32_value = 1.125f;
  double float64_value = 1.125;
  int8_t int8_value = -50;
  uint8_t uint8_value = 200;
  int16_t int16_value = -1000;
  uint16_t uint16_value = 2000;
  int32_t int32_value = -30000;
  uint32_t uint32_value = 60000;
  int64_t int64_value = -40000000;
  uint64_t uint64_value = 50000000;
  friend bool operator==(const Defaults&, const Defaults&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, Defaults>
void visit_fields(V& v, M& m) {
  v(m.bool_value);
  v(m.byte_value);
  v(m.char_value);
  v(m.float32_value);
  v(m.float64_value);
  v(m.int8_value);
  v(m.uint8_value);
  v(m.int16_value);
  v(m.uint16_value);
  v(m.int32_value);
  v(m.uint32_value);
  v(m.int64_value);
  v(m.uint64_value);
}

// Arrays.msg: fixed-size arrays of every basic type, of strings and of the
// three nested messages, then the same with .msg defaults, then an int32.
struct Arrays {
  std::array<bool, 3> bool_values{};
  std::array<uint8_t, 3> byte_values{};
  std::array<uint8_t, 3> char_values{};
  std::array<float, 3> float32_values{};
  std::array<double, 3> float64_values{};
  std::array<int8_t, 3> int8_values{};
  std::array<uint8_t, 3> uint8_values{};
  std::array<int16_t, 3> int16_values{};
  std::array<uint16_t, 3> uint16_values{};
  std::array<int32_t, 3> int32_values{};
  std::array<uint32_t, 3> uint32_values{};
  std::array<int64_t, 3> int64_values{};
  std::array<uint64_t, 3> uint64_values{};
  std::array<std::string, 3> string_values{};
  std::array<BasicTypes, 3> basic_types_values{};
  std::array<Constants, 3> constants_values{};
  std::array<Defaults, 3> defaults_values{};
  std::array<bool, 3> bool_values_default{false, true, false};
  std::array<uint8_t, 3> byte_values_default{0, 1, 255};
  std::array<uint8_t, 3> char_values_default{0, 1, 127};
  std::array<float, 3> float32_values_default{1.125f, 0.0f, -1.125f};
  std::array<double, 3> float64_values_default{3.1415, 0.0, -3.1415};
  std::array<int8_t, 3> int8_values_default{0, 127, -128};
  std::array<uint8_t, 3> uint8_values_default{0, 1, 255};
  std::array<int16_t, 3> int16_values_default{0, 32767, -32768};
  std::array<uint16_t, 3> uint16_values_default{0, 1, 65535};
  std::array<int32_t, 3> int32_values_default{0, 2147483647, -2147483647 - 1};
  std::array<uint32_t, 3> uint32_values_default{0, 1, 4294967295u};
  std::array<int64_t, 3> int64_values_default{0, INT64_MAX, INT64_MIN};
  std::array<uint64_t, 3> uint64_values_default{0, 1, UINT64_MAX};
  std::array<std::string, 3> string_values_default{"", "max value", "min value"};
  int32_t alignment_check = 0;
  friend bool operator==(const Arrays&, const Arrays&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, Arrays>
void visit_fields(V& v, M& m) {
  v(m.bool_values);
  v(m.byte_values);
  v(m.char_values);
  v(m.float32_values);
  v(m.float64_values);
  v(m.int8_values);
  v(m.uint8_values);
  v(m.int16_values);
  v(m.uint16_values);
  v(m.int32_values);
  v(m.uint32_values);
  v(m.int64_values);
  v(m.uint64_values);
  v(m.string_values);
  v(m.basic_types_values);
  v(m.constants_values);
  v(m.defaults_values);
  v(m.bool_values_default);
  v(m.byte_values_default);
  v(m.char_values_default);
  v(m.float32_values_default);
  v(m.float64_values_default);
  v(m.int8_values_default);
  v(m.uint8_values_default);
  v(m.int16_values_default);
  v(m.uint16_values_default);
  v(m.int32_values_default);
  v(m.uint32_values_default);
  v(m.int64_values_default);
  v(m.uint64_values_default);
  v(m.string_values_default);
  v(m.alignment_check);
}

}  // namespace test_msgs
