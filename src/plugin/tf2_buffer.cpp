#include "robotperf/plugin/tf2_buffer.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <mutex>

#include "robotperf/tracing/tracepoints.hpp"

namespace robotperf::plugin {
namespace {

using Quaternion = std::array<double, 4>;  // x, y, z, w
using Vector = std::array<double, 3>;

Quaternion multiply(const Quaternion& a, const Quaternion& b) {
  return {a[3] * b[0] + a[0] * b[3] + a[1] * b[2] - a[2] * b[1],
          a[3] * b[1] - a[0] * b[2] + a[1] * b[3] + a[2] * b[0],
          a[3] * b[2] + a[0] * b[1] - a[1] * b[0] + a[2] * b[3],
          a[3] * b[3] - a[0] * b[0] - a[1] * b[1] - a[2] * b[2]};
}

Vector cross(const Vector& a, const Vector& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

// v rotated by the unit quaternion q: v + w t + u x t, with u = q's vector part, t = 2 u x v.
Vector rotate(const Quaternion& q, const Vector& v) {
  const Vector u{q[0], q[1], q[2]};
  Vector t = cross(u, v);
  for (double& x : t) x *= 2;
  const Vector ut = cross(u, t);
  return {v[0] + q[3] * t[0] + ut[0], v[1] + q[3] * t[1] + ut[1], v[2] + q[3] * t[2] + ut[2]};
}

Quaternion normalized(Quaternion q) {
  const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  for (double& x : q) x /= n;
  return q;
}

std::string strip_slash(const std::string& frame) {
  return !frame.empty() && frame[0] == '/' ? frame.substr(1) : frame;
}

std::string seconds(int64_t ns) {
  char text[48];
  std::snprintf(text, sizeof text, "%.6f", static_cast<double>(ns) * 1e-9);
  return text;
}

// tf2's bound on a path's length: a longer walk is a loop in the tree.
constexpr std::size_t kMaxDepth = 1000;

// robotperf:tf2_begin and tf2_end around one call, numbered so that the analysis pairs them; the
// number is drawn only while a session records.
class TracedCall {
 public:
  TracedCall(const std::string& owner, const char* operation, std::atomic<uint64_t>& calls) {
    if (lttng_ust_tracepoint_enabled(robotperf, tf2_begin)) {
      owner_ = owner.c_str();
      operation_ = operation;
      call_ = calls.fetch_add(1, std::memory_order_relaxed);
      lttng_ust_do_tracepoint(robotperf, tf2_begin, owner_, operation_, call_);
    }
  }
  TracedCall(const TracedCall&) = delete;
  TracedCall& operator=(const TracedCall&) = delete;
  ~TracedCall() {
    if (owner_ != nullptr) lttng_ust_tracepoint(robotperf, tf2_end, owner_, operation_, call_);
  }

 private:
  const char* owner_ = nullptr;
  const char* operation_ = nullptr;
  uint64_t call_ = 0;
};

}  // namespace

RigidTransform RigidTransform::of(const msgs::Transform& t) {
  return {{t.translation.x, t.translation.y, t.translation.z},
          normalized({t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w})};
}

msgs::Transform RigidTransform::to_msg() const {
  msgs::Transform t;
  t.translation = {translation[0], translation[1], translation[2]};
  t.rotation = {rotation[0], rotation[1], rotation[2], rotation[3]};
  return t;
}

RigidTransform RigidTransform::operator*(const RigidTransform& child) const {
  const Vector moved = rotate(rotation, child.translation);
  return {{translation[0] + moved[0], translation[1] + moved[1], translation[2] + moved[2]},
          multiply(rotation, child.rotation)};
}

RigidTransform RigidTransform::inverse() const {
  const Quaternion conjugate{-rotation[0], -rotation[1], -rotation[2], rotation[3]};
  const Vector back = rotate(conjugate, translation);
  return {{-back[0], -back[1], -back[2]}, conjugate};
}

std::array<double, 3> RigidTransform::apply(const std::array<double, 3>& point) const {
  const Vector r = rotate(rotation, point);
  return {r[0] + translation[0], r[1] + translation[1], r[2] + translation[2]};
}

RigidTransform interpolate(const RigidTransform& a, const RigidTransform& b, double fraction) {
  RigidTransform out;
  for (int i = 0; i < 3; ++i)
    out.translation[i] = a.translation[i] + fraction * (b.translation[i] - a.translation[i]);
  Quaternion q1 = b.rotation;
  double cos_angle =
      a.rotation[0] * q1[0] + a.rotation[1] * q1[1] + a.rotation[2] * q1[2] + a.rotation[3] * q1[3];
  if (cos_angle < 0) {  // q and -q are one rotation: take the shorter arc
    for (double& x : q1) x = -x;
    cos_angle = -cos_angle;
  }
  double wa = 1 - fraction, wb = fraction;
  // Nearly equal rotations: sin(angle) vanishes, and the straight line is the arc.
  if (cos_angle < 0.9995) {
    const double angle = std::acos(cos_angle);
    const double s = std::sin(angle);
    wa = std::sin((1 - fraction) * angle) / s;
    wb = std::sin(fraction * angle) / s;
  }
  for (int i = 0; i < 4; ++i) out.rotation[i] = wa * a.rotation[i] + wb * q1[i];
  out.rotation = normalized(out.rotation);
  return out;
}

TransformBuffer::TransformBuffer(std::string owner, std::chrono::nanoseconds cache_time)
    : owner_(std::move(owner)), cache_ns_(cache_time.count()), frames_(1) {
  if (cache_ns_ <= 0)
    throw std::invalid_argument("tf2 buffer '" + owner_ + "': the cache time must be > 0");
}

uint32_t TransformBuffer::id_or_insert(const std::string& name) {
  auto [it, inserted] = ids_.try_emplace(name, static_cast<uint32_t>(frames_.size()));
  if (inserted) frames_.push_back(Frame{name, false, {}});
  return it->second;
}

uint32_t TransformBuffer::id_of(const std::string& name, const char* argument) const {
  if (name.empty()) {
    throw TransformError(TransformError::Kind::kInvalidArgument,
                         std::string("Invalid argument passed to lookupTransform argument ") +
                             argument + " in tf2 frame_ids cannot be empty");
  }
  const auto it = name[0] == '/' ? ids_.find(name.substr(1)) : ids_.find(name);
  if (it == ids_.end()) {
    throw TransformError(
        TransformError::Kind::kLookup,
        "\"" + name + "\" passed to lookupTransform argument " + argument + " does not exist. ");
  }
  return it->second;
}

bool TransformBuffer::set_transform(const msgs::TransformStamped& t, const std::string& authority,
                                    bool is_static) {
  const TracedCall traced(owner_, "set", calls_);
  const std::string parent = strip_slash(t.header.frame_id);
  const std::string child = strip_slash(t.child_frame_id);
  auto refuse = [](const std::string& what) {
    throw TransformError(TransformError::Kind::kInvalidArgument, what);
  };
  if (child.empty())
    refuse("TF_NO_CHILD_FRAME_ID: Ignoring transform from authority \"" + authority +
           "\" because child_frame_id not set");
  if (parent.empty())
    refuse("TF_NO_FRAME_ID: Ignoring transform with child_frame_id \"" + child +
           "\" from authority \"" + authority + "\" because frame_id not set");
  if (parent == child)
    refuse("TF_SELF_TRANSFORM: Ignoring transform from authority \"" + authority +
           "\" with frame_id and child_frame_id \"" + child + "\" because they are the same");
  const auto& tr = t.transform.translation;
  const auto& q = t.transform.rotation;
  for (double v : {tr.x, tr.y, tr.z, q.x, q.y, q.z, q.w}) {
    if (!std::isfinite(v))
      refuse("TF_NAN_INPUT: Ignoring transform for child_frame_id \"" + child +
             "\" from authority \"" + authority + "\" because of a nan value in the transform");
  }
  const double norm = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
  if (!(std::abs(norm - 1) < 1e-2))
    refuse("TF_DENORMALIZED_QUATERNION: Ignoring transform for child_frame_id \"" + child +
           "\" from authority \"" + authority + "\" because of an invalid quaternion (norm " +
           std::to_string(norm) + ")");

  const int64_t stamp = t.header.stamp.to_ns();
  const std::unique_lock lock(mutex_);
  const uint32_t parent_id = id_or_insert(parent);
  Frame& frame = frames_[id_or_insert(child)];
  const Sample sample{stamp, parent_id, RigidTransform::of(t.transform)};
  if (frame.samples.empty()) frame.is_static = is_static;
  if (frame.is_static) {
    frame.samples.assign(1, sample);
    return true;
  }
  auto& samples = frame.samples;
  if (!samples.empty() && stamp < samples.back().stamp - cache_ns_) return false;  // TF_OLD_DATA
  const auto at = std::lower_bound(samples.begin(), samples.end(), stamp,
                                   [](const Sample& s, int64_t time) { return s.stamp < time; });
  if (at != samples.end() && at->stamp == stamp) return false;  // TF_REPEATED_DATA
  samples.insert(at, sample);
  while (samples.front().stamp < samples.back().stamp - cache_ns_) samples.pop_front();
  return true;
}

bool TransformBuffer::edge_at(uint32_t frame_id, int64_t time, Edge& edge,
                              std::string& error) const {
  const Frame& frame = frames_[frame_id];
  const auto& samples = frame.samples;
  if (samples.empty()) return false;
  edge = {frame_id, samples.back().parent, &samples.back(), nullptr, 0};
  if (frame.is_static || time == kLatest) return true;
  const Sample& newest = samples.back();
  const Sample& oldest = samples.front();
  if (samples.size() == 1) {
    if (time == newest.stamp) return true;
    if (error.empty())
      error = "Lookup would require extrapolation at time " + seconds(time) + ", but only time " +
              seconds(newest.stamp) + " is in the buffer";
    return false;
  }
  if (time > newest.stamp) {
    if (error.empty())
      error = "Lookup would require extrapolation into the future.  Requested time " +
              seconds(time) + " but the latest data is at time " + seconds(newest.stamp);
    return false;
  }
  if (time < oldest.stamp) {
    if (error.empty())
      error = "Lookup would require extrapolation into the past.  Requested time " + seconds(time) +
              " but the earliest data is at time " + seconds(oldest.stamp);
    return false;
  }
  // The first sample at or after `time`, by index (a deque's iterators are slower to move).
  std::size_t low = 0, high = samples.size() - 1;
  while (low < high) {
    const std::size_t mid = (low + high) / 2;
    if (samples[mid].stamp < time) {
      low = mid + 1;
    } else {
      high = mid;
    }
  }
  const Sample* at = &samples[low];
  edge.before = at;
  edge.parent = at->parent;
  if (at->stamp == time) return true;
  const Sample& before = samples[low - 1];
  edge.before = &before;
  edge.parent = before.parent;
  // A frame whose parent changed between the samples: the older one holds until the newer.
  if (before.parent == at->parent) {
    edge.after = at;
    edge.fraction =
        static_cast<double>(time - before.stamp) / static_cast<double>(at->stamp - before.stamp);
  }
  return true;
}

TransformBuffer::Path TransformBuffer::path_at(uint32_t target, uint32_t source,
                                               int64_t time) const {
  Path p;
  std::string error;
  std::vector<uint32_t> from_source{source};
  // Most trees are shallow: one allocation each for the paths of nearly every lookup.
  constexpr std::size_t kTypicalDepth = 16;
  from_source.reserve(kTypicalDepth);
  p.up_from_source.reserve(kTypicalDepth);
  p.up_from_target.reserve(kTypicalDepth);
  Edge edge;
  for (uint32_t f = source; f != target && edge_at(f, time, edge, error);) {
    p.up_from_source.push_back(edge);
    f = edge.parent;
    from_source.push_back(f);
    if (from_source.size() > kMaxDepth)
      throw TransformError(TransformError::Kind::kConnectivity,
                           "The tf tree is invalid because it contains a loop.");
  }
  auto common = std::find(from_source.begin(), from_source.end(), target);
  for (uint32_t f = target; common == from_source.end() && edge_at(f, time, edge, error);) {
    p.up_from_target.push_back(edge);
    f = edge.parent;
    common = std::find(from_source.begin(), from_source.end(), f);
    if (p.up_from_target.size() > kMaxDepth)
      throw TransformError(TransformError::Kind::kConnectivity,
                           "The tf tree is invalid because it contains a loop.");
  }
  const std::string& target_name = frames_[target].name;
  const std::string& source_name = frames_[source].name;
  if (common == from_source.end()) {
    if (!error.empty()) {
      throw TransformError(TransformError::Kind::kExtrapolation,
                           error + ", when looking up transform from frame [" + source_name +
                               "] to frame [" + target_name + "]");
    }
    throw TransformError(TransformError::Kind::kConnectivity,
                         "Could not find a connection between '" + target_name + "' and '" +
                             source_name +
                             "' because they are not part of the same tree.Tf has two or more "
                             "unconnected trees.");
  }
  p.up_from_source.resize(static_cast<std::size_t>(common - from_source.begin()));
  p.time = time;
  if (time == kLatest) {
    // The latest time every dynamic frame of the path has data for; 0 when all are static.
    int64_t latest = INT64_MAX;
    for (const auto* edges : {&p.up_from_source, &p.up_from_target}) {
      for (const Edge& e : *edges) {
        if (!frames_[e.frame].is_static) latest = std::min(latest, e.before->stamp);
      }
    }
    p.time = latest == INT64_MAX ? kLatest : latest;
  }
  return p;
}

TransformBuffer::Path TransformBuffer::path(uint32_t target, uint32_t source, int64_t time) const {
  Path p = path_at(target, source, time);
  // The latest common time found: the frames' transforms at that time.
  if (time == kLatest && p.time != kLatest) p = path_at(target, source, p.time);
  return p;
}

msgs::TransformStamped TransformBuffer::lookup_locked(const std::string& target,
                                                      const std::string& source,
                                                      int64_t time_ns) const {
  const uint32_t target_id = id_of(target, "target_frame");
  const uint32_t source_id = id_of(source, "source_frame");
  const Path p = path(target_id, source_id, time_ns);
  auto up = [](const std::vector<Edge>& edges) {
    RigidTransform to_top;
    for (const Edge& e : edges) {
      to_top = (e.after ? interpolate(e.before->transform, e.after->transform, e.fraction)
                        : e.before->transform) *
               to_top;
    }
    return to_top;
  };
  msgs::TransformStamped out;
  out.header.stamp = msgs::Time::from_ns(p.time);
  out.header.frame_id = frames_[target_id].name;
  out.child_frame_id = frames_[source_id].name;
  out.transform = (up(p.up_from_target).inverse() * up(p.up_from_source)).to_msg();
  return out;
}

msgs::TransformStamped TransformBuffer::lookup_transform(const std::string& target,
                                                         const std::string& source,
                                                         int64_t time_ns) const {
  const TracedCall traced(owner_, "lookup", calls_);
  const std::shared_lock lock(mutex_);
  return lookup_locked(target, source, time_ns);
}

bool TransformBuffer::can_transform(const std::string& target, const std::string& source,
                                    int64_t time_ns, std::string* why) const {
  const std::shared_lock lock(mutex_);
  try {
    path(id_of(target, "target_frame"), id_of(source, "source_frame"), time_ns);
    return true;
  } catch (const TransformError& e) {
    if (why) *why = e.what();
    return false;
  }
}

std::vector<std::string> TransformBuffer::frames() const {
  const std::shared_lock lock(mutex_);
  std::vector<std::string> names;
  for (std::size_t i = 1; i < frames_.size(); ++i) names.push_back(frames_[i].name);
  std::sort(names.begin(), names.end());
  return names;
}

rmw::QoS tf_qos() {
  return {rmw::History::kKeepLast, 100, rmw::Reliability::kReliable, rmw::Durability::kVolatile};
}

rmw::QoS tf_static_broadcaster_qos() {
  return {rmw::History::kKeepLast, 1, rmw::Reliability::kReliable,
          rmw::Durability::kTransientLocal};
}

rmw::QoS tf_static_listener_qos() {
  return {rmw::History::kKeepLast, 100, rmw::Reliability::kReliable,
          rmw::Durability::kTransientLocal};
}

TransformListener::TransformListener(graph::Node& node, TransformBuffer& buffer,
                                     std::function<void(const msgs::TFMessage&)> after,
                                     const std::string& tf_topic,
                                     const std::string& tf_static_topic)
    : node_(node), buffer_(buffer), after_(std::move(after)) {
  tf_ = node.create_subscription<msgs::TFMessage>(
      tf_topic, tf_qos(),
      [this, tf_topic](std::shared_ptr<const msgs::TFMessage> m) { take(*m, tf_topic, false); });
  tf_static_ = node.create_subscription<msgs::TFMessage>(
      tf_static_topic, tf_static_listener_qos(),
      [this, tf_static_topic](std::shared_ptr<const msgs::TFMessage> m) {
        take(*m, tf_static_topic, true);
      });
}

void TransformListener::take(const msgs::TFMessage& message, const std::string& authority,
                             bool is_static) {
  for (const auto& t : message.transforms) {
    try {
      buffer_.set_transform(t, authority, is_static);
    } catch (const TransformError& e) {
      if (refused_.fetch_add(1, std::memory_order_relaxed) == 0)
        std::fprintf(stderr, "robotperf node %s: %s\n", node_.name().c_str(), e.what());
    }
  }
  if (after_) after_(message);
}

TransformBroadcaster::TransformBroadcaster(graph::Node& node, const std::string& topic)
    : publisher_(node.create_publisher<msgs::TFMessage>(topic, tf_qos())) {}

void TransformBroadcaster::send(std::vector<msgs::TransformStamped> transforms) {
  auto message = std::make_shared<msgs::TFMessage>();
  message->transforms = std::move(transforms);
  publisher_->publish(std::shared_ptr<const msgs::TFMessage>(std::move(message)));
}

StaticTransformBroadcaster::StaticTransformBroadcaster(graph::Node& node, const std::string& topic)
    : publisher_(node.create_publisher<msgs::TFMessage>(topic, tf_static_broadcaster_qos())) {}

void StaticTransformBroadcaster::send(const std::vector<msgs::TransformStamped>& transforms) {
  for (const auto& t : transforms) {
    auto same_child = [&](const msgs::TransformStamped& held) {
      return held.child_frame_id == t.child_frame_id;
    };
    const auto held =
        std::find_if(latched_.transforms.begin(), latched_.transforms.end(), same_child);
    if (held == latched_.transforms.end()) {
      latched_.transforms.push_back(t);
    } else {
      *held = t;
    }
  }
  publisher_->publish(latched_);
}

}  // namespace robotperf::plugin
