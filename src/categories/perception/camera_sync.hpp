// Private to the perception category: exact-time pairing of an image with its
// CameraInfo, as image_transport's camera subscriber does (a time synchronizer
// with a queue of 10 on each side).
#pragma once

#include <deque>
#include <functional>
#include <memory>

#include "robotperf/msgs/sensor_msgs.hpp"

namespace robotperf::perception {

class CameraSync {
 public:
  using ImagePtr = std::shared_ptr<const msgs::Image>;
  using InfoPtr = std::shared_ptr<const msgs::CameraInfo>;
  using Callback = std::function<void(const ImagePtr&, const InfoPtr&)>;

  explicit CameraSync(Callback callback, std::size_t queue_size = 10)
      : callback_(std::move(callback)), queue_size_(queue_size) {}

  void add(ImagePtr image) { add_to(images_, infos_, std::move(image)); }
  void add(InfoPtr info) { add_to(infos_, images_, std::move(info)); }

 private:
  template <class Mine, class Other>
  void add_to(std::deque<Mine>& mine, std::deque<Other>& other, Mine msg) {
    const msgs::Time stamp = msg->header.stamp;
    for (auto it = other.begin(); it != other.end(); ++it) {
      if ((*it)->header.stamp != stamp) continue;
      Other partner = std::move(*it);
      // Anything older than the pair can no longer be matched in order.
      other.erase(other.begin(), it + 1);
      std::erase_if(mine, [&](const Mine& m) { return m->header.stamp.to_ns() <= stamp.to_ns(); });
      if constexpr (std::is_same_v<Mine, ImagePtr>) {
        callback_(msg, partner);
      } else {
        callback_(partner, msg);
      }
      return;
    }
    mine.push_back(std::move(msg));
    if (mine.size() > queue_size_) mine.pop_front();
  }

  Callback callback_;
  std::size_t queue_size_;
  std::deque<ImagePtr> images_;
  std::deque<InfoPtr> infos_;
};

}  // namespace robotperf::perception
