// Private to the perception category: a node that skips the inputs its kernel cannot use.
#pragma once

#include <opencv2/core.hpp>
#include <stdexcept>

#include "robotperf/graph/node.hpp"
#include "robotperf/plugin/kernel.hpp"

namespace robotperf::perception {

// Inputs rejected by the kernel (a bad image, mismatched frames, an image OpenCV refuses) are
// skipped and counted (plugin::SkippedInputs).
class SkippingNode : public graph::Node, public plugin::NodeCounters {
 protected:
  using graph::Node::Node;
  template <class F>
  void guarded(F&& f) {
    try {
      f();
    } catch (const std::invalid_argument& e) {
      rejected_.note(name(), e.what());
    } catch (const cv::Exception& e) {
      rejected_.note(name(), e.what());
    }
  }
  plugin::SkippedInputs rejected_;
};

}  // namespace robotperf::perception
