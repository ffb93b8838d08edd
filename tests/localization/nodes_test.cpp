// The localization kernels as graph nodes, driven by hand on the intra transport: what they
// read from their messages (the stereo pair's calibration), what they publish (the odometry's
// twist) and the parameters they refuse when the graph is built.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>
#include <opencv2/core.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "robotperf/graph/node.hpp"
#include "robotperf/localization/synthetic_odometry.hpp"
#include "robotperf/localization/trajectory_metrics.hpp"
#include "robotperf/msgs/eigen_geometry.hpp"
#include "robotperf/msgs/nav_msgs.hpp"
#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/perception/camera_model.hpp"
#include "robotperf/perception/image_proc.hpp"
#include "robotperf/plugin/registry.hpp"
#include "robotperf/rmw/transport.hpp"

namespace robotperf::localization {
namespace {

// A kernel's node built as the harness builds it, and a driver node beside it on one intra
// context; run() executes both nodes' callbacks until none has work left.
class KernelUnderTest {
 public:
  KernelUnderTest(const std::string& kernel, const std::map<std::string, std::string>& parameters,
                  std::map<std::string, std::string> topics)
      : context_(rmw::make_transport("intra")) {
    const plugin::KernelEntry* entry = plugin::registry().find_kernel(kernel);
    if (entry == nullptr) throw std::logic_error("no kernel " + kernel);
    plugin::KernelConfig config;
    config.node_name = "under_test";
    config.parameters = plugin::Parameters(entry->info.parameters, parameters, "under_test");
    config.topics = std::move(topics);
    node_ = entry->factory(context_, config);
    driver_ = std::make_shared<graph::Node>(context_, "driver");
  }

  graph::Node& driver() { return *driver_; }

  void run() {
    for (bool busy = true; busy;) {
      busy = false;
      for (const auto* node : {node_.get(), driver_.get()})
        for (const auto& entity : node->entities()) busy = entity->execute() || busy;
    }
  }

  std::map<std::string, uint64_t> counters() const {
    return dynamic_cast<const plugin::NodeCounters&>(*node_).counters();
  }

 private:
  graph::Context context_;
  std::shared_ptr<graph::Node> node_;
  std::shared_ptr<graph::Node> driver_;
};

// localization/stereo_odometry with a pair's four inputs and its odometry output.
class StereoOdometryNode {
 public:
  explicit StereoOdometryNode(const SyntheticOdometryConfig& config)
      : kernel_("localization/stereo_odometry", {},
                {{"left_image", "/left/image_rect"},
                 {"left_camera_info", "/left/camera_info"},
                 {"right_image", "/right/image_rect"},
                 {"right_camera_info", "/right/camera_info"},
                 {"odom", "/odom"}}),
        left_image_(kernel_.driver().create_publisher<msgs::Image>("/left/image_rect")),
        left_info_(kernel_.driver().create_publisher<msgs::CameraInfo>("/left/camera_info")),
        right_image_(kernel_.driver().create_publisher<msgs::Image>("/right/image_rect")),
        right_info_(kernel_.driver().create_publisher<msgs::CameraInfo>("/right/camera_info")),
        odometry_(kernel_.driver().create_subscription<msgs::Odometry>(
            "/odom", graph::QoS{},
            [this](std::shared_ptr<const msgs::Odometry> m) { received.push_back(*m); })) {
    // The dataset's calibration (localization/stereo_odometry).
    left_camera = perception::make_pinhole_camera_info(config.width, config.height, config.hfov_rad,
                                                       std::vector<double>(5, 0.0),
                                                       "left_camera_optical_frame");
    right_camera = left_camera;
    right_camera.header.frame_id = "right_camera_optical_frame";
    right_camera.p[3] = -right_camera.p[0] * config.baseline_m;
  }

  // One stereo pair at `stamp_s`, with the cameras' current CameraInfos.
  void send(const cv::Mat& left, const cv::Mat& right, double stamp_s) {
    msgs::Header header;
    header.stamp = msgs::Time::from_ns(std::llround(stamp_s * 1e9));
    header.frame_id = left_camera.header.frame_id;
    left_image_->publish(mono_image(left, header));
    left_camera.header.stamp = header.stamp;
    left_info_->publish(left_camera);
    header.frame_id = right_camera.header.frame_id;
    right_image_->publish(mono_image(right, header));
    right_camera.header.stamp = header.stamp;
    right_info_->publish(right_camera);
    kernel_.run();
  }

  std::map<std::string, uint64_t> counters() const { return kernel_.counters(); }

  msgs::CameraInfo left_camera, right_camera;
  std::vector<msgs::Odometry> received;

 private:
  static msgs::Image mono_image(const cv::Mat& pixels, const msgs::Header& header) {
    msgs::Image image;
    pixels.copyTo(perception::prepare_image(image, header, "mono8", pixels.cols, pixels.rows));
    return image;
  }

  KernelUnderTest kernel_;
  std::shared_ptr<graph::Publisher<msgs::Image>> left_image_;
  std::shared_ptr<graph::Publisher<msgs::CameraInfo>> left_info_;
  std::shared_ptr<graph::Publisher<msgs::Image>> right_image_;
  std::shared_ptr<graph::Publisher<msgs::CameraInfo>> right_info_;
  std::shared_ptr<graph::GenericSubscription> odometry_;
};

// The image a camera `px` pixels to the left of its principal point would take: the content
// moved left, its last columns repeated.
cv::Mat moved_left(const cv::Mat& image, int px) {
  cv::Mat out = image.clone();
  image.colRange(px, image.cols).copyTo(out.colRange(0, image.cols - px));
  for (int c = image.cols - px; c < image.cols; ++c) image.col(image.cols - 1).copyTo(out.col(c));
  return out;
}

// A rectification may put the right principal point in another column than the left's
// (image_geometry's StereoCameraModel triangulates Z = fx * baseline / (d - (cx_l - cx_r))): the
// same scene with the right camera's cx 8 px lower and its images moved 8 px left is the same
// geometry, and the odometry must hold b1's drift limits on it. Triangulating the raw disparity
// would put every point 20 to 30 % too near.
TEST(StereoOdometryNodeCalibration, TriangulatesWithTheRightPrincipalPoint) {
  const SyntheticOdometryConfig config{.frames = 30};
  const OdometrySequence sequence = generate_odometry_sequence(config);
  StereoOdometryNode node(config);
  constexpr int kOffsetPx = 8;
  node.right_camera.k[2] -= kOffsetPx;
  node.right_camera.p[2] -= kOffsetPx;
  std::vector<Eigen::Isometry3d> estimate, truth;
  for (const OdometryFrame& frame : sequence.frames) {
    node.send(frame.left, moved_left(frame.right, kOffsetPx), frame.stamp_s);
    ASSERT_EQ(node.received.size(), estimate.size() + 1) << "at " << frame.stamp_s << " s";
    estimate.push_back(msgs::isometry_of(node.received.back().pose.pose));
    truth.push_back(frame.left_in_first);
  }
  EXPECT_EQ(node.counters().at("tracking_lost"), 0u);
  const RelativePoseError drift = relative_pose_error(estimate, truth, {1.0});
  ASSERT_GT(drift.segments, 0u);
  EXPECT_LE(drift.translation_percent, 2.0);
  EXPECT_LE(drift.rotation_deg_per_m, 0.5);
}

// Rows are matched as the same rows, seen with the same focal length: a pair whose P differ in
// fx is no rectified pair, refused with the reason (and counted), never triangulated.
TEST(StereoOdometryNodeCalibration, RefusesAPairThatIsNotRectified) {
  const SyntheticOdometryConfig config{.frames = 1};
  const OdometrySequence sequence = generate_odometry_sequence(config);
  StereoOdometryNode node(config);
  node.right_camera.p[0] *= 1.01;
  testing::internal::CaptureStderr();
  node.send(sequence.frames[0].left, sequence.frames[0].right, 0.0);
  const std::string said = testing::internal::GetCapturedStderr();
  EXPECT_TRUE(node.received.empty());
  EXPECT_EQ(node.counters().at("rejected_sets"), 1u);
  EXPECT_NE(said.find("differ in fx, fy or cy"), std::string::npos) << said;
}

// nav_msgs/Odometry's twist is in child_frame_id, the camera at the message's stamp: a step of
// 0.3 m forward while turning 8 degrees about the camera's y axis moves the camera along
// R^T t in its own new frame, sideways as well as forward.
TEST(StereoOdometryNodeTwist, IsInTheCameraFrameAtTheStamp) {
  const SyntheticOdometryConfig config;
  const double turn_rad = 8.0 * std::numbers::pi / 180.0;
  Eigen::Isometry3d step = Eigen::Isometry3d::Identity();
  step.linear() = Eigen::AngleAxisd(turn_rad, Eigen::Vector3d::UnitY()).toRotationMatrix();
  step.translation() = Eigen::Vector3d(0.0, 0.0, 0.3);
  const Eigen::Isometry3d start = odometry_trajectory_pose(3.0);
  const StereoPair first = render_odometry_stereo_pair(start, config);
  const StereoPair second = render_odometry_stereo_pair(start * step, config);
  StereoOdometryNode node(config);
  const double dt = 0.05;
  node.send(first.left, first.right, 1.0);
  node.send(second.left, second.right, 1.0 + dt);
  ASSERT_EQ(node.received.size(), 2u);
  const msgs::Twist& twist = node.received[1].twist.twist;
  const Eigen::Vector3d v = step.linear().transpose() * step.translation() / dt;
  // Within the odometry's own error over the step (under 1 cm and 0.2 degrees), per dt.
  EXPECT_NEAR(twist.linear.x, v.x(), 0.2);  // -0.84 m/s; in the previous frame it would be 0
  EXPECT_NEAR(twist.linear.y, v.y(), 0.2);
  EXPECT_NEAR(twist.linear.z, v.z(), 0.2);
  EXPECT_NEAR(twist.angular.x, 0.0, 0.07);
  EXPECT_NEAR(twist.angular.y, turn_rad / dt, 0.07);
  EXPECT_NEAR(twist.angular.z, 0.0, 0.07);
}

// A yaw lattice too fine for the search's tables is refused when the graph is built, naming the
// node, not when the first scan comes.
TEST(MapLocalizationNode, RefusesAnAngularStepTooFineWhenBuilt) {
  try {
    KernelUnderTest node("localization/map_localization", {{"angular_step", "1e-9"}},
                         {{"map", "/map"}, {"scan", "/scan"}, {"pose", "/pose"}});
    ADD_FAILURE() << "the node was built";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("node 'under_test'"), std::string::npos) << what;
    EXPECT_NE(what.find("angular_step_rad"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace robotperf::localization
