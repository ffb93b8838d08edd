#include "robotperf/msgs/definitions.hpp"

#include <algorithm>
#include <map>
#include <set>
#include <sstream>
#include <vector>

namespace robotperf::msgs {
namespace {

// Field lists of the ROS 2 interfaces (types and names only: comments and
// constants carry no wire information; defaults are kept where ROS states
// them). Nested types are found from the fields, so adding a type is one entry.
const std::map<std::string_view, std::string_view>& definitions() {
  static const std::map<std::string_view, std::string_view> table{
      {"builtin_interfaces/msg/Time", "int32 sec\nuint32 nanosec\n"},
      {"builtin_interfaces/msg/Duration", "int32 sec\nuint32 nanosec\n"},
      {"std_msgs/msg/Header", "builtin_interfaces/Time stamp\nstring frame_id\n"},
      {"std_msgs/msg/MultiArrayDimension", "string label\nuint32 size\nuint32 stride\n"},
      {"std_msgs/msg/MultiArrayLayout", "MultiArrayDimension[] dim\nuint32 data_offset\n"},
      {"std_msgs/msg/Float64MultiArray", "MultiArrayLayout layout\nfloat64[] data\n"},
      {"sensor_msgs/msg/RegionOfInterest",
       "uint32 x_offset\nuint32 y_offset\nuint32 height\nuint32 width\nbool do_rectify\n"},
      {"sensor_msgs/msg/Image",
       "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\n"
       "uint8 is_bigendian\nuint32 step\nuint8[] data\n"},
      {"sensor_msgs/msg/CameraInfo",
       "std_msgs/Header header\nuint32 height\nuint32 width\nstring distortion_model\n"
       "float64[] d\nfloat64[9] k\nfloat64[9] r\nfloat64[12] p\nuint32 binning_x\n"
       "uint32 binning_y\nRegionOfInterest roi\n"},
      {"sensor_msgs/msg/PointField", "string name\nuint32 offset\nuint8 datatype\nuint32 count\n"},
      {"sensor_msgs/msg/PointCloud2",
       "std_msgs/Header header\nuint32 height\nuint32 width\nPointField[] fields\n"
       "bool is_bigendian\nuint32 point_step\nuint32 row_step\nuint8[] data\nbool is_dense\n"},
      {"sensor_msgs/msg/JointState",
       "std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\n"
       "float64[] effort\n"},
      {"stereo_msgs/msg/DisparityImage",
       "std_msgs/Header header\nsensor_msgs/Image image\nfloat32 f\nfloat32 t\n"
       "sensor_msgs/RegionOfInterest valid_window\nfloat32 min_disparity\n"
       "float32 max_disparity\nfloat32 delta_d\n"},
      {"geometry_msgs/msg/Vector3", "float64 x\nfloat64 y\nfloat64 z\n"},
      {"geometry_msgs/msg/Point", "float64 x\nfloat64 y\nfloat64 z\n"},
      {"geometry_msgs/msg/Quaternion", "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n"},
      {"geometry_msgs/msg/Pose", "Point position\nQuaternion orientation\n"},
      {"geometry_msgs/msg/PoseStamped", "std_msgs/Header header\nPose pose\n"},
      {"geometry_msgs/msg/PoseArray", "std_msgs/Header header\nPose[] poses\n"},
      {"geometry_msgs/msg/PoseWithCovariance", "Pose pose\nfloat64[36] covariance\n"},
      {"geometry_msgs/msg/PoseWithCovarianceStamped",
       "std_msgs/Header header\nPoseWithCovariance pose\n"},
      {"geometry_msgs/msg/Twist", "Vector3 linear\nVector3 angular\n"},
      {"geometry_msgs/msg/TwistStamped", "std_msgs/Header header\nTwist twist\n"},
      {"geometry_msgs/msg/TwistWithCovariance", "Twist twist\nfloat64[36] covariance\n"},
      {"geometry_msgs/msg/Transform", "Vector3 translation\nQuaternion rotation\n"},
      {"geometry_msgs/msg/TransformStamped",
       "std_msgs/Header header\nstring child_frame_id\nTransform transform\n"},
      {"nav_msgs/msg/Odometry",
       "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/PoseWithCovariance pose\n"
       "geometry_msgs/TwistWithCovariance twist\n"},
      {"nav_msgs/msg/MapMetaData",
       "builtin_interfaces/Time map_load_time\nfloat32 resolution\nuint32 width\n"
       "uint32 height\ngeometry_msgs/Pose origin\n"},
      {"nav_msgs/msg/OccupancyGrid", "std_msgs/Header header\nMapMetaData info\nint8[] data\n"},
      {"sensor_msgs/msg/LaserScan",
       "std_msgs/Header header\nfloat32 angle_min\nfloat32 angle_max\nfloat32 angle_increment\n"
       "float32 time_increment\nfloat32 scan_time\nfloat32 range_min\nfloat32 range_max\n"
       "float32[] ranges\nfloat32[] intensities\n"},
      {"apriltag_msgs/msg/Point", "float64 x\nfloat64 y\n"},
      {"apriltag_msgs/msg/AprilTagDetection",
       "string family\nint32 id\nint32 hamming\nfloat32 goodness\nfloat32 decision_margin\n"
       "Point centre\nPoint[4] corners\nfloat64[9] homography\n"},
      {"apriltag_msgs/msg/AprilTagDetectionArray",
       "std_msgs/Header header\nAprilTagDetection[] detections\n"},
      {"tf2_msgs/msg/TFMessage", "geometry_msgs/TransformStamped[] transforms\n"},
      {"trajectory_msgs/msg/JointTrajectoryPoint",
       "float64[] positions\nfloat64[] velocities\nfloat64[] accelerations\nfloat64[] effort\n"
       "builtin_interfaces/Duration time_from_start\n"},
      {"trajectory_msgs/msg/JointTrajectory",
       "std_msgs/Header header\nstring[] joint_names\nJointTrajectoryPoint[] points\n"},
      {"trajectory_msgs/msg/MultiDOFJointTrajectoryPoint",
       "geometry_msgs/Transform[] transforms\ngeometry_msgs/Twist[] velocities\n"
       "geometry_msgs/Twist[] accelerations\nbuiltin_interfaces/Duration time_from_start\n"},
      {"control_msgs/msg/JointTrajectoryControllerState",
       "std_msgs/Header header\nstring[] joint_names\n"
       "trajectory_msgs/JointTrajectoryPoint reference\n"
       "trajectory_msgs/JointTrajectoryPoint feedback\n"
       "trajectory_msgs/JointTrajectoryPoint error\n"
       "trajectory_msgs/JointTrajectoryPoint output\nstring[] multi_dof_joint_names\n"
       "trajectory_msgs/MultiDOFJointTrajectoryPoint multi_dof_reference\n"
       "trajectory_msgs/MultiDOFJointTrajectoryPoint multi_dof_feedback\n"
       "trajectory_msgs/MultiDOFJointTrajectoryPoint multi_dof_error\n"
       "trajectory_msgs/MultiDOFJointTrajectoryPoint multi_dof_output\n"
       "float64 speed_scaling_factor\n"},
      // ros_discovery_info's type (Iron and later: 16-byte GIDs), for its endpoints' type hash.
      {"rmw_dds_common/msg/Gid", "char[16] data\n"},
      {"rmw_dds_common/msg/NodeEntitiesInfo",
       "string<=256 node_namespace\nstring<=256 node_name\nGid[] reader_gid_seq\n"
       "Gid[] writer_gid_seq\n"},
      {"rmw_dds_common/msg/ParticipantEntitiesInfo",
       "Gid gid\nNodeEntitiesInfo[] node_entities_info_seq\n"},
      // robotperf's own (not ROS 2 interfaces): the manipulation kernels' results.
      {"robotperf_msgs/msg/CollisionResult",
       "std_msgs/Header header\nbool in_collision\nbool with_scene\nstring first\nstring second\n"},
      {"robotperf_msgs/msg/PlanExecutionResult",
       "std_msgs/Header header\nbool success\nfloat64 planning_time\n"
       "trajectory_msgs/JointTrajectory trajectory\nfloat64 path_length\n"
       "uint32 execution_steps\nfloat64 max_tracking_error\nfloat64 final_error\n"},
  };
  return table;
}

// The nested message types named by `fields` ("pkg/msg/Type"), in field order.
std::vector<std::string> nested_types(std::string_view own_type, std::string_view fields) {
  static const std::set<std::string, std::less<>> primitives{
      "bool",   "byte",  "char",   "int8",    "uint8",   "int16",  "uint16", "int32",
      "uint32", "int64", "uint64", "float32", "float64", "string", "wstring"};
  const std::string own_package(own_type.substr(0, own_type.find('/')));
  std::vector<std::string> out;
  std::istringstream lines{std::string(fields)};
  std::string type;
  std::string rest;
  while (lines >> type && std::getline(lines, rest)) {
    type = type.substr(0, type.find_first_of("[<"));
    if (primitives.contains(type)) continue;
    if (type == "Header") {
      out.emplace_back("std_msgs/msg/Header");
    } else if (auto slash = type.find('/'); slash != std::string::npos) {
      out.push_back(type.substr(0, slash) + "/msg/" + type.substr(slash + 1));
    } else {
      out.push_back(own_package + "/msg/" + type);
    }
  }
  return out;
}

// Depth-first, each type once, in the order it is first needed.
void collect_dependencies(std::string_view type, std::vector<std::string>& seen) {
  for (const std::string& dep : nested_types(type, definitions().at(type))) {
    if (std::find(seen.begin(), seen.end(), dep) != seen.end()) continue;
    seen.push_back(dep);
    collect_dependencies(dep, seen);
  }
}

}  // namespace

std::optional<std::string> ros2msg_schema(std::string_view ros_type) {
  const auto& table = definitions();
  auto it = table.find(ros_type);
  if (it == table.end()) return std::nullopt;
  std::string out(it->second);
  std::vector<std::string> dependencies;
  collect_dependencies(ros_type, dependencies);
  for (const std::string& dep : dependencies) {
    // "pkg/msg/Type" is named "pkg/Type" after MSG:, as rosbag2 writes it.
    std::string name = dep;
    name.erase(name.find("/msg/"), 4);
    out += std::string(80, '=') + "\nMSG: " + name + "\n" + std::string(table.at(dep));
  }
  return out;
}

std::vector<std::string_view> builtin_message_types() {
  std::vector<std::string_view> out;
  for (const auto& [type, fields] : definitions()) out.push_back(type);
  return out;
}

}  // namespace robotperf::msgs
