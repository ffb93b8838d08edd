#pragma once

#include "robotperf/msgs/sensor_msgs.hpp"

namespace robotperf::msgs {

// stereo_msgs/DisparityImage: a float disparity image with the stereo geometry that turns it into
// depth (Z = f * t / d).
struct DisparityImage {
  Header header;
  Image image;  // 32FC1 disparities in pixels
  float f = 0;  // focal length, pixels
  float t = 0;  // baseline, metres
  RegionOfInterest valid_window;
  float min_disparity = 0;
  float max_disparity = 0;
  float delta_d = 0;  // smallest step between disparity values
  friend bool operator==(const DisparityImage&, const DisparityImage&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, DisparityImage>
void visit_fields(V& v, M& m) {
  v(m.header);
  v(m.image);
  v(m.f);
  v(m.t);
  v(m.valid_window);
  v(m.min_disparity);
  v(m.max_disparity);
  v(m.delta_d);
}
template <>
struct MessageTraits<DisparityImage> {
  static constexpr std::string_view ros_type = "stereo_msgs/msg/DisparityImage";
};

// Their type supports live in the msgs library (type_support_instances.cpp).
extern template const TypeSupport& type_support<DisparityImage>();

}  // namespace robotperf::msgs
