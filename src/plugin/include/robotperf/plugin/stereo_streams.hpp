// A rectified stereo pair as a dataset's streams, on the topics stereo_image_proc's nodes take
// (/left/image_rect, /left/camera_info, /right/image_rect, /right/camera_info), so that every
// stereo dataset plays into every stereo kernel without remapping.
#pragma once

#include <utility>
#include <vector>

#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/plugin/dataset.hpp"

namespace robotperf::plugin {

// Their descriptions, then the dataset's own streams (its ground truth), for DatasetInfo::streams
// in the order StereoPairStreams::take gives the streams.
inline std::vector<StreamInfo> stereo_pair_stream_infos(std::vector<StreamInfo> more) {
  std::vector<StreamInfo> out{
      {"left_image", "/left/image_rect", "sensor_msgs/msg/Image", false, "rectified left image"},
      {"left_camera_info", "/left/camera_info", "sensor_msgs/msg/CameraInfo", false,
       "left calibration"},
      {"right_image", "/right/image_rect", "sensor_msgs/msg/Image", false, "rectified right image"},
      {"right_camera_info", "/right/camera_info", "sensor_msgs/msg/CameraInfo", false,
       "right calibration (P[3] = -fx * baseline)"}};
  for (StreamInfo& s : more) out.push_back(std::move(s));
  return out;
}

// The four streams, filled one frame at a time.
class StereoPairStreams {
 public:
  void append(msgs::Image left, msgs::CameraInfo left_info, msgs::Image right,
              msgs::CameraInfo right_info) {
    plugin::append(left_, std::move(left));
    plugin::append(left_info_, std::move(left_info));
    plugin::append(right_, std::move(right));
    plugin::append(right_info_, std::move(right_info));
  }

  // The four streams, then the dataset's own (its ground truth).
  std::vector<DatasetStream> take(std::vector<DatasetStream> more) {
    std::vector<DatasetStream> out;
    out.reserve(4 + more.size());
    for (DatasetStream* s : {&left_, &left_info_, &right_, &right_info_})
      out.push_back(std::move(*s));
    for (DatasetStream& s : more) out.push_back(std::move(s));
    return out;
  }

 private:
  DatasetStream left_ = make_stream<msgs::Image>("left_image", "/left/image_rect");
  DatasetStream left_info_ = make_stream<msgs::CameraInfo>("left_camera_info", "/left/camera_info");
  DatasetStream right_ = make_stream<msgs::Image>("right_image", "/right/image_rect");
  DatasetStream right_info_ =
      make_stream<msgs::CameraInfo>("right_camera_info", "/right/camera_info");
};

}  // namespace robotperf::plugin
