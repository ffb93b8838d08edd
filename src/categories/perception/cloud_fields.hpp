// Private to the perception category: reading the float32 fields of a PointCloud2's points.
#pragma once

#include <cstdint>
#include <cstring>

#include "robotperf/msgs/sensor_msgs.hpp"

namespace robotperf::perception {

// The float32 field `name` of a cloud's points, if it has one inside its point_step.
inline const msgs::PointField* float32_field(const msgs::PointCloud2& cloud, const char* name) {
  for (const auto& f : cloud.fields) {
    if (f.name == name && f.datatype == msgs::PointField::kFloat32 && f.count == 1 &&
        uint64_t{f.offset} + 4 <= cloud.point_step) {
      return &f;
    }
  }
  return nullptr;
}

inline float read_float(const uint8_t* point, const msgs::PointField& f) {
  float value;
  std::memcpy(&value, point + f.offset, sizeof value);
  return value;
}

// Whether a little-endian cloud's data holds its width x height points of point_step bytes,
// rows row_step apart.
inline bool holds_its_points(const msgs::PointCloud2& cloud) {
  return !cloud.is_bigendian && uint64_t{cloud.row_step} * cloud.height <= cloud.data.size() &&
         uint64_t{cloud.point_step} * cloud.width <= cloud.row_step;
}

}  // namespace robotperf::perception
