// An out-of-tree robotperf plug-in: Canny edge detection on a camera stream (OpenCV), with a
// `cpu` backend (cv::Mat) and an `opencl` backend (OpenCV's transparent API on cv::UMat), and a
// functional evaluator that checks the edges against a CPU reference computed from the dataset's
// own image. Build it against an installed robotperf (see CMakeLists.txt and README.md).
#include <cmath>
#include <iostream>
#include <opencv2/core/ocl.hpp>
#include <opencv2/imgproc.hpp>
#include <robotperf/msgs/sensor_msgs.hpp>
#include <robotperf/plugin.hpp>
#include <stdexcept>

namespace {

using namespace robotperf;

constexpr const char* kKernel = "example/canny";

struct CannyParams {
  double low_threshold = 50;
  double high_threshold = 150;
  int aperture = 3;
  bool l2_gradient = false;
};

// The same parameters, declared once for the kernel and its evaluator: each one's type follows
// from its member's, and the whole struct is read back (no parameter is read by name).
const CannyParams kDefaults;
const plugin::ParameterStruct<CannyParams> kCannyParameters{
    plugin::field(&CannyParams::low_threshold, "low_threshold", kDefaults.low_threshold,
                  "hysteresis: weaker edges"),
    plugin::field(&CannyParams::high_threshold, "high_threshold", kDefaults.high_threshold,
                  "hysteresis: strong edges"),
    plugin::field(&CannyParams::aperture, "aperture", kDefaults.aperture,
                  "Sobel aperture: 3, 5 or 7"),
    plugin::field(&CannyParams::l2_gradient, "l2_gradient", kDefaults.l2_gradient,
                  "L2 gradient norm instead of L1")};

CannyParams canny_params(const plugin::Parameters& p, const std::string& who) {
  const CannyParams c = kCannyParameters.read(p);
  if (c.aperture != 3 && c.aperture != 5 && c.aperture != 7)
    throw std::invalid_argument(who + ": aperture must be 3, 5 or 7");
  if (!(c.low_threshold >= 0 && c.low_threshold <= c.high_threshold))
    throw std::invalid_argument(who + ": need 0 <= low_threshold <= high_threshold");
  return c;
}

// The image as grey levels (a view of the message, converted when it has colour).
cv::Mat grey_of(const msgs::Image& image) {
  int type = 0, code = -1;
  if (image.encoding == "mono8") {
    type = CV_8UC1;
  } else if (image.encoding == "rgb8" || image.encoding == "bgr8") {
    type = CV_8UC3;
    code = image.encoding == "rgb8" ? cv::COLOR_RGB2GRAY : cv::COLOR_BGR2GRAY;
  } else {
    throw std::invalid_argument("encoding " + image.encoding + " (expected mono8, rgb8 or bgr8)");
  }
  if (uint64_t{image.step} * image.height > image.data.size() ||
      image.step < image.width * static_cast<uint32_t>(CV_ELEM_SIZE(type))) {
    throw std::invalid_argument("image data shorter than step x height");
  }
  const cv::Mat view(static_cast<int>(image.height), static_cast<int>(image.width), type,
                     const_cast<uint8_t*>(image.data.data()), image.step);
  if (code < 0) return view;
  cv::Mat grey;
  cv::cvtColor(view, grey, code);
  return grey;
}

class CannyNode final : public graph::Node, public plugin::NodeCounters {
 public:
  CannyNode(graph::Context& context, const plugin::KernelConfig& config)
      : Node(context, config.node_name),
        params_(canny_params(config.parameters, "node '" + config.node_name + "'")),
        opencl_(config.backend == "opencl") {
    if (opencl_) {
      // The transparent API falls back to the CPU without a device it uses (by default OpenCV
      // uses GPUs only): say so instead of measuring the CPU under the name of the accelerator.
      cv::ocl::setUseOpenCL(true);
      if (!cv::ocl::useOpenCL()) {
        throw std::invalid_argument(
            "node '" + name() +
            "': backend opencl needs an OpenCL device, and OpenCV uses none (install the "
            "device's OpenCL ICD, or set OPENCV_OPENCL_DEVICE=:CPU: for a CPU one such as "
            "pocl-opencl-icd's, or use backend cpu)");
      }
    }
    edges_ = create_publisher<msgs::Image>(config.topic("edges"), config.qos);
    image_ = create_subscription<msgs::Image>(
        config.topic("image"), config.qos,
        [this](std::shared_ptr<const msgs::Image> image) { detect(*image); });
  }

  std::map<std::string, uint64_t> counters() const override {
    return {{"images_processed", processed_}, {"images_rejected", rejected_}};
  }

 private:
  void detect(const msgs::Image& image) {
    auto out = std::make_shared<msgs::Image>();
    try {
      plugin::trace_kernel_init(*this, kKernel, image.header.stamp.to_ns(), image);
      const cv::Mat grey = grey_of(image);
      out->header = image.header;
      out->height = image.height;
      out->width = image.width;
      out->encoding = "mono8";
      out->step = image.width;
      out->data.resize(std::size_t{out->step} * out->height);
      cv::Mat edges(grey.rows, grey.cols, CV_8UC1, out->data.data(), out->step);
      if (opencl_) {
        // Host memory in and out, as the graph's messages are (docs/design.md §6).
        cv::UMat device_edges;
        cv::Canny(grey.getUMat(cv::ACCESS_READ), device_edges, params_.low_threshold,
                  params_.high_threshold, params_.aperture, params_.l2_gradient);
        device_edges.copyTo(edges);
      } else {
        cv::Canny(grey, edges, params_.low_threshold, params_.high_threshold, params_.aperture,
                  params_.l2_gradient);
      }
      plugin::trace_kernel_fini(*this, kKernel, *out);
    } catch (const std::invalid_argument& e) {
      // As a ROS node logs and skips an image it cannot use; the frame shows as lost.
      if (rejected_++ == 0)
        std::cerr << "node " << name() << ": skipping image: " << e.what() << "\n";
      return;
    }
    ++processed_;
    edges_->publish(std::shared_ptr<const msgs::Image>(std::move(out)));
  }

  CannyParams params_;
  bool opencl_;
  uint64_t processed_ = 0, rejected_ = 0;
  std::shared_ptr<graph::Publisher<msgs::Image>> edges_;
  std::shared_ptr<graph::GenericSubscription> image_;
};

// The output edges against cv::Canny on the CPU over the dataset's image of the same frame,
// with the same parameters: exact for the cpu backend, and the check that another backend computes
// the same answer. An edge within one pixel of a reference edge counts as found.
class CannyEdgesEvaluator final : public plugin::FunctionalEvaluator {
 public:
  CannyEdgesEvaluator(const plugin::DatasetStream& images, CannyParams params)
      : images_(images), params_(params) {
    plugin::require_type<msgs::Image>(images, "example/canny_edges");
  }

  void add(const void* output, std::size_t frame) override {
    const auto& out = *static_cast<const msgs::Image*>(output);
    const auto& image = *static_cast<const msgs::Image*>(images_.messages[frame].get());
    if (out.encoding != "mono8" || out.width != image.width || out.height != image.height ||
        out.step < out.width || uint64_t{out.step} * out.height > out.data.size()) {
      problem("edges are " + std::to_string(out.width) + "x" + std::to_string(out.height) + " " +
              out.encoding + ", expected " + std::to_string(image.width) + "x" +
              std::to_string(image.height) + " mono8");
      return;
    }
    cv::Mat reference;
    cv::Canny(grey_of(image), reference, params_.low_threshold, params_.high_threshold,
              params_.aperture, params_.l2_gradient);
    const cv::Mat edges(static_cast<int>(out.height), static_cast<int>(out.width), CV_8UC1,
                        const_cast<uint8_t*>(out.data.data()), out.step);
    cv::Mat near_reference, near_edges;
    cv::dilate(reference, near_reference, cv::Mat());
    cv::dilate(edges, near_edges, cv::Mat());
    pixels_ += edges.total();
    equal_ += edges.total() - static_cast<uint64_t>(cv::countNonZero(edges != reference));
    output_edges_ += static_cast<uint64_t>(cv::countNonZero(edges));
    reference_edges_ += static_cast<uint64_t>(cv::countNonZero(reference));
    found_ += static_cast<uint64_t>(cv::countNonZero(edges & near_reference));
    recalled_ += static_cast<uint64_t>(cv::countNonZero(reference & near_edges));
  }

  std::map<std::string, double> metrics() const override {
    const double nan = std::nan("");
    auto ratio = [&](uint64_t a, uint64_t b) { return b ? static_cast<double>(a) / b : nan; };
    return {{"pixel_agreement", ratio(equal_, pixels_)},
            {"precision", ratio(found_, output_edges_)},
            {"recall", ratio(recalled_, reference_edges_)},
            {"edge_density", ratio(output_edges_, pixels_)}};
  }

 private:
  const plugin::DatasetStream& images_;
  CannyParams params_;
  uint64_t pixels_ = 0, equal_ = 0, output_edges_ = 0, reference_edges_ = 0, found_ = 0,
           recalled_ = 0;
};

}  // namespace

ROBOTPERF_PLUGIN(registrar) {
  registrar.add_kernel(
      {.name = kKernel,
       .description = "Canny edges of a camera image (OpenCV cv::Canny), mono8 out",
       .backends = {"cpu", "opencl"},
       .inputs = {{"image", "sensor_msgs/msg/Image"}},
       .outputs = {{"edges", "sensor_msgs/msg/Image"}},
       .parameters = kCannyParameters.declarations()},
      [](graph::Context& context, const plugin::KernelConfig& config) {
        return std::make_shared<CannyNode>(context, config);
      });
  registrar.add_evaluator(
      {.name = "example/canny_edges",
       .description = "edges against cv::Canny on the CPU over the dataset's image, same "
                      "parameters; an edge within 1 px of a reference edge is found",
       .output_type = "sensor_msgs/msg/Image",
       .truth_roles = {"image"},
       .metrics = {{"pixel_agreement", "fraction", "pixels equal to the reference"},
                   {"precision", "fraction", "edge pixels within 1 px of a reference edge"},
                   {"recall", "fraction", "reference edge pixels within 1 px of an edge"},
                   {"edge_density", "fraction", "share of pixels that are edges"}},
       .parameters = kCannyParameters.declarations()},
      [](const plugin::TruthStreams& truth, const plugin::Parameters& parameters) {
        return std::make_unique<CannyEdgesEvaluator>(
            truth["image"], canny_params(parameters, "evaluator example/canny_edges"));
      });
}
