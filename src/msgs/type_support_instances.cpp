// The one TypeSupport of each message type of a process: instantiated here, in the shared msgs
// library, and declared extern in the message headers, so that robotperf, its libraries and every
// plug-in it loads hold the same TypeSupport object for a type (datasets and evaluators compare
// them by address).
#include "robotperf/msgs/apriltag_msgs.hpp"
#include "robotperf/msgs/builtin_interfaces.hpp"
#include "robotperf/msgs/geometry_msgs.hpp"
#include "robotperf/msgs/nav_msgs.hpp"
#include "robotperf/msgs/robotperf_msgs.hpp"
#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/msgs/std_msgs.hpp"
#include "robotperf/msgs/stereo_msgs.hpp"
#include "robotperf/msgs/tf2_msgs.hpp"
#include "robotperf/msgs/trajectory_msgs.hpp"

namespace robotperf::msgs {

template const TypeSupport& type_support<Time>();
template const TypeSupport& type_support<Duration>();
template const TypeSupport& type_support<Vector3>();
template const TypeSupport& type_support<Point>();
template const TypeSupport& type_support<Quaternion>();
template const TypeSupport& type_support<Pose>();
template const TypeSupport& type_support<PoseStamped>();
template const TypeSupport& type_support<PoseArray>();
template const TypeSupport& type_support<PoseWithCovariance>();
template const TypeSupport& type_support<PoseWithCovarianceStamped>();
template const TypeSupport& type_support<Twist>();
template const TypeSupport& type_support<TwistStamped>();
template const TypeSupport& type_support<TwistWithCovariance>();
template const TypeSupport& type_support<Transform>();
template const TypeSupport& type_support<TransformStamped>();
template const TypeSupport& type_support<Odometry>();
template const TypeSupport& type_support<MapMetaData>();
template const TypeSupport& type_support<OccupancyGrid>();
template const TypeSupport& type_support<CollisionResult>();
template const TypeSupport& type_support<PlanExecutionResult>();
template const TypeSupport& type_support<RegionOfInterest>();
template const TypeSupport& type_support<CameraInfo>();
template const TypeSupport& type_support<Image>();
template const TypeSupport& type_support<PointField>();
template const TypeSupport& type_support<PointCloud2>();
template const TypeSupport& type_support<JointState>();
template const TypeSupport& type_support<LaserScan>();
template const TypeSupport& type_support<AprilTagPoint>();
template const TypeSupport& type_support<AprilTagDetection>();
template const TypeSupport& type_support<AprilTagDetectionArray>();
template const TypeSupport& type_support<Header>();
template const TypeSupport& type_support<MultiArrayDimension>();
template const TypeSupport& type_support<MultiArrayLayout>();
template const TypeSupport& type_support<Float64MultiArray>();
template const TypeSupport& type_support<DisparityImage>();
template const TypeSupport& type_support<TFMessage>();
template const TypeSupport& type_support<JointTrajectoryPoint>();
template const TypeSupport& type_support<JointTrajectory>();
template const TypeSupport& type_support<MultiDOFJointTrajectoryPoint>();
template const TypeSupport& type_support<JointTrajectoryControllerState>();

}  // namespace robotperf::msgs
