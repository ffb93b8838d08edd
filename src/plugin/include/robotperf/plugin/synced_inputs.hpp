// The inputs of a kernel node that computes on one message of each of N topics per frame (a
// stereo pair and its CameraInfo, depth + colour + CameraInfo): subscribed on the topics wired to
// their ports, paired by their header stamps (MessageSync) and counted by port. Written once for
// every category and plug-in, so that each such node pairs and counts the same way.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "robotperf/graph/node.hpp"
#include "robotperf/plugin/kernel.hpp"
#include "robotperf/plugin/message_sync.hpp"

namespace robotperf::plugin {

template <std::size_t N>
class SyncedInputs {
 public:
  using Set = typename MessageSync<N>::Set;

  // `ports` names input i (as KernelInfo::inputs does); `on_set` runs, in the node's callback,
  // with one message of each input.
  SyncedInputs(std::array<std::string, N> ports, SyncOptions options,
               std::function<void(const Set&)> on_set)
      : ports_(std::move(ports)), sync_(options, std::move(on_set)) {}
  // The subscriptions' callbacks hold this object's address.
  SyncedInputs(const SyncedInputs&) = delete;
  SyncedInputs& operator=(const SyncedInputs&) = delete;

  // Subscribes input `index`, of type T (a message with a std_msgs/Header), on the topic wired to
  // its port.
  template <class T>
  void subscribe(graph::Node& node, const KernelConfig& config, std::size_t index) {
    subscriptions_.push_back(node.create_subscription<T>(
        config.topic(ports_.at(index)), config.qos, [this, index](std::shared_ptr<const T> m) {
          const int64_t stamp = m->header.stamp.to_ns();
          sync_.add(index, std::move(m), stamp);
        }));
  }

  // The message of input `index` in a set.
  template <class T>
  static const T& message(const Set& set, std::size_t index) {
    return *std::static_pointer_cast<const T>(set[index]);
  }

  // For NodeCounters: the sets formed ("sets_processed") and, per port, the messages dropped
  // without a set ("unpaired_<port>").
  std::map<std::string, uint64_t> counters() const {
    std::map<std::string, uint64_t> out{{"sets_processed", sync_.emitted()}};
    for (std::size_t i = 0; i < N; ++i) out["unpaired_" + ports_[i]] = sync_.dropped()[i];
    return out;
  }

 private:
  std::array<std::string, N> ports_;
  MessageSync<N> sync_;
  std::vector<std::shared_ptr<graph::GenericSubscription>> subscriptions_;
};

}  // namespace robotperf::plugin
