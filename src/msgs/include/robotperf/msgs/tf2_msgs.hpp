#pragma once

#include <vector>

#include "robotperf/msgs/geometry_msgs.hpp"

namespace robotperf::msgs {

// tf2_msgs/TFMessage: what is published on /tf.
struct TFMessage {
  std::vector<TransformStamped> transforms;
  friend bool operator==(const TFMessage&, const TFMessage&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, TFMessage>
void visit_fields(V& v, M& m) {
  v(m.transforms);
}
template <>
struct MessageTraits<TFMessage> {
  static constexpr std::string_view ros_type = "tf2_msgs/msg/TFMessage";
};

// Their type supports live in the msgs library (type_support_instances.cpp).
extern template const TypeSupport& type_support<TFMessage>();

}  // namespace robotperf::msgs
