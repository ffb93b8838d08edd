#include "robotperf/msgs/definitions.hpp"

#include <map>
#include <vector>

namespace robotperf::msgs {
namespace {

struct Definition {
  std::string_view fields;
  std::vector<std::string_view> dependencies;  // every nested type, transitively
};

// Field lists of the ROS 2 interfaces (types and names only: comments and
// constants carry no wire information).
const std::map<std::string_view, Definition>& definitions() {
  static const std::map<std::string_view, Definition> table{
      {"builtin_interfaces/msg/Time", {"int32 sec\nuint32 nanosec\n", {}}},
      {"std_msgs/msg/Header",
       {"builtin_interfaces/Time stamp\nstring frame_id\n", {"builtin_interfaces/msg/Time"}}},
      {"sensor_msgs/msg/RegionOfInterest",
       {"uint32 x_offset\nuint32 y_offset\nuint32 height\nuint32 width\nbool do_rectify\n", {}}},
      {"sensor_msgs/msg/Image",
       {"std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\n"
        "uint8 is_bigendian\nuint32 step\nuint8[] data\n",
        {"std_msgs/msg/Header", "builtin_interfaces/msg/Time"}}},
      {"sensor_msgs/msg/CameraInfo",
       {"std_msgs/Header header\nuint32 height\nuint32 width\nstring distortion_model\n"
        "float64[] d\nfloat64[9] k\nfloat64[9] r\nfloat64[12] p\nuint32 binning_x\n"
        "uint32 binning_y\nRegionOfInterest roi\n",
        {"std_msgs/msg/Header", "builtin_interfaces/msg/Time",
         "sensor_msgs/msg/RegionOfInterest"}}},
      {"sensor_msgs/msg/PointField",
       {"string name\nuint32 offset\nuint8 datatype\nuint32 count\n", {}}},
      {"sensor_msgs/msg/PointCloud2",
       {"std_msgs/Header header\nuint32 height\nuint32 width\nPointField[] fields\n"
        "bool is_bigendian\nuint32 point_step\nuint32 row_step\nuint8[] data\nbool is_dense\n",
        {"std_msgs/msg/Header", "builtin_interfaces/msg/Time", "sensor_msgs/msg/PointField"}}},
      {"stereo_msgs/msg/DisparityImage",
       {"std_msgs/Header header\nsensor_msgs/Image image\nfloat32 f\nfloat32 t\n"
        "sensor_msgs/RegionOfInterest valid_window\nfloat32 min_disparity\n"
        "float32 max_disparity\nfloat32 delta_d\n",
        {"std_msgs/msg/Header", "builtin_interfaces/msg/Time", "sensor_msgs/msg/Image",
         "sensor_msgs/msg/RegionOfInterest"}}},
  };
  return table;
}

}  // namespace

std::optional<std::string> ros2msg_schema(std::string_view ros_type) {
  const auto& table = definitions();
  auto it = table.find(ros_type);
  if (it == table.end()) return std::nullopt;
  std::string out(it->second.fields);
  for (std::string_view dep : it->second.dependencies) {
    // "pkg/msg/Type" is named "pkg/Type" after MSG:, as rosbag2 writes it.
    std::string name(dep);
    name.erase(name.find("/msg/"), 4);
    out += std::string(80, '=') + "\nMSG: " + name + "\n" + std::string(table.at(dep).fields);
  }
  return out;
}

}  // namespace robotperf::msgs
