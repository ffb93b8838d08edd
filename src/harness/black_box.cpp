#include "black_box.hpp"

#include <sys/prctl.h>
#include <time.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <random>
#include <stdexcept>

#include "robotperf/msgs/known_types.hpp"
#include "robotperf/msgs/serialized_message.hpp"
#include "robotperf/tracing/tracepoints.hpp"

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

// The Playback starts preparing a message at least this long before its deadline.
constexpr int64_t kMinPrepareLeadNs = 2'000'000;
// While the Playback waits for a far deadline, how often it checks whether to stop.
constexpr int64_t kStopCheckNs = 100'000'000;

void sleep_until_ns(int64_t deadline_ns) {
  timespec ts{static_cast<time_t>(deadline_ns / 1'000'000'000),
              static_cast<long>(deadline_ns % 1'000'000'000)};
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

}  // namespace

std::vector<int64_t> timeline_schedule(const std::vector<int64_t>& frame_times_ns, double scale,
                                       std::size_t count) {
  const std::size_t n = frame_times_ns.size();
  if (n < 2) throw BenchmarkError("following the recorded timeline needs at least 2 frames");
  if (!(scale > 0) || !std::isfinite(scale))
    throw std::invalid_argument("--rate-scale must be a positive number");
  // Offsets from the first frame in integers: absolute times near 1.7e18 ns
  // lose nanoseconds as doubles.
  const int64_t first = frame_times_ns.front();
  const double span = static_cast<double>(frame_times_ns.back() - first);
  const double loop = span + span / static_cast<double>(n - 1);
  std::vector<int64_t> schedule(count);
  for (std::size_t k = 0; k < count; ++k) {
    const double recorded =
        static_cast<double>(k / n) * loop + static_cast<double>(frame_times_ns[k % n] - first);
    schedule[k] = std::llround(recorded / scale);
  }
  return schedule;
}

ArrivalPattern ArrivalPattern::parse(const std::string& text) {
  ArrivalPattern p;
  if (text == "fixed") return p;
  if (text == "poisson") {
    p.kind = Kind::kPoisson;
    return p;
  }
  if (text.starts_with("burst:")) {
    const std::string n = text.substr(6);
    std::size_t used = 0;
    unsigned long long burst = 0;
    try {
      if (!n.empty() && n[0] != '-') burst = std::stoull(n, &used);
    } catch (const std::exception&) {
    }
    if (used == n.size() && burst >= 1 && burst <= 1'000'000) {
      p.kind = Kind::kBurst;
      p.burst = static_cast<std::size_t>(burst);
      return p;
    }
  }
  throw std::invalid_argument("--arrival " + text +
                              ": expected fixed, poisson or burst:N (N from 1 to 1000000)");
}

std::string ArrivalPattern::name() const {
  switch (kind) {
    case Kind::kPoisson:
      return "poisson";
    case Kind::kBurst:
      return "burst:" + std::to_string(burst);
    case Kind::kFixed:
      break;
  }
  return "fixed";
}

std::vector<int64_t> arrival_schedule(const ArrivalPattern& pattern, int64_t period_ns,
                                      std::size_t count) {
  std::vector<int64_t> schedule(count);
  switch (pattern.kind) {
    case ArrivalPattern::Kind::kFixed:
      for (std::size_t k = 0; k < count; ++k) schedule[k] = static_cast<int64_t>(k) * period_ns;
      break;
    case ArrivalPattern::Kind::kBurst: {
      const auto burst = static_cast<int64_t>(pattern.burst);
      for (std::size_t k = 0; k < count; ++k)
        schedule[k] = static_cast<int64_t>(k) / burst * burst * period_ns;
      break;
    }
    case ArrivalPattern::Kind::kPoisson: {
      std::mt19937_64 generator(pattern.seed);
      // The first message opens the run; each later one follows an exponential interval.
      double t = 0;
      for (std::size_t k = 1; k < count; ++k) {
        // u in [0, 1) from the top 53 bits; -ln(1 - u) is exponential with mean 1.
        const double u = static_cast<double>(generator() >> 11) * 0x1.0p-53;
        t += -std::log1p(-u) * static_cast<double>(period_ns);
        schedule[k] = std::llround(t);
      }
      break;
    }
  }
  return schedule;
}

Playback::Playback(graph::Context& context, const BenchmarkSpec& spec, const Dataset& dataset,
                   MessageIds ids, bool publish_serialized, std::vector<int64_t> schedule_ns)
    : node_(std::make_shared<graph::Node>(context, "robotperf_playback")),
      ids_(ids),
      schedule_ns_(std::move(schedule_ns)) {
  for (const auto& input : spec.inputs) {
    const DatasetStream& stream = dataset.stream(input.stream);
    if (stream.type->ros_type != input.type) {
      throw BenchmarkError("input " + input.topic + " is declared " + input.type +
                           " but dataset stream '" + input.stream + "' holds " +
                           stream.type->ros_type);
    }
    if (stream.messages.empty())
      throw BenchmarkError("dataset stream '" + input.stream + "' is empty");
    Input in{stream.type, stream.messages, msgs::is_serialized_type_support(*stream.type), {}};
    if (in.serialized && !publish_serialized) {
      // The transport hands objects to typed subscriptions: decode once, now.
      if (!msgs::with_message_type(input.type, []<class T>() {})) {
        throw BenchmarkError("input " + input.topic + ": type " + input.type +
                             " is not compiled into robotperf, so the intra transport cannot "
                             "deliver it; replay the bag with --rmw fastdds");
      }
      in.type = &type_support_by_name(input.type, input.topic);
      in.serialized = false;
      for (auto& m : in.messages) {
        std::shared_ptr<void> typed = in.type->create();
        try {
          in.type->deserialize(static_cast<const msgs::SerializedMessage*>(m.get())->cdr,
                               typed.get());
        } catch (const msgs::CdrError& e) {
          throw BenchmarkError("dataset " + dataset.name + ": a message on " + stream.topic +
                               " does not decode as " + input.type + ": " + e.what());
        }
        m = std::move(typed);
      }
    } else if (!in.serialized) {
      type_support_by_name(input.type, input.topic);  // refuses unstamped types
    }
    in.publisher = node_->create_generic_publisher(input.topic, *in.type, input.qos);
    inputs_.push_back(std::move(in));
  }
}

rmw::MessagePtr Playback::Input::copy_with_stamp(std::size_t frame, int64_t stamp_ns) const {
  const void* original = messages[frame].get();
  if (!serialized) return type->copy_with_stamp_ns(original, stamp_ns);
  auto copy = std::make_shared<msgs::SerializedMessage>(
      *static_cast<const msgs::SerializedMessage*>(original));
  msgs::write_header_stamp_ns(copy->cdr, stamp_ns);
  return copy;
}

bool DeviceWarmup::ready_after_round(std::size_t answers_so_far) {
  const std::size_t previous_round = answers_in_round_;
  const bool answered_before = answers_before_ > 0;
  answers_in_round_ = answers_so_far - answers_before_;
  answers_before_ = answers_so_far;
  return answers_in_round_ >= per_round_ ||
         (answers_in_round_ > 0 && answers_in_round_ <= previous_round) ||
         (answers_in_round_ == 0 && answered_before);
}

std::size_t Playback::run(std::vector<MessageRecord>& records,
                          const std::function<bool()>& should_stop,
                          const std::function<void(std::size_t)>& after_send,
                          const DeliveryGate* gate, int64_t* repeated_ns) {
  // The default 50 µs timer slack would show up as send lateness.
  prctl(PR_SET_TIMERSLACK, 1UL, 0, 0, 0);
  records.assign(ids_.count, MessageRecord{});
  // The messages of one deadline (several in a burst), per input.
  std::vector<std::vector<rmw::MessagePtr>> next;
  auto offset = [&](uint64_t k) {
    return schedule_ns_.empty() ? static_cast<int64_t>(k) * ids_.period_ns : schedule_ns_[k];
  };
  // The first deadline's messages are prepared once before the schedule starts, and thrown
  // away: with no earlier preparation to go by, the first one would get only the minimum lead,
  // and in a fresh process (its pages not yet faulted in) it is the slowest of all, so a first
  // burst of images went out tens of milliseconds late. The first deadline leaves time for it.
  int64_t longest_prepare_ns = 0;
  {
    const int64_t prepare_start = rmw::steady_now_ns();
    for (uint64_t k = 0; k < ids_.count && offset(k) == offset(0); ++k) {
      for (const Input& in : inputs_) (void)in.copy_with_stamp(k % in.messages.size(), 0);
    }
    longest_prepare_ns = rmw::steady_now_ns() - prepare_start;
  }
  const int64_t start_ns =
      rmw::steady_now_ns() + std::max<int64_t>(10'000'000, 4 * longest_prepare_ns);
  // Each repetition of the warm-up moves the rest of the schedule by the warm-up's span.
  int64_t shift_ns = 0;
  auto deadline = [&](uint64_t k) { return start_ns + shift_ns + offset(k); };
  const bool gated = gate != nullptr && gate->warmup > 0 && gate->warmup < ids_.count;
  bool repeating = false;  // sending the warm-up again: records and counts stay as they are
  // Paced by the graph: when each message went (a repeated warm-up's last time).
  std::vector<int64_t> sent_at(pacing_.scenario != Scenario::kOpenLoop ? ids_.count : 0);
  std::size_t sent = 0;
  for (uint64_t first = 0; first < ids_.count;) {
    if (should_stop()) break;
    if (gated && first == gate->warmup) {
      repeating = !gate->delivering();
      if (repeating) {
        if (rmw::steady_now_ns() > gate->deadline_ns)
          throw GraphNotConnected(gate->timeout_message());
        shift_ns += offset(gate->warmup);
        if (repeated_ns != nullptr) *repeated_ns += offset(gate->warmup);
        first = 0;
      }
    }
    const bool paced = pacing_.scenario != Scenario::kOpenLoop;
    if (paced && first >= pacing_.in_flight) {
      // The output of the message in_flight before, or giving up on it; in slices, so that a
      // stop is seen.
      const uint64_t before = first - pacing_.in_flight;
      const int64_t give_up = sent_at[before] + pacing_.give_up_ns;
      while (!pacing_.answered(before, std::min(give_up, rmw::steady_now_ns() + kStopCheckNs))) {
        if (rmw::steady_now_ns() >= give_up || should_stop()) break;
      }
      if (should_stop()) break;
    }
    // Paced by the graph, a message is due when it may go (its preparation is not measured).
    const int64_t due = paced ? INT64_MIN : deadline(first);
    uint64_t end = first + 1;
    // A burst that holds the last warm-up message and the first measured one is sent in two
    // parts at its deadline, the gate asked between them: no measured message goes out before it.
    while (!paced && end < ids_.count && deadline(end) == due && !(gated && end == gate->warmup))
      ++end;
    // Prepare before the deadline, so copying the payload is not measured, but only just before
    // it: copying megabytes right after the previous send would compete with the graph while it
    // handles that message (for a core, for memory bandwidth, and for the wake-up of the node
    // that has to take it). The lead is a multiple of the longest preparation seen, so that a
    // slow copy on a busy machine still ends before the deadline.
    // Long waits (low rates) in slices, so that a stop is seen within kStopCheckNs.
    const int64_t prepare_at =
        paced ? rmw::steady_now_ns() : due - std::max(kMinPrepareLeadNs, 4 * longest_prepare_ns);
    bool stopped = false;
    while (!stopped && rmw::steady_now_ns() + kStopCheckNs < prepare_at) {
      sleep_until_ns(rmw::steady_now_ns() + kStopCheckNs);
      stopped = should_stop();
    }
    if (stopped) break;
    sleep_until_ns(prepare_at);
    const int64_t prepare_start = rmw::steady_now_ns();
    next.assign(end - first, std::vector<rmw::MessagePtr>(inputs_.size()));
    for (uint64_t k = first; k < end; ++k) {
      for (std::size_t i = 0; i < inputs_.size(); ++i) {
        const Input& in = inputs_[i];
        next[k - first][i] = in.copy_with_stamp(k % in.messages.size(), ids_.stamp_ns(k));
      }
    }
    longest_prepare_ns = std::max(longest_prepare_ns, rmw::steady_now_ns() - prepare_start);
    const int64_t send_at = paced ? rmw::steady_now_ns() : due;
    if (!paced) sleep_until_ns(send_at);
    for (uint64_t k = first; k < end; ++k) {
      const int64_t now = rmw::steady_now_ns();
      if (paced) sent_at[k] = now;
      if (repeating) {
        for (std::size_t i = 0; i < inputs_.size(); ++i)
          inputs_[i].publisher->publish(std::move(next[k - first][i]));
        continue;
      }
      MessageRecord& r = records[k];
      r.id = k;
      r.scheduled_ns = send_at;
      r.sent_ns = now;
      lttng_ust_tracepoint(robotperf, input, node_->name().c_str(), ids_.stamp_ns(k), k, send_at);
      for (std::size_t i = 0; i < inputs_.size(); ++i)
        inputs_[i].publisher->publish(std::move(next[k - first][i]));
      ++sent;
      if (after_send) after_send(sent);
    }
    first = end;
  }
  records.resize(sent);
  return sent;
}

rmw::QoS Monitor::subscription_qos(rmw::QoS graph_output) {
  graph_output.history = rmw::History::kKeepAll;
  return graph_output;
}

Monitor::Monitor(graph::Context& context, const BoundaryTopic& output, MessageIds ids,
                 std::size_t warmup, RunIsolation* isolation, const std::string& node_name,
                 bool traced)
    : node_(std::make_shared<graph::Node>(context, node_name)),
      type_(&type_support_by_name(output.type, output.topic)),
      topic_(output.topic),
      ids_(ids),
      warmup_(warmup),
      isolation_(isolation),
      state_(output.state),
      traced_(traced) {
  tally_.received_ns.assign(ids_.count, -1);
  node_->create_generic_subscription(output.topic, *type_, subscription_qos(output.qos),
                                     [this](rmw::MessagePtr m, const graph::MessageInfo& info) {
                                       // Read the clock first: everything after is monitor
                                       // overhead.
                                       const int64_t now = rmw::steady_now_ns();
                                       on_message(m, info, now);
                                     });
}

void Monitor::on_message(const rmw::MessagePtr& msg, const graph::MessageInfo& info,
                         int64_t now_ns) {
  if (now_ns > closed_at_ns_.load(std::memory_order_relaxed)) return;
  const int64_t stamp = type_->stamp_ns(msg.get());
  const auto id = ids_.id_of(stamp);
  if (isolation_ != nullptr && isolation_->foreign(info.sender, stamp, id.has_value())) {
    // Not traced either: the grey-box analysis would count it as an unknown output.
    {
      std::lock_guard lock(mutex_);
      ++tally_.foreign;
    }
    return;
  }
  if (traced_) {
    lttng_ust_tracepoint(robotperf, output, node_->name().c_str(), topic_.c_str(), stamp,
                         type_->serialized_size(msg.get()));
  }
  const bool shared_with_graph = info.from_intra_process;
  // A kept output the graph shares with us (intra) is copied rather than held: holding it would
  // make a node that reuses its output buffer once released allocate and page-fault a fresh one
  // for the next frame, a cost the measurement would add to the graph.
  // keep_ is written only before the run starts.
  rmw::MessagePtr kept;
  const bool chosen = id && !keep_.empty() && keep_[*id];
  if (chosen && on_arrival_ == nullptr)
    kept = shared_with_graph ? type_->copy_with_stamp_ns(msg.get(), stamp) : msg;
  bool evaluate = false;
  {
    std::lock_guard lock(mutex_);
    ++received_;
    if (!id) {
      ++tally_.unknown;
    } else if (tally_.received_ns[*id] >= 0) {
      if (*id < warmup_) {
        // A warm-up message again: the Playback repeats the warm-up until the graph delivers.
      } else if (!state_) {
        ++tally_.duplicates;
      } else {
        ++tally_.repeats;
        // A state stream: the latest state reflecting this command is what is judged.
        if (kept) tally_.kept[kept_index_[*id]].second = std::move(kept);
      }
    } else {
      tally_.received_ns[*id] = now_ns;
      if (*id >= warmup_) ++tally_.received_measured;
      if (kept) {
        kept_index_[*id] = tally_.kept.size();
        tally_.kept.emplace_back(*id, std::move(kept));
      }
      evaluate = chosen && on_arrival_ != nullptr && tally_.evaluation_error.empty();
      if (evaluate) ++evaluations_pending_;
    }
  }
  cv_.notify_all();
  if (evaluate) {
    // After the reception time was taken: the check is not part of the latency. An evaluator
    // (a plug-in's code) that throws fails the functional check, not the measurement; and the
    // pending count must come down whatever it does, or tally() would wait for it forever.
    std::string error;
    {
      std::lock_guard lock(evaluate_mutex_);
      try {
        on_arrival_->add(msg.get(), static_cast<std::size_t>(*id % on_arrival_frames_));
      } catch (const std::exception& e) {
        error = e.what();
      } catch (...) {
        error = "an exception that is not a std::exception";
      }
    }
    {
      std::lock_guard lock(mutex_);
      --evaluations_pending_;
      if (error.empty()) {
        ++tally_.evaluated_on_arrival;
      } else if (tally_.evaluation_error.empty()) {
        tally_.evaluation_error = std::move(error);
      }
    }
    cv_.notify_all();
  }
}

void Monitor::evaluate_on_arrival(plugin::FunctionalEvaluator& evaluator, std::size_t frames) {
  std::lock_guard lock(mutex_);
  on_arrival_ = &evaluator;
  on_arrival_frames_ = std::max<std::size_t>(frames, 1);
}

void Monitor::keep_outputs(const std::vector<uint64_t>& ids) {
  std::lock_guard lock(mutex_);
  keep_.assign(ids_.count, false);
  kept_index_.assign(ids_.count, SIZE_MAX);
  for (uint64_t id : ids) {
    if (id < ids_.count) keep_[id] = true;
  }
  tally_.kept.reserve(ids.size());
}

void Monitor::keep_observed_truth(const std::string& topic, const msgs::TypeSupport& type) {
  {
    std::lock_guard lock(mutex_);
    observing_truth_ = true;
  }
  rmw::QoS qos;
  qos.history = rmw::History::kKeepAll;
  node_->create_generic_subscription(
      topic, type, qos, [this, &type](rmw::MessagePtr m, const graph::MessageInfo& info) {
        if (rmw::steady_now_ns() > closed_at_ns_.load(std::memory_order_relaxed)) return;
        const int64_t stamp = type.stamp_ns(m.get());
        const auto id = ids_.id_of(stamp);
        if (isolation_ != nullptr && isolation_->foreign(info.sender, stamp, id.has_value()))
          return;
        std::lock_guard lock(mutex_);
        if (id && !keep_.empty() && keep_[*id]) {
          tally_.observed_truth[*id] = std::move(m);
          cv_.notify_all();
        }
      });
}

bool Monitor::wait_received(uint64_t id, int64_t deadline_ns) {
  std::unique_lock lock(mutex_);
  const auto deadline =
      std::chrono::steady_clock::time_point(std::chrono::nanoseconds(deadline_ns));
  return cv_.wait_until(lock, deadline, [&] {
    return id < tally_.received_ns.size() && tally_.received_ns[id] >= 0;
  });
}

bool Monitor::wait_for(std::size_t expected, int64_t deadline_ns) {
  std::unique_lock lock(mutex_);
  const auto deadline =
      std::chrono::steady_clock::time_point(std::chrono::nanoseconds(deadline_ns));
  // A kept output whose observed truth has not come yet: with a node's second output (b3's poses
  // after its detections) the last one is often still on its way when the first has arrived.
  const auto truth_complete = [&] {
    if (!observing_truth_) return true;
    return std::all_of(tally_.kept.begin(), tally_.kept.end(), [&](const auto& kept) {
      return tally_.observed_truth.contains(kept.first);
    });
  };
  return cv_.wait_until(lock, deadline,
                        [&] { return tally_.received_measured >= expected && truth_complete(); });
}

void Monitor::close() {
  closed_at_ns_.store(rmw::steady_now_ns(), std::memory_order_relaxed);
}

Monitor::Tally Monitor::tally() const {
  std::unique_lock lock(mutex_);
  // An output being checked on arrival counts once its check returns.
  cv_.wait(lock, [&] { return evaluations_pending_ == 0; });
  return tally_;
}

std::size_t Monitor::received() const {
  std::lock_guard lock(mutex_);
  return received_;
}

}  // namespace robotperf::harness
