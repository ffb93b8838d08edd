// Type-erased description of a message type, used by transports that must
// name, create, serialize and deserialize messages without knowing their C++ type.
#pragma once

#include <concepts>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>

#include "robotperf/msgs/cdr.hpp"

namespace robotperf::msgs {

// Specialised for every message type: its ROS 2 and DDS type names.
template <class T>
struct MessageTraits;

// "sensor_msgs/msg/Image" -> "sensor_msgs::msg::dds_::Image_".
std::string dds_type_name(std::string_view ros_type);
// The inverse: "sensor_msgs::msg::dds_::Image_" -> "sensor_msgs/msg/Image"; a name not of that
// form (a plain DDS type) is returned as it is.
std::string ros_type_name(std::string_view dds_type);

struct TypeSupport {
  std::string ros_type;  // "sensor_msgs/msg/Image"
  std::string dds_type;  // "sensor_msgs::msg::dds_::Image_"
  // Exact CDR size of `msg`, the 4-byte encapsulation header included.
  std::size_t (*serialized_size)(const void* msg);
  // Writes header + body into `out`, which holds serialized_size(msg) bytes.
  void (*serialize)(const void* msg, std::span<uint8_t> out);
  // A default-constructed message.
  std::shared_ptr<void> (*create)();
  // Replaces *msg with the decoded payload; throws CdrError when malformed.
  void (*deserialize)(std::span<const uint8_t> payload, void* msg);
  // For types that start with a std_msgs/Header (null otherwise): read the
  // header stamp in nanoseconds, and copy a message giving it a new stamp.
  // The harness carries message IDs in the stamp (docs/design.md §3.1). Header-less
  // types with a HasMessageIdField trait (Float64MultiArray) read and write
  // their ID there instead.
  int64_t (*stamp_ns)(const void* msg);
  std::shared_ptr<void> (*copy_with_stamp_ns)(const void* msg, int64_t stamp_ns);

  bool stamped() const { return stamp_ns != nullptr; }
};

template <class T>
concept HasHeaderStamp = requires(T& m) {
  m.header.stamp.sec;
  m.header.stamp.nanosec;
};

// Header-less types that carry a message ID elsewhere (MessageTraits<T>::id_ns / set_id_ns),
// e.g. std_msgs/Float64MultiArray in a layout label.
template <class T>
concept HasMessageIdField = requires(T& m, const T& c) {
  { MessageTraits<T>::id_ns(c) } -> std::same_as<int64_t>;
  MessageTraits<T>::set_id_ns(m, int64_t{});
};

template <class T>
auto stamp_reader() -> int64_t (*)(const void*) {
  if constexpr (HasMessageIdField<T>) {
    return [](const void* m) { return MessageTraits<T>::id_ns(*static_cast<const T*>(m)); };
  } else if constexpr (HasHeaderStamp<T>) {
    return [](const void* m) {
      const auto& s = static_cast<const T*>(m)->header.stamp;
      return int64_t{s.sec} * 1'000'000'000 + s.nanosec;
    };
  } else {
    return nullptr;
  }
}

template <class T>
auto stamp_writer() -> std::shared_ptr<void> (*)(const void*, int64_t) {
  if constexpr (HasMessageIdField<T>) {
    return [](const void* m, int64_t ns) -> std::shared_ptr<void> {
      auto copy = std::make_shared<T>(*static_cast<const T*>(m));
      MessageTraits<T>::set_id_ns(*copy, ns);
      return copy;
    };
  } else if constexpr (HasHeaderStamp<T>) {
    return [](const void* m, int64_t ns) -> std::shared_ptr<void> {
      auto copy = std::make_shared<T>(*static_cast<const T*>(m));
      copy->header.stamp.sec = static_cast<int32_t>(ns / 1'000'000'000);
      copy->header.stamp.nanosec = static_cast<uint32_t>(ns % 1'000'000'000);
      return copy;
    };
  } else {
    return nullptr;
  }
}

template <class T>
const TypeSupport& type_support() {
  static const TypeSupport ts{
      std::string(MessageTraits<T>::ros_type),
      dds_type_name(MessageTraits<T>::ros_type),
      [](const void* m) {
        CdrSizer s;
        s(*static_cast<const T*>(m));
        return s.size();
      },
      [](const void* m, std::span<uint8_t> out) {
        CdrWriter w(out);
        w(*static_cast<const T*>(m));
      },
      []() -> std::shared_ptr<void> { return std::make_shared<T>(); },
      [](std::span<const uint8_t> payload, void* m) {
        CdrReader r(payload);
        r(*static_cast<T*>(m));
      },
      stamp_reader<T>(),
      stamp_writer<T>(),
  };
  return ts;
}

}  // namespace robotperf::msgs
