// Private to the perception category: a node that skips the inputs its kernel cannot use.
#pragma once

#include <cctype>
#include <cstdint>
#include <iostream>
#include <opencv2/core.hpp>
#include <stdexcept>
#include <string>

#include "robotperf/graph/node.hpp"
#include "robotperf/plugin/kernel.hpp"

namespace robotperf::perception {

// Inputs rejected by the kernel (a bad image, mismatched frames, an image OpenCV refuses) are
// skipped and counted, as the ROS nodes log and skip them: the frame shows as lost at the
// Monitor, and the run goes on. The first one is said.
class SkippingNode : public graph::Node, public plugin::NodeCounters {
 protected:
  using graph::Node::Node;
  template <class F>
  void guarded(F&& f) {
    try {
      f();
    } catch (const std::invalid_argument& e) {
      note(e.what());
    } catch (const cv::Exception& e) {
      note(e.what());
    }
  }
  uint64_t rejected_ = 0;

 private:
  void note(std::string what) {
    if (rejected_++ != 0) return;
    while (!what.empty() && std::isspace(static_cast<unsigned char>(what.back()))) what.pop_back();
    std::cerr << "robotperf node " << name() << ": skipping input: " << what << "\n";
  }
};

}  // namespace robotperf::perception
