// stereo_image_proc/disparity and depth_image_proc/point_cloud_xyzrgb as graph nodes.
#include <cmath>
#include <iostream>
#include <stdexcept>

#include "builtin_kernels.hpp"
#include "robotperf/kernels/depth_image_proc.hpp"
#include "robotperf/kernels/message_sync.hpp"
#include "robotperf/kernels/stereo_image_proc.hpp"
#include "robotperf/tracing/tracepoints.hpp"

namespace robotperf::kernels {
namespace {

int int_parameter(const KernelConfig& config, const std::string& name, int fallback) {
  const int64_t v = config.parameters.get_int(name, fallback);
  if (v < INT32_MIN || v > INT32_MAX) {
    throw std::invalid_argument("node '" + config.node_name + "': " + name + " is out of range");
  }
  return static_cast<int>(v);
}

SyncOptions sync_options(const KernelConfig& config, bool approximate, int64_t default_queue) {
  SyncOptions o;
  o.policy = approximate ? SyncPolicy::kApproximate : SyncPolicy::kExact;
  const int64_t queue = config.parameters.get_int("queue_size", default_queue);
  if (queue < 1)
    throw std::invalid_argument("node '" + config.node_name + "': queue_size must be >= 1");
  o.queue_size = static_cast<std::size_t>(queue);
  return o;
}

template <class T>
int64_t stamp_of(const std::shared_ptr<const T>& m) {
  return m->header.stamp.to_ns();
}

// Output messages of megabytes: the last one published is reused once every subscriber has let
// go of it (like a ROS 2 loaned message), so the kernel writes into memory already mapped instead
// of page-faulting a fresh buffer on every frame.
template <class T>
class OutputPool {
 public:
  std::shared_ptr<T> acquire() {
    // use_count 1: only we hold it, and nobody can take a new reference from us.
    if (last_ && last_.use_count() == 1) return last_;
    last_ = std::make_shared<T>();
    return last_;
  }

 private:
  std::shared_ptr<T> last_;
};

// Inputs rejected by the kernel (a bad image, mismatched frames) are skipped and counted, as the
// ROS nodes log and skip them: the frame shows as lost at the Monitor.
class SkippingNode : public graph::Node, public NodeCounters {
 protected:
  using graph::Node::Node;
  template <class F>
  void guarded(F&& f) {
    try {
      f();
    } catch (const std::invalid_argument& e) {
      if (rejected_++ == 0)
        std::cerr << "robotperf node " << name() << ": skipping input: " << e.what() << "\n";
    }
  }
  // robotperf:kernel_init/fini around the kernel's computation of one frame, so that grey-box
  // runs show the kernel's own time beside the node's; the sizes (CDR sizes of the frame's image
  // inputs and of the output) are computed only while traced.
  template <class... Inputs>
  void trace_kernel_init(const char* kernel, int64_t stamp, const Inputs&... inputs) const {
    if (lttng_ust_tracepoint_enabled(robotperf, kernel_init)) {
      const uint64_t size = (msgs::type_support<Inputs>().serialized_size(&inputs) + ...);
      lttng_ust_do_tracepoint(robotperf, kernel_init, name().c_str(), kernel, stamp, size);
    }
  }
  template <class T>
  void trace_kernel_fini(const char* kernel, const T& output) const {
    if (lttng_ust_tracepoint_enabled(robotperf, kernel_fini)) {
      lttng_ust_do_tracepoint(robotperf, kernel_fini, name().c_str(), kernel,
                              output.header.stamp.to_ns(),
                              msgs::type_support<T>().serialized_size(&output));
    }
  }

  uint64_t rejected_ = 0;
};

class DisparityNode final : public SkippingNode {
 public:
  enum Input { kLeftImage, kLeftInfo, kRightImage, kRightInfo };

  DisparityNode(graph::Context& context, const KernelConfig& config)
      : SkippingNode(context, config.node_name),
        processor_(params_from(config)),
        sync_(sync_options(config, config.parameters.get_bool("approximate_sync", false), 5),
              [this](const auto& set) { process(set); }) {
    output_ = create_publisher<msgs::DisparityImage>(config.topic("disparity"), config.qos);
    subscribe<msgs::Image>(config, "left_image", kLeftImage);
    subscribe<msgs::CameraInfo>(config, "left_camera_info", kLeftInfo);
    subscribe<msgs::Image>(config, "right_image", kRightImage);
    subscribe<msgs::CameraInfo>(config, "right_camera_info", kRightInfo);
  }

  std::map<std::string, uint64_t> counters() const override {
    const auto& d = sync_.dropped();
    return {{"sets_processed", sync_.emitted()},           {"unpaired_left_image", d[kLeftImage]},
            {"unpaired_left_camera_info", d[kLeftInfo]},   {"unpaired_right_image", d[kRightImage]},
            {"unpaired_right_camera_info", d[kRightInfo]}, {"rejected_sets", rejected_}};
  }

 private:
  static StereoParams params_from(const KernelConfig& c) {
    StereoParams p;
    const int algorithm = int_parameter(c, "stereo_algorithm", 0);
    if (algorithm != 0 && algorithm != 1) {
      throw std::invalid_argument("node '" + c.node_name +
                                  "': stereo_algorithm must be 0 (StereoBM) or 1 (StereoSGBM)");
    }
    p.algorithm = static_cast<StereoAlgorithm>(algorithm);
    p.prefilter_size = int_parameter(c, "prefilter_size", p.prefilter_size);
    p.prefilter_cap = int_parameter(c, "prefilter_cap", p.prefilter_cap);
    p.correlation_window_size =
        int_parameter(c, "correlation_window_size", p.correlation_window_size);
    p.min_disparity = int_parameter(c, "min_disparity", p.min_disparity);
    p.disparity_range = int_parameter(c, "disparity_range", p.disparity_range);
    p.texture_threshold = int_parameter(c, "texture_threshold", p.texture_threshold);
    p.speckle_size = int_parameter(c, "speckle_size", p.speckle_size);
    p.speckle_range = int_parameter(c, "speckle_range", p.speckle_range);
    p.uniqueness_ratio = int_parameter(c, "uniqueness_ratio", p.uniqueness_ratio);
    p.p1 = int_parameter(c, "P1", p.p1);
    p.p2 = int_parameter(c, "P2", p.p2);
    p.disp12_max_diff = int_parameter(c, "disp12_max_diff", p.disp12_max_diff);
    p.sgbm_mode = int_parameter(c, "sgbm_mode", p.sgbm_mode);
    try {
      validate(p);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("node '" + c.node_name + "': " + e.what());
    }
    return p;
  }

  template <class T>
  void subscribe(const KernelConfig& config, const char* port, Input input) {
    subscriptions_.push_back(create_subscription<T>(config.topic(port), config.qos,
                                                    [this, input](std::shared_ptr<const T> m) {
                                                      const int64_t stamp = stamp_of(m);
                                                      sync_.add(input, std::move(m), stamp);
                                                    }));
  }

  void process(const MessageSync<4>::Set& set) {
    guarded([&] {
      std::shared_ptr<msgs::DisparityImage> out = pool_.acquire();
      const auto& left = *std::static_pointer_cast<const msgs::Image>(set[kLeftImage]);
      const auto& right = *std::static_pointer_cast<const msgs::Image>(set[kRightImage]);
      trace_kernel_init(kKernel, left.header.stamp.to_ns(), left, right);
      processor_.compute(left, right,
                         *std::static_pointer_cast<const msgs::CameraInfo>(set[kLeftInfo]),
                         *std::static_pointer_cast<const msgs::CameraInfo>(set[kRightInfo]), *out);
      trace_kernel_fini(kKernel, *out);
      output_->publish(std::shared_ptr<const msgs::DisparityImage>(std::move(out)));
    });
  }

  static constexpr const char* kKernel = "stereo_image_proc/disparity";
  DisparityProcessor processor_;
  OutputPool<msgs::DisparityImage> pool_;
  MessageSync<4> sync_;
  std::shared_ptr<graph::Publisher<msgs::DisparityImage>> output_;
  std::vector<std::shared_ptr<graph::GenericSubscription>> subscriptions_;
};

class PointCloudXyzrgbNode final : public SkippingNode {
 public:
  enum Input { kDepth, kImage, kInfo };

  PointCloudXyzrgbNode(graph::Context& context, const KernelConfig& config)
      : SkippingNode(context, config.node_name),
        sync_(sync_options(config, !config.parameters.get_bool("exact_sync", false), 5),
              [this](const auto& set) { process(set); }) {
    params_.range_max = config.parameters.get_double("range_max", 0.0);
    if (!(params_.range_max >= 0.0) || !std::isfinite(params_.range_max)) {
      throw std::invalid_argument("node '" + config.node_name + "': range_max must be >= 0");
    }
    output_ = create_publisher<msgs::PointCloud2>(config.topic("points"), config.qos);
    subscribe<msgs::Image>(config, "depth", kDepth);
    subscribe<msgs::Image>(config, "image", kImage);
    subscribe<msgs::CameraInfo>(config, "camera_info", kInfo);
  }

  std::map<std::string, uint64_t> counters() const override {
    const auto& d = sync_.dropped();
    return {{"sets_processed", sync_.emitted()},
            {"unpaired_depth", d[kDepth]},
            {"unpaired_image", d[kImage]},
            {"unpaired_camera_info", d[kInfo]},
            {"rejected_sets", rejected_}};
  }

 private:
  template <class T>
  void subscribe(const KernelConfig& config, const char* port, Input input) {
    subscriptions_.push_back(create_subscription<T>(config.topic(port), config.qos,
                                                    [this, input](std::shared_ptr<const T> m) {
                                                      const int64_t stamp = stamp_of(m);
                                                      sync_.add(input, std::move(m), stamp);
                                                    }));
  }

  void process(const MessageSync<3>::Set& set) {
    guarded([&] {
      std::shared_ptr<msgs::PointCloud2> cloud = pool_.acquire();
      const auto& depth = *std::static_pointer_cast<const msgs::Image>(set[kDepth]);
      const auto& image = *std::static_pointer_cast<const msgs::Image>(set[kImage]);
      trace_kernel_init(kKernel, depth.header.stamp.to_ns(), depth, image);
      point_cloud_xyzrgb(depth, image,
                         *std::static_pointer_cast<const msgs::CameraInfo>(set[kInfo]), params_,
                         *cloud);
      trace_kernel_fini(kKernel, *cloud);
      output_->publish(std::shared_ptr<const msgs::PointCloud2>(std::move(cloud)));
    });
  }

  static constexpr const char* kKernel = "depth_image_proc/point_cloud_xyzrgb";
  PointCloudXyzrgbParams params_;
  OutputPool<msgs::PointCloud2> pool_;
  MessageSync<3> sync_;
  std::shared_ptr<graph::Publisher<msgs::PointCloud2>> output_;
  std::vector<std::shared_ptr<graph::GenericSubscription>> subscriptions_;
};

}  // namespace

std::shared_ptr<graph::Node> make_disparity_node(graph::Context& context,
                                                 const KernelConfig& config) {
  return std::make_shared<DisparityNode>(context, config);
}

std::shared_ptr<graph::Node> make_point_cloud_xyzrgb_node(graph::Context& context,
                                                          const KernelConfig& config) {
  return std::make_shared<PointCloudXyzrgbNode>(context, config);
}

}  // namespace robotperf::kernels
