// tf2 for kernels and plug-ins: a time-indexed tree of coordinate frames with tf2's semantics, and
// the /tf and /tf_static endpoints that fill it and publish into it as tf2_ros does.
//
// A TransformBuffer holds, for each frame, its transform to its parent over the last cache_time
// (10 s, tf2's default), or one static transform valid at every time. lookup_transform(target,
// source, time) walks both frames up to their common ancestor at `time`, interpolating each
// frame's transform between the two samples around it (linear for translation, SLERP for
// rotation); time 0 asks for the latest time every frame of the path has data for. A time beyond a
// frame's samples is an extrapolation error with tf2's text ("Lookup would require extrapolation
// into the future/past ..."). Every set and lookup emits robotperf:tf2_begin and tf2_end, which a
// grey-box run reports as tf2 set and lookup durations (docs/benchmarks/meta.md).
#pragma once

#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <shared_mutex>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

#include "robotperf/graph/node.hpp"
#include "robotperf/msgs/tf2_msgs.hpp"

namespace robotperf::plugin {

// A rotation (unit quaternion x, y, z, w) followed by a translation: a frame's pose in its parent.
struct RigidTransform {
  std::array<double, 3> translation{0, 0, 0};
  std::array<double, 4> rotation{0, 0, 0, 1};

  // The message's quaternion normalised.
  static RigidTransform of(const msgs::Transform& t);
  msgs::Transform to_msg() const;
  // `this` after `child`: a point in child's frame taken into this one's parent.
  RigidTransform operator*(const RigidTransform& child) const;
  RigidTransform inverse() const;
  std::array<double, 3> apply(const std::array<double, 3>& point) const;
};

// Between `a` (fraction 0) and `b` (fraction 1): the translation linearly, the rotation along the
// shorter great arc at constant angular speed (SLERP).
RigidTransform interpolate(const RigidTransform& a, const RigidTransform& b, double fraction);

// tf2's exceptions as one type: what kind of failure, and tf2's text.
class TransformError : public std::runtime_error {
 public:
  enum class Kind {
    kLookup,          // a frame that the buffer does not know
    kConnectivity,    // frames in trees of their own
    kExtrapolation,   // a time outside a frame's samples
    kInvalidArgument  // a transform set_transform refuses
  };
  TransformError(Kind kind, const std::string& what) : std::runtime_error(what), kind_(kind) {}
  Kind kind() const { return kind_; }

 private:
  Kind kind_;
};

class TransformBuffer {
 public:
  static constexpr std::chrono::nanoseconds kDefaultCacheTime = std::chrono::seconds(10);
  // lookup_transform's time that means the latest time the whole path has data for.
  static constexpr int64_t kLatest = 0;

  // `owner` names the buffer in its tracepoints (the node that holds it).
  explicit TransformBuffer(std::string owner,
                           std::chrono::nanoseconds cache_time = kDefaultCacheTime);
  TransformBuffer(const TransformBuffer&) = delete;
  TransformBuffer& operator=(const TransformBuffer&) = delete;

  // Stores `t` (child_frame_id's pose in frame_id at its stamp). A frame is static or dynamic by
  // its first transform; a static one holds its latest transform for every time. Returns false for
  // data tf2 ignores: older than the newest sample minus the cache time, or a second sample at a
  // stamp the frame has. Throws TransformError (kInvalidArgument) for an empty frame id, a frame
  // its own parent, a value that is not finite, or a quaternion whose norm is off 1 by 0.01 or
  // more. `authority` (the sender) is said in those errors.
  bool set_transform(const msgs::TransformStamped& t, const std::string& authority, bool is_static);

  // The transform taking data in `source` into `target` at `time_ns` (kLatest: the latest common
  // time): header.frame_id = target, child_frame_id = source, stamp the time it holds for.
  // Throws TransformError.
  msgs::TransformStamped lookup_transform(const std::string& target, const std::string& source,
                                          int64_t time_ns) const;
  // Whether lookup_transform would succeed; if not and `why` is given, its error text. Emits no
  // tracepoint: it is the question a listener asks before its lookup.
  bool can_transform(const std::string& target, const std::string& source, int64_t time_ns,
                     std::string* why = nullptr) const;

  // The frames known (with a transform, or named as a parent), sorted.
  std::vector<std::string> frames() const;
  std::chrono::nanoseconds cache_time() const { return std::chrono::nanoseconds(cache_ns_); }
  const std::string& owner() const { return owner_; }

 private:
  struct Sample {
    int64_t stamp;
    uint32_t parent;
    RigidTransform transform;
  };
  struct Frame {
    std::string name;
    bool is_static = false;
    std::deque<Sample> samples;  // by stamp; empty for a frame known only as a parent
  };
  // One edge of a path: a frame's transform to its parent, the samples around the time.
  struct Edge {
    uint32_t frame, parent;
    const Sample* before;
    const Sample* after;  // null: `before` alone
    double fraction;
  };
  struct Path {
    std::vector<Edge> up_from_source, up_from_target;  // each up to the common ancestor
    int64_t time = 0;
  };

  uint32_t id_or_insert(const std::string& name);
  uint32_t id_of(const std::string& name, const char* argument) const;
  // The edge from `frame` to its parent at `time` (kLatest: its newest sample); false for a root,
  // or with `error` set when `time` is outside its samples.
  bool edge_at(uint32_t frame, int64_t time, Edge& edge, std::string& error) const;
  // The path between the frames at `time` (kLatest: the latest common time), or throws.
  Path path(uint32_t target, uint32_t source, int64_t time) const;
  Path path_at(uint32_t target, uint32_t source, int64_t time) const;
  msgs::TransformStamped lookup_locked(const std::string& target, const std::string& source,
                                       int64_t time_ns) const;

  std::string owner_;
  int64_t cache_ns_;
  mutable std::shared_mutex mutex_;
  std::vector<Frame> frames_;  // by id; id 0 is no frame
  std::unordered_map<std::string, uint32_t> ids_;
  mutable std::atomic<uint64_t> calls_{0};  // pairs each tf2_begin with its tf2_end
};

// tf2_ros's QoS: /tf KEEP_LAST 100, RELIABLE, VOLATILE for broadcasters and listeners; /tf_static
// RELIABLE, TRANSIENT_LOCAL with KEEP_LAST 1 for its broadcaster (which republishes every static
// transform it has in one message) and 100 for listeners.
rmw::QoS tf_qos();
rmw::QoS tf_static_broadcaster_qos();
rmw::QoS tf_static_listener_qos();

// Subscribes `node` to /tf and /tf_static and sets what arrives into `buffer` (the sender's node
// name is not on the wire: the authority is the topic). A transform the buffer refuses is skipped
// and counted. `after`, when given, runs after each message's transforms are set, on the node's
// callback.
class TransformListener {
 public:
  TransformListener(graph::Node& node, TransformBuffer& buffer,
                    std::function<void(const msgs::TFMessage&)> after = {},
                    const std::string& tf_topic = "/tf",
                    const std::string& tf_static_topic = "/tf_static");
  uint64_t refused() const { return refused_.load(std::memory_order_relaxed); }

 private:
  void take(const msgs::TFMessage& message, const std::string& authority, bool is_static);

  graph::Node& node_;
  TransformBuffer& buffer_;
  std::function<void(const msgs::TFMessage&)> after_;
  std::shared_ptr<graph::GenericSubscription> tf_, tf_static_;
  std::atomic<uint64_t> refused_{0};
};

// Publishes transforms on /tf.
class TransformBroadcaster {
 public:
  explicit TransformBroadcaster(graph::Node& node, const std::string& topic = "/tf");
  void send(std::vector<msgs::TransformStamped> transforms);

 private:
  std::shared_ptr<graph::Publisher<msgs::TFMessage>> publisher_;
};

// Publishes static transforms on /tf_static: each send republishes every child frame's latest
// transform, so that a late listener's one transient-local message holds them all.
class StaticTransformBroadcaster {
 public:
  explicit StaticTransformBroadcaster(graph::Node& node, const std::string& topic = "/tf_static");
  void send(const std::vector<msgs::TransformStamped>& transforms);

 private:
  std::shared_ptr<graph::Publisher<msgs::TFMessage>> publisher_;
  msgs::TFMessage latched_;
};

}  // namespace robotperf::plugin
