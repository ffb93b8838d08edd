// Run-time dispatch from a ROS type name to the C++ message type.
#pragma once

#include <string_view>
#include <utility>

#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/msgs/stereo_msgs.hpp"

namespace robotperf::msgs {

// Calls `f.template operator()<T>()` for the message type named `ros_type`
// ("sensor_msgs/msg/Image"); returns false when the type is not compiled in.
template <class F>
bool with_message_type(std::string_view ros_type, F&& f) {
  if (ros_type == MessageTraits<Image>::ros_type) {
    f.template operator()<Image>();
  } else if (ros_type == MessageTraits<CameraInfo>::ros_type) {
    f.template operator()<CameraInfo>();
  } else if (ros_type == MessageTraits<PointCloud2>::ros_type) {
    f.template operator()<PointCloud2>();
  } else if (ros_type == MessageTraits<DisparityImage>::ros_type) {
    f.template operator()<DisparityImage>();
  } else {
    return false;
  }
  return true;
}

}  // namespace robotperf::msgs
