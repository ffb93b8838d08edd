#include "black_box.hpp"

#include <sys/prctl.h>
#include <time.h>

#include <cerrno>
#include <stdexcept>

#include "robotperf/msgs/known_types.hpp"

namespace robotperf::harness {
namespace {

const msgs::TypeSupport& type_support_by_name(const std::string& ros_type,
                                              const std::string& topic) {
  const msgs::TypeSupport* ts = nullptr;
  msgs::with_message_type(ros_type, [&]<class T>() { ts = &msgs::type_support<T>(); });
  if (ts == nullptr)
    throw BenchmarkError("topic " + topic + ": unsupported message type " + ros_type);
  if (!ts->stamped()) {
    throw BenchmarkError("topic " + topic + ": type " + ros_type +
                         " has no std_msgs/Header, so it cannot carry message IDs");
  }
  return *ts;
}

void sleep_until_ns(int64_t deadline_ns) {
  timespec ts{static_cast<time_t>(deadline_ns / 1'000'000'000),
              static_cast<long>(deadline_ns % 1'000'000'000)};
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

}  // namespace

std::optional<uint64_t> MessageIds::id_of(int64_t stamp) const {
  const int64_t offset = stamp - base_ns;
  if (offset < 0 || offset % period_ns != 0) return std::nullopt;
  const auto id = static_cast<uint64_t>(offset / period_ns);
  if (id >= count) return std::nullopt;
  return id;
}

Playback::Playback(graph::Context& context, const BenchmarkSpec& spec, const Dataset& dataset,
                   MessageIds ids)
    : node_(std::make_shared<graph::Node>(context, "robotperf_playback")), ids_(ids) {
  for (const auto& input : spec.inputs) {
    const DatasetStream& stream = dataset.stream(input.stream);
    const auto& ts = type_support_by_name(input.type, input.topic);
    if (stream.type != &ts) {
      throw BenchmarkError("input " + input.topic + " is declared " + input.type +
                           " but dataset stream '" + input.stream + "' holds " +
                           stream.type->ros_type);
    }
    if (stream.messages.empty())
      throw BenchmarkError("dataset stream '" + input.stream + "' is empty");
    inputs_.push_back({&stream, node_->create_generic_publisher(input.topic, ts, input.qos)});
  }
}

std::size_t Playback::run(std::vector<MessageRecord>& records,
                          const std::function<bool()>& should_stop,
                          const std::function<void(std::size_t)>& after_send) {
  // The default 50 µs timer slack would show up as send lateness.
  prctl(PR_SET_TIMERSLACK, 1UL, 0, 0, 0);
  records.assign(ids_.count, MessageRecord{});
  std::vector<rmw::MessagePtr> next(inputs_.size());
  // The first deadline leaves time to prepare the first message.
  const int64_t start_ns = rmw::steady_now_ns() + 10'000'000;
  std::size_t sent = 0;
  for (uint64_t k = 0; k < ids_.count; ++k) {
    if (should_stop()) break;
    // Prepare before the deadline, so copying the payload is not measured.
    for (std::size_t i = 0; i < inputs_.size(); ++i) {
      const DatasetStream& s = *inputs_[i].stream;
      const void* original = s.messages[k % s.messages.size()].get();
      next[i] = s.type->copy_with_stamp_ns(original, ids_.stamp_ns(k));
    }
    MessageRecord& r = records[k];
    r.id = k;
    r.scheduled_ns = start_ns + static_cast<int64_t>(k) * ids_.period_ns;
    sleep_until_ns(r.scheduled_ns);
    r.sent_ns = rmw::steady_now_ns();
    for (std::size_t i = 0; i < inputs_.size(); ++i)
      inputs_[i].publisher->publish(std::move(next[i]));
    ++sent;
    if (after_send) after_send(sent);
  }
  records.resize(sent);
  return sent;
}

Monitor::Monitor(graph::Context& context, const BoundaryTopic& output, MessageIds ids,
                 std::size_t warmup)
    : node_(std::make_shared<graph::Node>(context, "robotperf_monitor")),
      type_(&type_support_by_name(output.type, output.topic)),
      ids_(ids),
      warmup_(warmup) {
  tally_.received_ns.assign(ids_.count, -1);
  // The Monitor keeps everything the graph delivered: a briefly starved
  // Monitor must not turn into loss charged to the graph under test.
  rmw::QoS qos = output.qos;
  qos.history = rmw::History::kKeepAll;
  node_->create_generic_subscription(output.topic, *type_, qos,
                                     [this](rmw::MessagePtr m, const graph::MessageInfo&) {
                                       // Read the clock first: everything after is monitor
                                       // overhead.
                                       const int64_t now = rmw::steady_now_ns();
                                       on_message(m, now);
                                     });
}

void Monitor::on_message(const rmw::MessagePtr& msg, int64_t now_ns) {
  const auto id = ids_.id_of(type_->stamp_ns(msg.get()));
  {
    std::lock_guard lock(mutex_);
    ++received_;
    if (!id) {
      ++tally_.unknown;
    } else if (tally_.received_ns[*id] >= 0) {
      ++tally_.duplicates;
    } else {
      tally_.received_ns[*id] = now_ns;
      if (*id >= warmup_) ++tally_.received_measured;
      if (!keep_.empty() && keep_[*id]) tally_.kept.emplace_back(*id, msg);
    }
  }
  cv_.notify_all();
}

void Monitor::keep_outputs(const std::vector<uint64_t>& ids) {
  std::lock_guard lock(mutex_);
  keep_.assign(ids_.count, false);
  for (uint64_t id : ids) {
    if (id < ids_.count) keep_[id] = true;
  }
  tally_.kept.reserve(ids.size());
}

bool Monitor::wait_for(std::size_t expected, int64_t deadline_ns) {
  std::unique_lock lock(mutex_);
  const auto deadline =
      std::chrono::steady_clock::time_point(std::chrono::nanoseconds(deadline_ns));
  return cv_.wait_until(lock, deadline, [&] { return tally_.received_measured >= expected; });
}

Monitor::Tally Monitor::tally() const {
  std::lock_guard lock(mutex_);
  return tally_;
}

std::size_t Monitor::received() const {
  std::lock_guard lock(mutex_);
  return received_;
}

}  // namespace robotperf::harness
