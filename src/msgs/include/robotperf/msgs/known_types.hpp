// Run-time dispatch from a ROS type name to the C++ message type.
#pragma once

#include <string_view>
#include <utility>

#include "robotperf/msgs/apriltag_msgs.hpp"
#include "robotperf/msgs/geometry_msgs.hpp"
#include "robotperf/msgs/nav_msgs.hpp"
#include "robotperf/msgs/robotperf_msgs.hpp"
#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/msgs/stereo_msgs.hpp"
#include "robotperf/msgs/tf2_msgs.hpp"
#include "robotperf/msgs/trajectory_msgs.hpp"

namespace robotperf::msgs {

template <class... Ts>
struct MessageTypeList {};

// The top-level messages graphs exchange (not the nested-only ones).
using KnownMessageTypes =
    MessageTypeList<Image, CameraInfo, PointCloud2, DisparityImage, JointState, Float64MultiArray,
                    Pose, PoseStamped, PoseArray, PoseWithCovarianceStamped, Twist, TwistStamped,
                    TransformStamped, Odometry, TFMessage, LaserScan, OccupancyGrid,
                    AprilTagDetectionArray, JointTrajectory, JointTrajectoryControllerState,
                    CollisionResult, PlanExecutionResult>;

// Calls `f.template operator()<T>()` for the message type named `ros_type`
// ("sensor_msgs/msg/Image"); returns false when the type is not compiled in.
template <class F>
bool with_message_type(std::string_view ros_type, F&& f) {
  return [&]<class... Ts>(MessageTypeList<Ts...>) {
    return (
        (ros_type == MessageTraits<Ts>::ros_type ? (f.template operator()<Ts>(), true) : false) ||
        ...);
  }(KnownMessageTypes{});
}

}  // namespace robotperf::msgs
