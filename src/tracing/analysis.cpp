#include "robotperf/tracing/analysis.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <exception>
#include <future>
#include <iterator>
#include <map>
#include <mutex>
#include <span>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <thread>
#include <tuple>
#include <unordered_map>

#include "huge_page_allocator.hpp"
#include "robotperf/metrics/delivery_validity.hpp"
#include "robotperf/tracing/ctf.hpp"

namespace robotperf::tracing {
namespace {

namespace fs = std::filesystem;
using ctf::Event;
using ctf::Value;

constexpr double kNsPerMs = 1e6;
// Decoding threads at most, and the smallest part of a stream worth a thread of its own.
constexpr unsigned kMaxDecodeThreads = 16;
constexpr uint64_t kMinPartBytes = 1 << 20;
// Defective packets described one by one; the rest are counted (a trace may have thousands).
constexpr std::size_t kMaxDefectLines = 20;

// What the analysis does with an event class, and where its fields are.
enum class Handler : uint8_t {
  kIgnore,
  kRunBegin,
  kRunJoin,
  kRunEnd,
  kInput,
  kOutput,
  kPublish,
  kCallbackEntry,
  kKernelInit,
  kKernelFini,
  kDeviceBegin,
  kDeviceEnd,
  kNodeInit,
  kPublisherInit,
  kSubscriptionInit,
  kRclcppSubscriptionInit,
  kSubscriptionCallbackAdded,
  kTimerInit,
  kTimerCallbackAdded,
  kTimerLinkNode,
  kCallbackRegister,
  kCallbackStart,
  kCallbackEnd,
  kRmwPublish,
  kRmwTake,
  kControllerUpdateBegin,
  kControllerUpdateEnd,
  kTf2Begin,
  kTf2End,
};

struct Dispatch {
  Handler handler = Handler::kIgnore;
  int f[8] = {-1, -1, -1, -1, -1, -1, -1, -1};  // payload field indices, per handler
  int vpid = -1, vtid = -1;                     // stream context indices
};

Dispatch dispatch_for(const ctf::EventClass& ec, const ctf::Trace& trace) {
  struct Spec {
    const char* name;
    Handler handler;
    std::vector<const char*> fields;
  };
  static const std::vector<Spec> specs = {
      {"robotperf:run_begin",
       Handler::kRunBegin,
       {"benchmark", "rmw", "count", "warmup", "period_ns", "min_samples", "max_loss_percent",
        "state_output"}},
      {"robotperf:run_join", Handler::kRunJoin, {"run_pid"}},
      {"robotperf:run_end", Handler::kRunEnd, {"sent"}},
      {"robotperf:input", Handler::kInput, {"message_id", "index", "scheduled_ns"}},
      {"robotperf:output", Handler::kOutput, {"message_id"}},
      {"robotperf:publish", Handler::kPublish, {"node", "topic", "message_id"}},
      {"robotperf:callback_entry", Handler::kCallbackEntry, {"node", "topic", "message_id"}},
      {"robotperf:kernel_init", Handler::kKernelInit, {"node", "kernel", "message_id"}},
      {"robotperf:kernel_fini", Handler::kKernelFini, {"node", "kernel", "message_id"}},
      {"robotperf:device_begin", Handler::kDeviceBegin, {"node", "stage", "message_id"}},
      {"robotperf:device_end", Handler::kDeviceEnd, {"node", "stage", "message_id"}},
      {"ros2:rcl_node_init", Handler::kNodeInit, {"node_handle", "node_name", "namespace"}},
      {"ros2:rcl_publisher_init",
       Handler::kPublisherInit,
       {"publisher_handle", "node_handle", "rmw_publisher_handle", "topic_name"}},
      {"ros2:rcl_subscription_init",
       Handler::kSubscriptionInit,
       {"subscription_handle", "node_handle", "rmw_subscription_handle", "topic_name"}},
      {"ros2:rclcpp_subscription_init",
       Handler::kRclcppSubscriptionInit,
       {"subscription_handle", "subscription"}},
      {"ros2:rclcpp_subscription_callback_added",
       Handler::kSubscriptionCallbackAdded,
       {"subscription", "callback"}},
      {"ros2:rcl_timer_init", Handler::kTimerInit, {"timer_handle", "period"}},
      {"ros2:rclcpp_timer_callback_added",
       Handler::kTimerCallbackAdded,
       {"timer_handle", "callback"}},
      {"ros2:rclcpp_timer_link_node", Handler::kTimerLinkNode, {"timer_handle", "node_handle"}},
      {"ros2:rclcpp_callback_register", Handler::kCallbackRegister, {"callback", "symbol"}},
      {"ros2:callback_start", Handler::kCallbackStart, {"callback"}},
      {"ros2:callback_end", Handler::kCallbackEnd, {"callback"}},
      {"ros2:rmw_publish", Handler::kRmwPublish, {"rmw_publisher_handle", "timestamp"}},
      {"ros2:rmw_take",
       Handler::kRmwTake,
       {"rmw_subscription_handle", "source_timestamp", "taken"}},
      {"robotperf:controller_update_begin",
       Handler::kControllerUpdateBegin,
       {"node", "controller", "cycle"}},
      {"robotperf:controller_update_end",
       Handler::kControllerUpdateEnd,
       {"node", "controller", "cycle"}},
      {"robotperf:tf2_begin", Handler::kTf2Begin, {"node", "operation", "call"}},
      {"robotperf:tf2_end", Handler::kTf2End, {"node", "operation", "call"}},
  };
  Dispatch d;
  for (const auto& s : specs) {
    if (ec.name != s.name) continue;
    for (std::size_t i = 0; i < s.fields.size(); ++i) {
      d.f[i] = ec.field_index(s.fields[i]);
      // Older ros2_tracing versions lack some fields (rmw_publish's timestamp):
      // such events cannot be used, the rest of the analysis still can.
      // robotperf's own traces before state_output lack it.
      const bool optional = std::string_view(s.fields[i]) == "namespace" ||
                            std::string_view(s.fields[i]) == "state_output" ||
                            (s.handler == Handler::kRmwTake && i == 2);
      if (d.f[i] < 0 && !optional) return d;
    }
    d.handler = s.handler;
    d.vpid = trace.stream_context_index(ec.stream_id, "vpid");
    d.vtid = trace.stream_context_index(ec.stream_id, "vtid");
    break;
  }
  return d;
}

struct Key {
  int32_t vpid;
  uint64_t handle;
  bool operator==(const Key&) const = default;
};
struct KeyHash {
  std::size_t operator()(const Key& k) const {
    return std::hash<uint64_t>()(k.handle * 0x9E3779B97F4A7C15ull ^ static_cast<uint64_t>(k.vpid));
  }
};
template <class V>
using HandleMap = std::unordered_map<Key, V, KeyHash>;

enum class IdKind : uint8_t {
  kPublish,
  kEntry,
  kKernelInit,
  kKernelFini,
  kDeviceBegin,
  kDeviceEnd
};

// Where an event carrying a message ID was emitted and what it says, apart from its time and
// message. A trace holds few of them (threads x nodes x topics), against millions of events.
struct IdSite {
  int32_t vpid;
  int32_t vtid;
  uint32_t node;
  uint32_t what;  // topic, or kernel name
  IdKind kind;
  bool operator==(const IdSite&) const = default;
};
struct IdSiteHash {
  std::size_t operator()(const IdSite& s) const {
    uint64_t h = static_cast<uint32_t>(s.vpid) * 0x9E3779B97F4A7C15ull;
    h ^= (static_cast<uint64_t>(static_cast<uint32_t>(s.vtid)) << 21) + s.node * 0xC2B2AE3Dull;
    h ^= (static_cast<uint64_t>(s.what) << 7) * 0x27D4EB2Full + static_cast<uint64_t>(s.kind);
    return static_cast<std::size_t>(h ^ (h >> 29));
  }
};

// Where a callback ran, for ros2:callback_start/end.
struct CallbackSite {
  int32_t vpid;
  int32_t vtid;
  uint64_t callback;
  bool operator==(const CallbackSite&) const = default;
};
struct CallbackSiteHash {
  std::size_t operator()(const CallbackSite& s) const {
    uint64_t h = (static_cast<uint64_t>(static_cast<uint32_t>(s.vpid)) << 32 |
                  static_cast<uint32_t>(s.vtid)) *
                 0x9E3779B97F4A7C15ull;
    h ^= s.callback * 0xC2B2AE3D27D4EB4Full;
    return static_cast<std::size_t>(h ^ (h >> 29));
  }
};

// The distinct sites of a trace's events, numbered in order of first use. The last two are
// remembered, since a thread's events cycle through a few sites.
template <class Site, class Hash>
class SiteTable {
 public:
  uint32_t intern(const Site& site) {
    if (recent_ids_[0] != UINT32_MAX && recent_[0] == site) return recent_ids_[0];
    uint32_t id;
    if (recent_ids_[1] != UINT32_MAX && recent_[1] == site) {
      id = recent_ids_[1];
    } else {
      auto [it, inserted] = ids_.try_emplace(site, static_cast<uint32_t>(sites_.size()));
      if (inserted) sites_.push_back(site);
      id = it->second;
    }
    recent_[1] = recent_[0];
    recent_ids_[1] = recent_ids_[0];
    recent_[0] = site;
    recent_ids_[0] = id;
    return id;
  }
  const Site& operator[](uint32_t id) const { return sites_[id]; }
  const std::vector<Site>& all() const { return sites_; }

  // Interns every site of `part` here, each as `rename` makes it; returns their numbers here, or
  // an empty vector when every number stays the same.
  template <class Rename>
  std::vector<uint32_t> merge(const SiteTable& part, Rename rename) {
    std::vector<uint32_t> number(part.sites_.size());
    bool renumbered = false;
    for (std::size_t i = 0; i < part.sites_.size(); ++i) {
      number[i] = intern(rename(part.sites_[i]));
      renumbered |= number[i] != i;
    }
    if (!renumbered) number.clear();
    return number;
  }

 private:
  std::vector<Site> sites_;
  std::unordered_map<Site, uint32_t, Hash> ids_;
  Site recent_[2] = {};
  uint32_t recent_ids_[2] = {UINT32_MAX, UINT32_MAX};
};

// 16 bytes, as the callback events: millions of them are written and read again, and in a
// virtual machine memory that a process touches for the first time costs about a nanosecond a
// byte.
struct IdEvent {
  int64_t ts;
  uint32_t message;  // index into its part's message IDs (Collected::message_ids)
  uint32_t site;     // in Collected::id_sites
};
static_assert(sizeof(IdEvent) == 16);

struct Input {
  int64_t ts, id, scheduled;
  uint64_t index;
  int32_t vpid;
};
struct Output {
  int64_t ts, id;
  int32_t vpid;
};
struct CallbackEvent {
  int64_t ts;
  uint32_t site;  // in Collected::callback_sites
  bool start;
};
static_assert(sizeof(CallbackEvent) == 16);
struct RmwEvent {
  int64_t ts;
  int32_t vpid;
  int32_t vtid;  // for callback causality (paths); fills what was padding
  uint64_t handle;
  int64_t stamp;
};
// The begin or end of a span a node numbers: a controller's update (`what`: the controller,
// `number`: the cycle) or a tf2 buffer's call (`what`: the operation, `number`: the call).
struct SpanEvent {
  int64_t ts;
  int32_t vpid;
  uint32_t node, what;  // interned names
  uint64_t number;
  bool begin;
};
struct Endpoint {
  uint32_t topic;
  uint64_t node_handle;
};

// Everything the analysis keeps from the events, before the run is known.
struct Collected {
  // Names (node, topic, kernel) interned; views into the mapped traces.
  std::unordered_map<std::string_view, uint32_t> name_ids;
  std::vector<std::string_view> names;
  uint32_t intern(std::string_view s) {
    // A trace repeats a few names millions of times: a small cache keyed on a name's length and
    // three of its bytes answers most without hashing the whole name.
    uint32_t& cached = recent[s.empty() ? 0
                                        : (s.size() * 31 + static_cast<unsigned char>(s.front()) +
                                           static_cast<unsigned char>(s[s.size() / 2]) * 7 +
                                           static_cast<unsigned char>(s.back()) * 13) %
                                              std::size(recent)];
    if (cached < names.size() && names[cached] == s) return cached;
    auto [it, inserted] = name_ids.try_emplace(s, static_cast<uint32_t>(names.size()));
    if (inserted) names.push_back(s);
    cached = it->second;
    return it->second;
  }
  uint32_t recent[64] = {};  // ids of names recently interned; any value is only a guess

  std::vector<std::pair<int64_t, RunInfo>> runs;   // (time, info)
  std::vector<std::pair<int32_t, int32_t>> joins;  // (vpid, run pid)
  std::vector<std::pair<int32_t, uint64_t>> ends;  // (vpid, sent)
  // One vector per part of a stream decoded (see StreamPart), in order: merged without a copy.
  PartedVector<Input> inputs;
  PartedVector<Output> outputs;
  PartedVector<IdEvent> id_events;
  // The message IDs of each part's ID events, one part for each of id_events' parts: a frame's
  // events follow one another in a stream, so an ID is stored once for several events.
  PartedVector<int64_t> message_ids;
  SiteTable<IdSite, IdSiteHash> id_sites;
  PartedVector<CallbackEvent> callbacks;
  SiteTable<CallbackSite, CallbackSiteHash> callback_sites;
  PartedVector<RmwEvent> rmw_publishes, rmw_takes;
  PartedVector<SpanEvent> controller_updates, tf2_calls;

  HandleMap<std::string> node_names;
  HandleMap<Endpoint> publishers_by_rmw, subscriptions_by_handle, subscriptions_by_rmw;
  HandleMap<uint64_t> rclcpp_subscriptions;  // rclcpp subscription -> rcl handle
  HandleMap<uint64_t> callback_subscription, callback_timer;
  HandleMap<int64_t> timer_period;
  HandleMap<uint64_t> timer_node;
  HandleMap<std::string_view> callback_symbol;

  // What the trace's metadata declares, for saying why a table is missing.
  bool has_rmw_publish = false, rmw_publish_has_timestamp = false;
};

// What each event class of a trace is for. Found by stream and event id, without hashing: the
// class changes at nearly every event.
class DispatchTable {
 public:
  void add(const ctf::EventClass& ec, const Dispatch& d) {
    auto it = std::find_if(streams_.begin(), streams_.end(),
                           [&](const auto& s) { return s.first == ec.stream_id; });
    if (it == streams_.end()) it = streams_.insert(streams_.end(), {ec.stream_id, {}});
    if (it->second.size() <= ec.id) it->second.resize(ec.id + 1);
    it->second[ec.id] = d;
    for (const int f : {d.vpid, d.vtid}) {
      if (f >= 0 &&
          std::find(context_fields_.begin(), context_fields_.end(), f) == context_fields_.end())
        context_fields_.push_back(f);
    }
  }
  // The fields that the dispatch of some class reads: the reader decodes only those.
  ctf::FieldSelection selection() const {
    ctf::FieldSelection s;
    s.payload = [this](const ctf::EventClass& ec, std::size_t field) {
      const Dispatch& d = of(ec);
      return d.handler != Handler::kIgnore &&
             std::find(std::begin(d.f), std::end(d.f), static_cast<int>(field)) != std::end(d.f);
    };
    s.stream_context = [this](const ctf::StreamClass&, std::size_t field) {
      return std::find(context_fields_.begin(), context_fields_.end(), static_cast<int>(field)) !=
             context_fields_.end();
    };
    return s;
  }
  // The dispatch of a class of this trace (every class was added).
  const Dispatch& of(const ctf::EventClass& ec) const {
    for (const auto& [stream, by_id] : streams_) {
      if (stream == ec.stream_id) return by_id[ec.id];
    }
    throw std::logic_error("event class '" + ec.name + "' has no dispatch");
  }

 private:
  std::vector<std::pair<uint64_t, std::vector<Dispatch>>> streams_;  // few: searched in turn
  std::vector<int> context_fields_;  // stream-context fields read (vpid, vtid)
};

// What each of a trace's event classes is for; notes what the metadata declares in `c`.
DispatchTable dispatch_table(const ctf::Trace& trace, Collected& c) {
  DispatchTable dispatch;
  for (const auto& ec : trace.metadata().events) {
    dispatch.add(*ec, dispatch_for(*ec, trace));
    if (ec->name == "ros2:rmw_publish") {
      c.has_rmw_publish = true;
      c.rmw_publish_has_timestamp |= ec->field_index("timestamp") >= 0;
    }
  }
  return dispatch;
}

// A run of consecutive packets of one stream, decoded on its own (by one thread), and what it
// gave: the part of the Collected of the whole trace that its events make.
struct StreamPart {
  const ctf::Trace* trace = nullptr;
  const DispatchTable* dispatch = nullptr;
  const ctf::FieldSelection* selection = nullptr;  // the dispatch's fields
  std::size_t stream = 0;
  std::span<ctf::Packet> packets;  // its own: decoding marks the defective ones
  uint64_t bytes = 0;

  Collected c;
  uint64_t events = 0;
  int64_t first_ns = INT64_MAX, last_ns = 0;  // of its events; meaningful when it has some
  std::exception_ptr error;
};

// What an event carrying a message ID says, by its handler (one of the six that carry one).
IdKind id_kind_of(Handler handler) {
  switch (handler) {
    case Handler::kPublish:
      return IdKind::kPublish;
    case Handler::kCallbackEntry:
      return IdKind::kEntry;
    case Handler::kKernelInit:
      return IdKind::kKernelInit;
    case Handler::kKernelFini:
      return IdKind::kKernelFini;
    case Handler::kDeviceBegin:
      return IdKind::kDeviceBegin;
    default:
      return IdKind::kDeviceEnd;
  }
}

// Collects the events of the part's packets; returns how many packets it found defective.
uint64_t collect_once(StreamPart& part) {
  Collected& c = part.c;
  // Room for every event the part may hold (LTTng events take 40 bytes or more): growing the
  // vectors would copy them and fault in pages twice.
  const std::size_t estimate = part.bytes / 40;
  BigVector<IdEvent>& id_events = c.id_events.add_part(estimate);
  BigVector<int64_t>& message_ids = c.message_ids.add_part(estimate / 2);
  // Reserved room that is never written costs nothing (pages are mapped when first written); a
  // vector grown from small blocks would fault each of their 4 KiB pages.
  BigVector<Input>& inputs = c.inputs.add_part(estimate / 8);
  BigVector<Output>& outputs = c.outputs.add_part(estimate / 8);
  BigVector<CallbackEvent>& callbacks = c.callbacks.add_part(estimate / 4);
  BigVector<RmwEvent>& rmw_publishes = c.rmw_publishes.add_part(estimate / 8);
  BigVector<RmwEvent>& rmw_takes = c.rmw_takes.add_part(estimate / 8);
  BigVector<SpanEvent>& controller_updates = c.controller_updates.add_part();
  BigVector<SpanEvent>& tf2_calls = c.tf2_calls.add_part();
  const DispatchTable& dispatch = *part.dispatch;
  const ctf::EventClass* last_class = nullptr;
  const Dispatch* d = nullptr;
  auto on_event = [&](const Event& e) {
    const auto ts = static_cast<int64_t>(e.timestamp);
    part.first_ns = std::min(part.first_ns, ts);
    part.last_ns = std::max(part.last_ns, ts);
    if (e.cls != last_class) {
      last_class = e.cls;
      d = &dispatch.of(*e.cls);
    }
    if (d->handler == Handler::kIgnore) return;
    const auto& f = e.fields;
    auto field = [&](int i) -> const Value& { return f[static_cast<std::size_t>(d->f[i])]; };
    const int32_t vpid =
        d->vpid >= 0
            ? static_cast<int32_t>(e.stream_context[static_cast<std::size_t>(d->vpid)].as_int())
            : 0;
    auto vtid = [&] {
      return d->vtid >= 0 ? static_cast<int32_t>(
                                e.stream_context[static_cast<std::size_t>(d->vtid)].as_int())
                          : 0;
    };
    switch (d->handler) {
      case Handler::kIgnore:
        break;
      case Handler::kRunBegin: {
        RunInfo r;
        r.benchmark = std::string(field(0).s);
        r.rmw = std::string(field(1).s);
        r.count = field(2).as_uint();
        r.warmup = field(3).as_uint();
        r.period_ns = field(4).as_int();
        r.min_samples = field(5).as_uint();
        r.max_loss_percent = field(6).tag == Value::Tag::kFloat
                                 ? field(6).f
                                 : static_cast<double>(field(6).as_int());
        r.state_output = d->f[7] >= 0 && field(7).as_int() != 0;
        r.pid = vpid;
        c.runs.emplace_back(ts, std::move(r));
        break;
      }
      case Handler::kRunJoin:
        c.joins.emplace_back(vpid, static_cast<int32_t>(field(0).as_int()));
        break;
      case Handler::kRunEnd:
        c.ends.emplace_back(vpid, field(0).as_uint());
        break;
      case Handler::kInput:
        inputs.push_back({ts, field(0).as_int(), field(2).as_int(), field(1).as_uint(), vpid});
        break;
      case Handler::kOutput:
        outputs.push_back({ts, field(0).as_int(), vpid});
        break;
      case Handler::kPublish:
      case Handler::kCallbackEntry:
      case Handler::kKernelInit:
      case Handler::kKernelFini:
      case Handler::kDeviceBegin:
      case Handler::kDeviceEnd: {
        const IdKind kind = id_kind_of(d->handler);
        const int64_t id = field(2).as_int();
        if (message_ids.empty() || message_ids.back() != id) message_ids.push_back(id);
        const uint32_t site =
            c.id_sites.intern({vpid, vtid(), c.intern(field(0).s), c.intern(field(1).s), kind});
        id_events.push_back({ts, static_cast<uint32_t>(message_ids.size() - 1), site});
        break;
      }
      case Handler::kNodeInit: {
        std::string ns = d->f[2] >= 0 ? std::string(field(2).s) : std::string();
        std::string name(field(1).s);
        // A node in a namespace other than "/" is shown with it.
        if (!ns.empty() && ns != "/") name = ns + (ns.ends_with('/') ? "" : "/") + name;
        c.node_names[{vpid, field(0).u}] = std::move(name);
        break;
      }
      case Handler::kPublisherInit:
        c.publishers_by_rmw[{vpid, field(2).u}] = {c.intern(field(3).s), field(1).u};
        break;
      case Handler::kSubscriptionInit: {
        const Endpoint ep{c.intern(field(3).s), field(1).u};
        c.subscriptions_by_handle[{vpid, field(0).u}] = ep;
        c.subscriptions_by_rmw[{vpid, field(2).u}] = ep;
        break;
      }
      case Handler::kRclcppSubscriptionInit:
        c.rclcpp_subscriptions[{vpid, field(1).u}] = field(0).u;
        break;
      case Handler::kSubscriptionCallbackAdded:
        c.callback_subscription[{vpid, field(1).u}] = field(0).u;
        break;
      case Handler::kTimerInit:
        c.timer_period[{vpid, field(0).u}] = field(1).as_int();
        break;
      case Handler::kTimerCallbackAdded:
        c.callback_timer[{vpid, field(1).u}] = field(0).u;
        break;
      case Handler::kTimerLinkNode:
        c.timer_node[{vpid, field(0).u}] = field(1).u;
        break;
      case Handler::kCallbackRegister:
        c.callback_symbol[{vpid, field(0).u}] = field(1).s;
        break;
      case Handler::kCallbackStart:
      case Handler::kCallbackEnd:
        callbacks.push_back({ts, c.callback_sites.intern({vpid, vtid(), field(0).u}),
                             d->handler == Handler::kCallbackStart});
        break;
      case Handler::kRmwPublish:
        rmw_publishes.push_back({ts, vpid, vtid(), field(0).u, field(1).as_int()});
        break;
      case Handler::kRmwTake:
        if (d->f[2] < 0 || field(2).as_int() != 0)
          rmw_takes.push_back({ts, vpid, vtid(), field(0).u, field(1).as_int()});
        break;
      case Handler::kControllerUpdateBegin:
      case Handler::kControllerUpdateEnd:
        controller_updates.push_back({ts, vpid, c.intern(field(0).s), c.intern(field(1).s),
                                      field(2).as_uint(),
                                      d->handler == Handler::kControllerUpdateBegin});
        break;
      case Handler::kTf2Begin:
      case Handler::kTf2End:
        tf2_calls.push_back({ts, vpid, c.intern(field(0).s), c.intern(field(1).s),
                             field(2).as_uint(), d->handler == Handler::kTf2Begin});
        break;
    }
  };
  const ctf::PacketsRead read =
      part.trace->read_packets(part.stream, part.packets, on_event, part.selection);
  part.events = read.events;
  return read.defective_packets;
}

// Collects the events of the part's packets, none of a defective packet's: the events a packet
// gave before its defect showed are dropped with the rest of the part, which is collected again
// without that packet (a corrupt trace's parts only).
void collect(StreamPart& part) {
  while (collect_once(part) > 0) {
    part.c = Collected{};
    part.first_ns = INT64_MAX;
    part.last_ns = 0;
  }
}

// Appends `part` to `c` as if its events had been collected into `c` after those before it:
// vectors in order, later handles replacing earlier ones, names interned in order of first use.
void merge(Collected& c, Collected&& part) {
  std::vector<uint32_t> id_of(part.names.size());
  for (std::size_t i = 0; i < part.names.size(); ++i) id_of[i] = c.intern(part.names[i]);
  auto append = [](auto& to, auto& from) {
    if (to.empty()) {
      to.swap(from);
    } else {
      to.insert(to.end(), std::make_move_iterator(from.begin()),
                std::make_move_iterator(from.end()));
    }
  };
  auto replace = [](auto& to, auto& from) {
    for (auto& [k, v] : from) to.insert_or_assign(k, std::move(v));
  };
  // The part's sites in the names of the whole trace, numbered among its sites; the events are
  // renumbered only where a number changed (most often none does).
  auto renumber = [](auto& events, const std::vector<uint32_t>& number) {
    if (number.empty()) return;
    for (auto& part_events : events.parts()) {
      for (auto& e : part_events) e.site = number[e.site];
    }
  };
  renumber(part.id_events, c.id_sites.merge(part.id_sites, [&](IdSite site) {
    site.node = id_of[site.node];
    site.what = id_of[site.what];
    return site;
  }));
  renumber(part.callbacks,
           c.callback_sites.merge(part.callback_sites, [](const CallbackSite& s) { return s; }));
  for (auto* spans : {&part.controller_updates, &part.tf2_calls}) {
    for (auto& events : spans->parts()) {
      for (auto& e : events) {
        e.node = id_of[e.node];
        e.what = id_of[e.what];
      }
    }
  }
  for (auto* endpoints :
       {&part.publishers_by_rmw, &part.subscriptions_by_handle, &part.subscriptions_by_rmw}) {
    for (auto& [k, ep] : *endpoints) ep.topic = id_of[ep.topic];
  }
  append(c.runs, part.runs);
  append(c.joins, part.joins);
  append(c.ends, part.ends);
  c.inputs.append(std::move(part.inputs));
  c.outputs.append(std::move(part.outputs));
  c.id_events.append(std::move(part.id_events));
  c.message_ids.append(std::move(part.message_ids));
  c.callbacks.append(std::move(part.callbacks));
  c.rmw_publishes.append(std::move(part.rmw_publishes));
  c.rmw_takes.append(std::move(part.rmw_takes));
  c.controller_updates.append(std::move(part.controller_updates));
  c.tf2_calls.append(std::move(part.tf2_calls));
  replace(c.node_names, part.node_names);
  replace(c.publishers_by_rmw, part.publishers_by_rmw);
  replace(c.subscriptions_by_handle, part.subscriptions_by_handle);
  replace(c.subscriptions_by_rmw, part.subscriptions_by_rmw);
  replace(c.rclcpp_subscriptions, part.rclcpp_subscriptions);
  replace(c.callback_subscription, part.callback_subscription);
  replace(c.callback_timer, part.callback_timer);
  replace(c.timer_period, part.timer_period);
  replace(c.timer_node, part.timer_node);
  replace(c.callback_symbol, part.callback_symbol);
}

// Cuts each stream into parts of about `target_bytes`, at packets that give their clock.
std::vector<StreamPart> cut_into_parts(const ctf::Trace& trace, const DispatchTable& dispatch,
                                       const ctf::FieldSelection& selection, std::size_t stream,
                                       std::span<ctf::Packet> packets, uint64_t target_bytes) {
  std::vector<StreamPart> parts;
  std::size_t first = 0;
  uint64_t bytes = 0;
  auto add = [&](std::size_t end) {
    StreamPart& p = parts.emplace_back();
    p.trace = &trace;
    p.dispatch = &dispatch;
    p.selection = &selection;
    p.stream = stream;
    p.packets = packets.subspan(first, end - first);
    p.bytes = bytes;
  };
  for (std::size_t i = 0; i < packets.size(); ++i) {
    if (i > first && bytes >= target_bytes && packets[i].has_clock) {
      add(i);
      first = i;
      bytes = 0;
    }
    bytes += (packets[i].end_bits - packets[i].start_bits) / 8;
  }
  if (first < packets.size()) add(packets.size());
  return parts;
}

// Decodes the parts on up to `threads` threads and merges them into `c` in order, each as soon as
// it and those before it are done (so that at most a few parts' events are held twice). The
// first part in order that failed gives the error, as reading them one after another would.
void collect_parallel(std::vector<StreamPart>& parts, unsigned threads, Collected& c,
                      TraceAnalysis& a) {
  std::mutex mutex;
  std::condition_variable done_cv;
  std::vector<char> done(parts.size(), 0);
  std::atomic<std::size_t> next{0};
  std::atomic<bool> failed{false};
  auto work = [&] {
    for (std::size_t i; !failed && (i = next++) < parts.size();) {
      try {
        collect(parts[i]);
      } catch (...) {
        parts[i].error = std::current_exception();
        failed = true;
      }
      {
        std::lock_guard lock(mutex);
        done[i] = 1;
      }
      done_cv.notify_all();
    }
  };
  std::vector<std::thread> pool;
  // One thread alone decodes here; several decode beside this one, which merges (a copy-free
  // append, mostly waiting).
  std::exception_ptr error;
  if (threads <= 1) {
    work();
  } else {
    for (unsigned t = 0; t < threads; ++t) pool.emplace_back(work);
  }
  // Parts are taken in order, so every part before the first failed one was taken and comes: the
  // merge stops at that failed one and never waits for a part no thread took.
  for (std::size_t i = 0; i < parts.size() && !error; ++i) {
    {
      std::unique_lock lock(mutex);
      done_cv.wait(lock, [&] { return done[i] != 0; });
    }
    StreamPart& p = parts[i];
    if (p.error) {
      error = p.error;
      break;
    }
    if (p.events > 0) {
      if (a.events == 0 || p.first_ns < a.first_ns) a.first_ns = p.first_ns;
      if (p.last_ns > a.last_ns) a.last_ns = p.last_ns;
      a.events += p.events;
    }
    merge(c, std::move(p.c));
    p.c = Collected{};
  }
  for (auto& t : pool) t.join();
  if (error) std::rethrow_exception(error);
}

// Millions of samples a table: kept in huge pages, and sorted where they lie (not copied).
using Samples = BigVector<double>;

// The statistics of `samples`, sorting them.
metrics::SampleStats stats_of(Samples& samples) {
  // The sort's second buffer in huge pages too (Samples' allocator leaves it unwritten).
  Samples scratch(samples.size());
  metrics::sort_samples(samples, scratch);
  return metrics::compute_stats_of_sorted(samples);
}

// Message ID -> index in a run's messages (sorted by index). robotperf's Playback makes ID k
// base + k * period: when every message has such an ID at its own place, the index is computed;
// otherwise (a trace from elsewhere, a missing input) it is looked up.
class MessageLookup {
 public:
  MessageLookup(const std::vector<MessageTimes>& messages, int64_t period_ns) {
    arithmetic_ = period_ns > 0 && !messages.empty();
    if (arithmetic_) {
      base_ = messages.front().id - static_cast<int64_t>(messages.front().index) * period_ns;
      period_ = period_ns;
      for (std::size_t i = 0; i < messages.size() && arithmetic_; ++i) {
        arithmetic_ =
            messages[i].index == i && messages[i].id == base_ + static_cast<int64_t>(i) * period_;
      }
      count_ = messages.size();
    }
    if (arithmetic_) return;
    by_id_.reserve(messages.size() * 2);
    for (std::size_t i = 0; i < messages.size(); ++i) {
      if (!by_id_.try_emplace(messages[i].id, i).second) repeated_.push_back(messages[i].id);
    }
  }
  // IDs that two messages carry (a lookup finds the first).
  const std::vector<int64_t>& repeated() const { return repeated_; }

  std::optional<std::size_t> find(int64_t id) const {
    if (arithmetic_) {
      // Unsigned: an ID below the base wraps to a huge offset, past count_.
      const uint64_t offset = static_cast<uint64_t>(id) - static_cast<uint64_t>(base_);
      if (offset % static_cast<uint64_t>(period_) != 0) return std::nullopt;
      const uint64_t index = offset / static_cast<uint64_t>(period_);
      if (index >= count_) return std::nullopt;
      return static_cast<std::size_t>(index);
    }
    auto it = by_id_.find(id);
    if (it == by_id_.end()) return std::nullopt;
    return it->second;
  }

 private:
  bool arithmetic_ = false;
  int64_t base_ = 0, period_ = 1;
  std::size_t count_ = 0;
  std::unordered_map<int64_t, std::size_t> by_id_;
  std::vector<int64_t> repeated_;
};

// The first `warmup` messages are sent but not measured (docs/design.md §3.4): every table
// of the run tells them by this.
bool is_warmup(const Input& in, const RunInfo& run) {
  return in.index < run.warmup;
}

// When the run's measurement begins: the send of its first measured message (INT64_MAX when it
// has none). Events without a message ID (rmw_publish) are measured from then on.
int64_t measurement_start(const Collected& c, const RunInfo& run) {
  int64_t start = INT64_MAX;
  for (const auto& in : c.inputs) {
    if (run.processes.contains(in.vpid) && !is_warmup(in, run)) start = std::min(start, in.ts);
  }
  return start;
}

// The black-box statistics and validity rules (harness/run.cpp), from the trace.
// Fills a.messages and returns the lookup of their IDs.
MessageLookup summarise_run(TraceAnalysis& a, const Collected& c, const RunInfo& run) {
  auto in_run = [&](int32_t vpid) { return run.processes.contains(vpid); };
  auto message_of = [&](const Input& in) {
    MessageTimes m;
    m.id = in.id;
    m.index = in.index;
    m.scheduled_ns = in.scheduled;
    m.sent_ns = in.ts;
    m.warmup = is_warmup(in, run);
    return m;
  };
  // The messages in order of their index. Where the indices are 0..n-1 (robotperf's own runs,
  // whatever order the streams hold them in), each is put at its place; otherwise they are sorted.
  std::size_t n = 0;
  for (const auto& in : c.inputs) n += in_run(in.vpid) ? 1 : 0;
  bool permutation = true;
  {
    std::vector<char> seen(n, 0);
    for (const auto& in : c.inputs) {
      if (!in_run(in.vpid)) continue;
      if (in.index >= n || seen[in.index] != 0) {
        permutation = false;
        break;
      }
      seen[in.index] = 1;
    }
  }
  a.messages.reserve(n);
  advise_huge_pages(a.messages.data(), a.messages.capacity() * sizeof(MessageTimes));
  if (permutation) {
    a.messages.resize(n);
    for (const auto& in : c.inputs) {
      if (in_run(in.vpid)) a.messages[in.index] = message_of(in);
    }
  } else {
    for (const auto& in : c.inputs) {
      if (in_run(in.vpid)) a.messages.push_back(message_of(in));
    }
    std::stable_sort(
        a.messages.begin(), a.messages.end(),
        [](const MessageTimes& x, const MessageTimes& y) { return x.index < y.index; });
  }
  MessageLookup lookup(a.messages, run.period_ns);
  for (const int64_t id : lookup.repeated())
    a.invalid_reasons.push_back("two inputs carry the message ID " + std::to_string(id));
  // The first reception of an ID is the one counted (the earliest: the outputs are in stream
  // order, not in time order); every other one of a measured message is a duplicate.
  std::size_t receptions_of_measured = 0;
  for (const auto& o : c.outputs) {
    if (!in_run(o.vpid)) continue;
    const auto i = lookup.find(o.id);
    if (!i) {
      ++a.unknown;
      continue;
    }
    MessageTimes& m = a.messages[*i];
    if (!m.warmup) ++receptions_of_measured;
    if (m.received_ns < 0 || o.ts < m.received_ns) m.received_ns = o.ts;
  }

  Samples from_scheduled, from_sent, lateness;
  BigVector<metrics::TimedEvent> receptions, sends;
  for (auto* v : {&from_scheduled, &from_sent, &lateness}) v->reserve(a.messages.size());
  for (auto* v : {&receptions, &sends}) v->reserve(a.messages.size());
  for (const auto& m : a.messages) {
    lateness.push_back(static_cast<double>(m.sent_ns - m.scheduled_ns));
    if (m.warmup) continue;
    ++a.measured;
    sends.push_back({m.scheduled_ns, m.sent_ns});
    if (m.received_ns < 0) continue;
    ++a.matched;
    from_scheduled.push_back(static_cast<double>(m.received_ns - m.scheduled_ns));
    from_sent.push_back(static_cast<double>(m.received_ns - m.sent_ns));
    receptions.push_back({m.scheduled_ns, m.received_ns});
  }
  // A state stream's further receptions are the state it keeps publishing (the Monitor counts
  // them as repeats, too).
  (run.state_output ? a.repeats : a.duplicates) = receptions_of_measured - a.matched;
  a.sent = a.messages.size();
  // Trace loss is never message loss: with events discarded, a missing output event says nothing.
  if (a.discarded_events > 0 || a.lost_packets > 0 || a.defective_packets > 0)
    a.unobserved = a.measured - a.matched;
  a.lost = a.measured - a.matched - a.unobserved;
  a.loss_percent =
      a.measured ? 100.0 * static_cast<double>(a.lost) / static_cast<double>(a.measured) : 0.0;
  {
    auto scheduled = std::async(std::launch::async, [&] { return stats_of(from_scheduled); });
    auto sent = std::async(std::launch::async, [&] { return stats_of(from_sent); });
    a.send_lateness = stats_of(lateness);
    a.latency_from_scheduled = scheduled.get();
    a.latency_from_sent = sent.get();
  }
  const metrics::DeliveryRates rates = metrics::delivery_rates(sends, receptions);
  a.throughput_hz = rates.output_hz;
  a.offered_rate_hz = rates.offered_hz;
  a.window_s = rates.window_s;

  auto invalid = [&](std::string why) { a.invalid_reasons.push_back(std::move(why)); };
  if (!run.ended) {
    invalid("the trace ends before the run did (no robotperf:run_end event)");
  } else if (run.sent_reported != run.count) {
    invalid("run ended early: sent " + std::to_string(run.sent_reported) + " of " +
            std::to_string(run.count) + " messages");
  }
  if (a.sent != run.sent_reported && run.ended) {
    invalid("the trace holds " + std::to_string(a.sent) + " input events for " +
            std::to_string(run.sent_reported) + " messages sent");
  }
  for (auto& why : metrics::delivery_invalid_reasons(
           {a.matched, a.duplicates, a.unknown, a.loss_percent},
           static_cast<std::size_t>(run.min_samples), run.max_loss_percent))
    invalid(std::move(why));
  return lookup;
}

constexpr uint32_t kNoGroup = UINT32_MAX;

// Groups `items` by a number below `groups` with a counting sort: linear, and in the items' order
// within a group. `group_of(i, item)` gives the i-th item's group, or kNoGroup to leave it out;
// `out` receives `place(item)` for each. Returns where each group starts in `out`, and its end.
template <class Items, class GroupOf, class Place, class Out>
BigVector<std::size_t> group_by(const Items& items, std::size_t groups, GroupOf group_of,
                                Place place, Out& out) {
  BigVector<std::size_t> starts(groups + 1, 0);
  std::size_t i = 0;
  for (const auto& item : items) {
    if (const uint32_t g = group_of(i++, item); g != kNoGroup) ++starts[g + 1];
  }
  for (std::size_t g = 1; g < starts.size(); ++g) starts[g] += starts[g - 1];
  out.resize(starts.back());
  BigVector<std::size_t> next(starts.begin(), starts.end() - 1);
  i = 0;
  for (const auto& item : items) {
    if (const uint32_t g = group_of(i++, item); g != kNoGroup) out[next[g]++] = place(item);
  }
  return starts;
}

// Per-hop breakdown from the events that carry message IDs.
void breakdown(TraceAnalysis& a, const Collected& c, const RunInfo& run,
               const MessageLookup& lookup) {
  // Group the events of measured messages by message (a counting sort on the
  // message's index: linear in the number of events), then by time within one.
  std::vector<char> site_in_run;
  for (const IdSite& site : c.id_sites.all())
    site_in_run.push_back(run.processes.contains(site.vpid) ? 1 : 0);
  // Each message ID stored is looked up once; its events follow it.
  BigVector<uint32_t> slot_of;
  slot_of.reserve(c.id_events.size());
  for (std::size_t p = 0; p < c.id_events.parts().size(); ++p) {
    const BigVector<int64_t>& ids = c.message_ids.parts()[p];
    uint32_t last_message = UINT32_MAX;
    uint32_t last_slot = kNoGroup;
    for (const IdEvent& e : c.id_events.parts()[p]) {
      if (site_in_run[e.site] == 0) {
        slot_of.push_back(kNoGroup);
        continue;
      }
      if (e.message != last_message) {
        const auto i = lookup.find(ids[e.message]);
        last_slot = i && !a.messages[*i].warmup ? static_cast<uint32_t>(*i) : kNoGroup;
        last_message = e.message;
      }
      slot_of.push_back(last_slot);
    }
  }
  // Pointers, not copies: a tenth of the memory to fill, and a frame's events lie close together.
  BigVector<const IdEvent*> ev;
  const BigVector<std::size_t> starts = group_by(
      c.id_events, a.messages.size(), [&](std::size_t i, const IdEvent&) { return slot_of[i]; },
      [](const IdEvent& e) { return &e; }, ev);
  for (std::size_t m = 0; m + 1 < starts.size(); ++m) {
    std::sort(ev.begin() + static_cast<std::ptrdiff_t>(starts[m]),
              ev.begin() + static_cast<std::ptrdiff_t>(starts[m + 1]),
              [](const IdEvent* x, const IdEvent* y) { return x->ts < y->ts; });
  }

  struct Acc {
    Samples durations;
    double offset_sum = 0;
  };
  // (kind, node, from, to) -> samples
  std::map<std::tuple<int, uint32_t, uint32_t, uint32_t>, Acc> acc;
  auto add = [&](int kind, uint32_t node, uint32_t from, uint32_t to, int64_t start, int64_t end,
                 int64_t sent) {
    auto [it, added] = acc.try_emplace({kind, node, from, to});
    Acc& x = it->second;
    // Most hops take one sample per measured message: room for them all at once, since growing
    // would write the samples' memory again at each doubling.
    if (added) x.durations.reserve(a.measured);
    x.durations.push_back(static_cast<double>(end - start));
    x.offset_sum += static_cast<double>(start - sent);
  };

  for (std::size_t m = 0; m + 1 < starts.size(); ++m) {
    const std::size_t lo = starts[m], hi = starts[m + 1];
    const int64_t sent = a.messages[m].sent_ns;
    auto site = [&](std::size_t j) -> const IdSite& { return c.id_sites[ev[j]->site]; };
    for (std::size_t i = lo; i < hi; ++i) {
      const IdSite& e = site(i);
      const int64_t ts = ev[i]->ts;
      // One sample per hop and message, as end to end takes the first reception: a node that
      // keeps publishing a state with this ID (a controller manager) publishes it again, and its
      // subscribers take it again.
      if (e.kind == IdKind::kEntry) {
        // Transport: the node's first take of this message on this topic, from the latest
        // publish on the topic before it.
        std::size_t publish = hi;
        bool taken_before = false;
        for (std::size_t j = i; j-- > lo && !taken_before;) {
          const IdSite& s = site(j);
          taken_before =
              s.kind == IdKind::kEntry && s.node == e.node && s.vpid == e.vpid && s.what == e.what;
          if (publish == hi && s.kind == IdKind::kPublish && s.what == e.what) publish = j;
        }
        if (!taken_before && publish != hi)
          add(0, e.node, site(publish).node, e.what, ev[publish]->ts, ts, sent);
      } else if (e.kind == IdKind::kPublish) {
        // Node: from the node's latest callback start on this message to its first publish on
        // this topic after it.
        for (std::size_t j = i; j-- > lo;) {
          const IdSite& s = site(j);
          if (s.node != e.node || s.vpid != e.vpid) continue;
          if (s.kind == IdKind::kPublish && s.what == e.what) break;
          if (s.kind == IdKind::kEntry) {
            add(1, e.node, s.what, e.what, ev[j]->ts, ts, sent);
            break;
          }
        }
      } else if (e.kind == IdKind::kKernelFini || e.kind == IdKind::kDeviceEnd) {
        // Kernel, or one stage of it on a device: from its begin on the same thread.
        const bool device = e.kind == IdKind::kDeviceEnd;
        const IdKind begin = device ? IdKind::kDeviceBegin : IdKind::kKernelInit;
        for (std::size_t j = i; j-- > lo;) {
          if (site(j).kind == begin && site(j).node == e.node && site(j).what == e.what &&
              site(j).vtid == e.vtid) {
            add(device ? 3 : 2, e.node, e.what, e.what, ev[j]->ts, ts, sent);
            break;
          }
        }
      }
    }
  }
  static const char* kinds[] = {"transport", "node", "kernel", "device"};
  // Each hop's statistics on a thread of its own: sorting its samples is what takes the time.
  std::vector<std::future<metrics::SampleStats>> stats;
  for (auto& [key, x] : acc) {
    const auto& [kind, node, from, to] = key;
    Hop h;
    h.kind = kinds[kind];
    h.node = std::string(c.names[node]);
    h.from = kind >= 2 ? std::string() : std::string(c.names[from]);
    h.to = std::string(c.names[to]);
    h.mean_start_offset_ns = x.offset_sum / static_cast<double>(x.durations.size());
    stats.push_back(
        std::async(std::launch::async, [&samples = x.durations] { return stats_of(samples); }));
    a.hops.push_back(std::move(h));
  }
  for (std::size_t i = 0; i < stats.size(); ++i) a.hops[i].duration = stats[i].get();
  std::stable_sort(a.hops.begin(), a.hops.end(), [](const Hop& x, const Hop& y) {
    return x.mean_start_offset_ns < y.mean_start_offset_ns;
  });
}

std::string hex(uint64_t v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "0x%llx", static_cast<unsigned long long>(v));
  return buf;
}

std::string node_name(const Collected& c, int32_t vpid, uint64_t node_handle) {
  auto it = c.node_names.find({vpid, node_handle});
  return it != c.node_names.end() ? it->second : "?";
}

// A callback's node, source (its topic, or "timer <period>") and symbol, from the init events.
using CallbackName = std::tuple<std::string, std::string, std::string>;
CallbackName callback_name(const Collected& c, int32_t vpid, uint64_t cb) {
  std::string symbol;
  if (auto sym = c.callback_symbol.find({vpid, cb}); sym != c.callback_symbol.end())
    symbol = sym->second;
  if (auto s = c.callback_subscription.find({vpid, cb}); s != c.callback_subscription.end()) {
    uint64_t handle = s->second;
    if (auto r = c.rclcpp_subscriptions.find({vpid, handle}); r != c.rclcpp_subscriptions.end())
      handle = r->second;
    if (auto ep = c.subscriptions_by_handle.find({vpid, handle});
        ep != c.subscriptions_by_handle.end()) {
      return {node_name(c, vpid, ep->second.node_handle), std::string(c.names[ep->second.topic]),
              symbol};
    }
  }
  if (auto t = c.callback_timer.find({vpid, cb}); t != c.callback_timer.end()) {
    std::string node = "?";
    if (auto n = c.timer_node.find({vpid, t->second}); n != c.timer_node.end())
      node = node_name(c, vpid, n->second);
    std::string source = "timer";
    if (auto p = c.timer_period.find({vpid, t->second}); p != c.timer_period.end()) {
      char buf[64];
      std::snprintf(buf, sizeof buf, "timer %g ms", static_cast<double>(p->second) / kNsPerMs);
      source = buf;
    }
    return {node, source, symbol};
  }
  return {"?", "callback " + hex(cb), symbol};
}

// Calls visit(site, start_ts, end_ts) for each callback of the run's threads that started and
// ended in the trace, thread by thread, each thread's in time order.
template <class Visit>
void for_each_callback(const Collected& c, const std::optional<RunInfo>& run, Visit visit) {
  // The run's events grouped by thread (a counting sort on the thread's number), then in time
  // order within one: a thread's events are in order already unless it moved between CPUs'
  // streams.
  std::map<std::pair<int32_t, int32_t>, uint32_t> thread_numbers;  // (vpid, vtid), in that order
  for (const CallbackSite& site : c.callback_sites.all()) {
    if (!run || run->processes.contains(site.vpid))
      thread_numbers.try_emplace({site.vpid, site.vtid}, 0);
  }
  uint32_t threads = 0;
  for (auto& [key, number] : thread_numbers) number = threads++;
  std::vector<uint32_t> thread_of;  // of each site; kNoGroup outside the run
  for (const CallbackSite& site : c.callback_sites.all()) {
    auto it = thread_numbers.find({site.vpid, site.vtid});
    thread_of.push_back(it != thread_numbers.end() ? it->second : kNoGroup);
  }
  BigVector<CallbackEvent> ev;
  const BigVector<std::size_t> starts = group_by(
      c.callbacks, threads, [&](std::size_t, const CallbackEvent& e) { return thread_of[e.site]; },
      [](const CallbackEvent& e) { return e; }, ev);
  auto earlier = [](const CallbackEvent& x, const CallbackEvent& y) { return x.ts < y.ts; };
  for (uint32_t t = 0; t < threads; ++t) {
    const auto from = ev.begin() + static_cast<std::ptrdiff_t>(starts[t]);
    const auto to = ev.begin() + static_cast<std::ptrdiff_t>(starts[t + 1]);
    if (!std::is_sorted(from, to, earlier)) std::stable_sort(from, to, earlier);
  }
  std::vector<std::pair<uint64_t, int64_t>> stack;
  for (uint32_t t = 0; t < threads; ++t) {
    stack.clear();
    for (std::size_t i = starts[t]; i < starts[t + 1]; ++i) {
      const CallbackSite& site = c.callback_sites[ev[i].site];
      if (ev[i].start) {
        stack.emplace_back(site.callback, ev[i].ts);
      } else if (!stack.empty() && stack.back().first == site.callback) {
        visit(site, stack.back().second, ev[i].ts);
        stack.pop_back();
      }
    }
  }
}

// Callback durations from ros2:callback_start/end, per node and source.
void callback_durations(TraceAnalysis& a, const Collected& c, const std::optional<RunInfo>& run) {
  // Callbacks with the same name make one series; each callback's series is named once.
  std::map<CallbackName, std::size_t> series_of_name;
  std::vector<Samples> series;
  HandleMap<std::size_t> series_of_callback;
  auto samples_of = [&](int32_t vpid, uint64_t cb) -> Samples& {
    auto [it, inserted] = series_of_callback.try_emplace({vpid, cb}, 0);
    if (inserted) {
      auto [named, added] = series_of_name.try_emplace(callback_name(c, vpid, cb), series.size());
      if (added) series.emplace_back();
      it->second = named->second;
    }
    return series[it->second];
  };
  for_each_callback(c, run, [&](const CallbackSite& site, int64_t start, int64_t end) {
    samples_of(site.vpid, site.callback).push_back(static_cast<double>(end - start));
  });
  for (auto& [name, index] : series_of_name) {
    a.callbacks.push_back(
        {std::get<0>(name), std::get<1>(name), std::get<2>(name), stats_of(series[index])});
  }
}

// Every callback, publish and take of the run's processes (of all, without a run), in time order.
void timeline(TraceAnalysis& a, const Collected& c, const std::optional<RunInfo>& run) {
  HandleMap<std::pair<std::string, std::string>> names;  // (node, source) of each callback
  for_each_callback(c, run, [&](const CallbackSite& site, int64_t start, int64_t end) {
    auto [it, inserted] = names.try_emplace({site.vpid, site.callback});
    if (inserted) {
      auto [node, source, symbol] = callback_name(c, site.vpid, site.callback);
      it->second = {std::move(node), std::move(source)};
    }
    a.timeline.push_back({TimelineEvent::Kind::kCallback, start, end - start, site.vpid, site.vtid,
                          it->second.first, it->second.second});
  });
  auto add = [&](const PartedVector<RmwEvent>& events, const HandleMap<Endpoint>& endpoints,
                 TimelineEvent::Kind kind) {
    for (const RmwEvent& e : events) {
      if (run && !run->processes.contains(e.vpid)) continue;
      auto ep = endpoints.find({e.vpid, e.handle});
      std::string node = "?", topic = "?";
      if (ep != endpoints.end()) {
        node = node_name(c, e.vpid, ep->second.node_handle);
        topic = std::string(c.names[ep->second.topic]);
      }
      a.timeline.push_back({kind, e.ts, 0, e.vpid, e.vtid, std::move(node), std::move(topic)});
    }
  };
  add(c.rmw_publishes, c.publishers_by_rmw, TimelineEvent::Kind::kPublish);
  add(c.rmw_takes, c.subscriptions_by_rmw, TimelineEvent::Kind::kTake);
  std::stable_sort(a.timeline.begin(), a.timeline.end(),
                   [](const TimelineEvent& x, const TimelineEvent& y) { return x.ts < y.ts; });
}

}  // namespace

std::string missing_run(const TraceAnalysis& a, int run_pid) {
  if (run_pid == 0 || a.run_pids.empty()) {
    return "no robotperf run in the trace (robotperf:run_begin)";
  }
  std::string pids;
  for (const int pid : a.run_pids) pids += (pids.empty() ? "" : ", ") + std::to_string(pid);
  return "no robotperf run of process " + std::to_string(run_pid) +
         " in the trace (it holds the run" + (a.run_pids.size() > 1 ? "s" : "") + " of process" +
         (a.run_pids.size() > 1 ? "es " : " ") + pids + ")";
}

namespace {

// Why each table the trace cannot fill is empty, from the events it lacks.
void explain_missing_tables(TraceAnalysis& a, const Collected& c, int run_pid) {
  if (a.hops.empty()) {
    a.unavailable.push_back(
        a.run ? "per-hop breakdown: no robotperf:publish / callback_entry / kernel events of the "
                "run's nodes"
              : "per-hop breakdown and end-to-end latency: " + missing_run(a, run_pid) +
                    "; they need a graph run by robotperf");
  }
  if (a.callbacks.empty()) {
    a.unavailable.push_back(
        c.callbacks.empty()
            ? "callback durations: no ros2:callback_start / callback_end events"
            : "callback durations: no callback_start / callback_end pair in the run's processes");
  } else if (c.callback_symbol.empty()) {
    a.unavailable.push_back(
        "callback symbols: no ros2:rclcpp_callback_register events (tracing started after the "
        "callbacks were registered, or a tracer that does not record them)");
  }
  if (a.topics.empty()) {
    std::string why;
    if (!c.has_rmw_publish || (c.rmw_publishes.empty() && c.rmw_publish_has_timestamp)) {
      why = "no ros2:rmw_publish events";
    } else if (!c.rmw_publish_has_timestamp) {
      why =
          "ros2:rmw_publish has no timestamp field (ros2_tracing before Jazzy does not record "
          "it), so takes cannot be paired with their publishes";
    } else if (c.rmw_takes.empty()) {
      why = "no ros2:rmw_take events";
    } else if (c.publishers_by_rmw.empty() || c.subscriptions_by_rmw.empty()) {
      why =
          "no ros2:rcl_publisher_init / rcl_subscription_init events to name the topics "
          "(tracing started after the nodes were created)";
    } else if (a.run && a.measured == 0) {
      why = "the run measured no message (the warm-up's publishes are not counted)";
    } else {
      why = "no rmw_take's source_timestamp equals an rmw_publish timestamp of its topic";
    }
    a.unavailable.push_back("publish -> take latencies: " + why);
  }
  if (a.controller_updates.empty()) {
    a.unavailable.push_back(
        "controller update durations: no robotperf:controller_update events (the graph runs no "
        "control loop)");
  }
  if (a.tf2_calls.empty()) {
    a.unavailable.push_back(
        "tf2 set and lookup durations: no robotperf:tf2 events (no node holds a tf2 buffer)");
  }
}

// A begin and its end: what a node spans, when and how long.
struct Span {
  uint32_t node, what;  // interned names
  int64_t begin, duration;
};

// The spans of the run's processes: a begin and an end of the same number of the same node and
// process make one span.
std::vector<Span> paired_spans(const PartedVector<SpanEvent>& events,
                               const std::optional<RunInfo>& run) {
  std::vector<SpanEvent> ev;
  for (const auto& e : events) {
    if (!run || run->processes.contains(e.vpid)) ev.push_back(e);
  }
  auto key = [](const SpanEvent& e) {
    return std::tuple(e.vpid, e.node, e.what, e.number, !e.begin, e.ts);
  };
  std::sort(ev.begin(), ev.end(), [&](const auto& x, const auto& y) { return key(x) < key(y); });
  std::vector<Span> spans;
  for (std::size_t i = 0; i + 1 < ev.size(); ++i) {
    const auto& b = ev[i];
    const auto& e = ev[i + 1];
    if (!b.begin || e.begin || b.vpid != e.vpid || b.node != e.node || b.what != e.what ||
        b.number != e.number)
      continue;
    spans.push_back({b.node, b.what, b.ts, e.ts - b.ts});
    ++i;
  }
  return spans;
}

// Span durations per node and what it spans.
std::map<std::pair<std::string, std::string>, Samples> span_durations(
    const Collected& c, const std::vector<Span>& spans) {
  std::map<std::pair<std::string, std::string>, Samples> acc;
  for (const Span& s : spans) {
    acc[{std::string(c.names[s.node]), std::string(c.names[s.what])}].push_back(
        static_cast<double>(s.duration));
  }
  return acc;
}

// Controller update durations from robotperf:controller_update_begin/end, per controller manager
// and controller (the span's number is the loop's cycle), and tf2 call durations from
// robotperf:tf2_begin/end, per buffer and operation (numbered by the buffer's calls). Returns the
// tf2 calls, for their share of the latency.
std::vector<Span> span_tables(TraceAnalysis& a, const Collected& c,
                              const std::optional<RunInfo>& run) {
  for (auto& [k, d] : span_durations(c, paired_spans(c.controller_updates, run)))
    a.controller_updates.push_back({k.first, k.second, stats_of(d)});
  std::vector<Span> tf2 = paired_spans(c.tf2_calls, run);
  for (auto& [k, d] : span_durations(c, tf2))
    a.tf2_calls.push_back({k.first, k.second, stats_of(d)});
  return tf2;
}

// The tf2 calls' share of the run's latency (docs/guides/grey-box.md): the calls that begin
// between the first measured message's send and the last matched output, per matched message,
// against the mean end-to-end latency from the actual send. Over a window rather than per message,
// so that a call is counted once however many messages are in flight.
void tf2_share(TraceAnalysis& a, const std::vector<Span>& tf2) {
  if (tf2.empty() || a.matched == 0) return;
  int64_t from = INT64_MAX, to = INT64_MIN;
  for (const auto& m : a.messages) {
    if (m.warmup || m.received_ns < 0) continue;
    from = std::min(from, m.sent_ns);
    to = std::max(to, m.received_ns);
  }
  Tf2Share share;
  double total_ns = 0;
  for (const Span& s : tf2) {
    if (s.begin < from || s.begin > to) continue;
    ++share.calls;
    total_ns += static_cast<double>(s.duration);
  }
  const auto matched = static_cast<double>(a.matched);
  share.calls_per_message = static_cast<double>(share.calls) / matched;
  share.per_message_ns = total_ns / matched;
  share.of_latency = share.per_message_ns / a.latency_from_sent.mean;
  a.tf2_share = share;
}

// rmw_publish -> rmw_take latencies, matched by topic and source timestamp; in a run, of the
// publishes from its measurement's start on (the warm-up's are not counted).
void topic_latencies(TraceAnalysis& a, const Collected& c, const std::optional<RunInfo>& run) {
  const int64_t since = run ? measurement_start(c, *run) : INT64_MIN;
  struct PubKey {
    uint32_t topic;
    int64_t stamp;
    bool operator==(const PubKey&) const = default;
  };
  struct PubHash {
    std::size_t operator()(const PubKey& k) const {
      return std::hash<int64_t>()(k.stamp) ^ (static_cast<std::size_t>(k.topic) << 40);
    }
  };
  // Nodes by (process, handle), numbered in order of first use; named at the end.
  HandleMap<uint32_t> node_numbers;
  std::vector<Key> nodes;
  auto node_number = [&](int32_t vpid, uint64_t handle) {
    auto [it, inserted] = node_numbers.try_emplace({vpid, handle}, nodes.size());
    if (inserted) nodes.push_back({vpid, handle});
    return it->second;
  };
  // (topic, stamp) -> the first publish's time and publishing node.
  std::unordered_map<PubKey, std::pair<int64_t, uint32_t>, PubHash> pubs;
  pubs.reserve(c.rmw_publishes.size());
  for (const auto& p : c.rmw_publishes) {
    if (p.ts < since || (run && !run->processes.contains(p.vpid))) continue;
    auto ep = c.publishers_by_rmw.find({p.vpid, p.handle});
    if (ep == c.publishers_by_rmw.end()) continue;
    pubs.try_emplace({ep->second.topic, p.stamp}, p.ts,
                     node_number(p.vpid, ep->second.node_handle));
  }
  // (topic, publisher, subscriber) -> samples.
  std::map<std::tuple<uint32_t, uint32_t, uint32_t>, Samples> acc;
  for (const auto& t : c.rmw_takes) {
    if (run && !run->processes.contains(t.vpid)) continue;
    auto ep = c.subscriptions_by_rmw.find({t.vpid, t.handle});
    if (ep == c.subscriptions_by_rmw.end()) continue;
    auto p = pubs.find({ep->second.topic, t.stamp});
    if (p == pubs.end()) continue;
    acc[{ep->second.topic, p->second.second, node_number(t.vpid, ep->second.node_handle)}]
        .push_back(static_cast<double>(t.ts - p->second.first));
  }
  // Named: nodes that share a name ("?" for unknown handles) share a row.
  std::map<std::tuple<std::string, std::string, std::string>, Samples> named;
  for (auto& [key, d] : acc) {
    const auto& [topic, publisher, subscriber] = key;
    auto name = [&](uint32_t n) { return node_name(c, nodes[n].vpid, nodes[n].handle); };
    auto& samples = named[{std::string(c.names[topic]), name(publisher), name(subscriber)}];
    samples.insert(samples.end(), d.begin(), d.end());
  }
  for (auto& [key, d] : named) {
    a.topics.push_back({std::get<0>(key), std::get<1>(key), std::get<2>(key), stats_of(d)});
  }
}

// The graph the trace's init events show: topics with their publishing and subscribing nodes.
// ROS 2's /rosout and /parameter_events, which every node has, would join every path.
TracedGraph traced_graph(const Collected& c, const std::optional<RunInfo>& run) {
  std::map<std::string_view, std::pair<std::set<std::string>, std::set<std::string>>> topics;
  auto add = [&](const HandleMap<Endpoint>& endpoints, bool publisher) {
    for (const auto& [key, ep] : endpoints) {
      if (run && !run->processes.contains(key.vpid)) continue;
      const std::string_view topic = c.names[ep.topic];
      if (topic == "/rosout" || topic == "/parameter_events") continue;
      auto& [pubs, subs] = topics[topic];
      (publisher ? pubs : subs).insert(node_name(c, key.vpid, ep.node_handle));
    }
  };
  add(c.publishers_by_rmw, true);
  add(c.subscriptions_by_handle, false);
  TracedGraph g;
  for (auto& [name, ends] : topics) {
    g.topics.push_back({std::string(name),
                        {ends.first.begin(), ends.first.end()},
                        {ends.second.begin(), ends.second.end()}});
  }
  return g;
}

// The events path latency reads, for the topics of `path`: publishes and takes on them, and the
// callbacks of the threads that made those (docs/design.md §3.13).
PathEvents path_events(const Collected& c, const std::vector<std::string>& path,
                       const std::optional<RunInfo>& run) {
  PathEvents pe;
  pe.topics = path;
  if (run) pe.since = measurement_start(c, *run);
  std::unordered_map<std::string_view, uint32_t> topic_number;
  for (std::size_t i = 0; i < path.size(); ++i)
    topic_number.try_emplace(path[i], static_cast<uint32_t>(i));
  HandleMap<uint32_t> node_number;
  auto node_of = [&](int32_t vpid, uint64_t handle) {
    auto [it, inserted] = node_number.try_emplace({vpid, handle}, pe.nodes.size());
    if (inserted) pe.nodes.push_back(node_name(c, vpid, handle));
    return it->second;
  };
  std::set<std::pair<int32_t, int32_t>> threads;
  auto add = [&](const PartedVector<RmwEvent>& events, const HandleMap<Endpoint>& endpoints,
                 PathEvent::Kind kind) {
    for (const RmwEvent& e : events) {
      if (run && !run->processes.contains(e.vpid)) continue;
      auto ep = endpoints.find({e.vpid, e.handle});
      if (ep == endpoints.end()) continue;
      auto t = topic_number.find(c.names[ep->second.topic]);
      if (t == topic_number.end()) continue;
      pe.events.push_back({e.ts, e.stamp, e.vpid, e.vtid, node_of(e.vpid, ep->second.node_handle),
                           t->second, kind});
      threads.insert({e.vpid, e.vtid});
    }
  };
  add(c.rmw_publishes, c.publishers_by_rmw, PathEvent::Kind::kPublish);
  add(c.rmw_takes, c.subscriptions_by_rmw, PathEvent::Kind::kTake);
  const auto& sites = c.callback_sites.all();
  std::vector<char> site_wanted(sites.size());
  for (std::size_t i = 0; i < sites.size(); ++i)
    site_wanted[i] = threads.contains({sites[i].vpid, sites[i].vtid}) ? 1 : 0;
  for (const CallbackEvent& e : c.callbacks) {
    if (!site_wanted[e.site]) continue;
    const CallbackSite& site = sites[e.site];
    pe.events.push_back(
        {e.ts, 0, site.vpid, site.vtid, 0, 0,
         e.start ? PathEvent::Kind::kCallbackStart : PathEvent::Kind::kCallbackEnd});
  }
  return pe;
}

// The path's topics checked against the graph: each in the trace, each pair joined by a node.
void check_path(const TracedGraph& g, const std::vector<std::string>& path) {
  const std::string hint = " (robotperf trace paths lists the trace's paths)";
  if (path.size() < 2)
    throw std::invalid_argument("a path needs at least two topics, comma-separated" + hint);
  for (std::size_t i = 0; i < path.size(); ++i) {
    if (g.find(path[i]) == nullptr)
      throw std::invalid_argument("topic " + path[i] + " is not in the trace" + hint);
    if (i == 0) continue;
    const auto& subs = g.find(path[i - 1])->subscribers;
    const auto& pubs = g.find(path[i])->publishers;
    if (std::none_of(subs.begin(), subs.end(), [&](const std::string& n) {
          return std::find(pubs.begin(), pubs.end(), n) != pubs.end();
        }))
      throw std::invalid_argument("no node in the trace subscribes " + path[i - 1] +
                                  " and publishes " + path[i] + hint);
  }
}

std::string fixed(double v, int decimals) {
  if (!std::isfinite(v)) return "-";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

// A demangled symbol for a table: parameter lists shortened to "(...)", anonymous namespaces
// dropped ("A::(anonymous namespace)::B::B(Context&, Config const&)::{lambda(Ptr)#1}" becomes
// "A::B::B(...)::{lambda(...)#1}").
std::string short_symbol(std::string_view symbol) {
  std::string s(symbol);
  for (std::size_t at; (at = s.find("(anonymous namespace)::")) != std::string::npos;)
    s.erase(at, std::string_view("(anonymous namespace)::").size());
  std::string out;
  int depth = 0;
  for (const char ch : s) {
    if (ch == '(') {
      if (depth++ == 0) out += "(...";
    } else if (ch == ')') {
      if (depth > 0 && --depth == 0) out += ')';
    } else if (depth == 0) {
      out += ch;
    }
  }
  return out;
}

std::string ms(double ns) {
  return fixed(ns / kNsPerMs, 3);
}

}  // namespace

std::string Hop::label() const {
  if (kind == "transport") return to + ": " + from + " -> " + node;
  if (kind == "node") return node + ": " + from + " -> " + to;
  if (kind == "device") return node + ": device " + to;
  return node + ": " + to;
}

TraceAnalysis analyze_trace(const fs::path& dir, const AnalyzeOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  TraceAnalysis a;
  const auto dirs = ctf::find_traces(dir);
  if (dirs.empty())
    throw std::invalid_argument(dir.string() + " holds no CTF trace (no 'metadata' file)");
  // Every trace opened and its streams' packets indexed first (cheap: headers only), then the
  // events decoded in parts on every core.
  std::vector<ctf::Trace> traces;
  traces.reserve(dirs.size());
  Collected c;
  // Reserved whole: the parts and the field selections refer to the tables where they lie.
  std::vector<DispatchTable> dispatch;
  dispatch.reserve(dirs.size());
  std::vector<ctf::FieldSelection> selections;
  std::vector<std::vector<ctf::StreamIndex>> indexes(dirs.size());
  uint64_t total_bytes = 0;
  for (std::size_t t = 0; t < dirs.size(); ++t) {
    traces.emplace_back(dirs[t]);
    a.traces.push_back(dirs[t].string());
    dispatch.push_back(dispatch_table(traces[t], c));
    selections.push_back(dispatch.back().selection());
    for (std::size_t s = 0; s < traces[t].stream_count(); ++s) {
      indexes[t].push_back(traces[t].index_stream(s));
      const ctf::StreamStats& st = indexes[t].back().stats;
      ++a.streams;
      a.packets += st.packets;
      a.discarded_events += st.discarded_events;
      a.lost_packets += st.lost_packets;
    }
    total_bytes += traces[t].total_bytes();
  }
  const unsigned threads = std::clamp(
      options.decode_threads != 0 ? options.decode_threads : std::thread::hardware_concurrency(),
      1u, kMaxDecodeThreads);
  // Several parts per thread, so that a thread that drew small ones takes more.
  const uint64_t target_bytes =
      options.part_bytes != 0 ? options.part_bytes
                              : std::max<uint64_t>(total_bytes / (4 * threads), kMinPartBytes);
  std::vector<StreamPart> parts;
  for (std::size_t t = 0; t < traces.size(); ++t) {
    for (std::size_t s = 0; s < indexes[t].size(); ++s) {
      auto cut = cut_into_parts(traces[t], dispatch[t], selections[t], s, indexes[t][s].packets,
                                target_bytes);
      std::move(cut.begin(), cut.end(), std::back_inserter(parts));
    }
  }
  collect_parallel(parts, std::min<unsigned>(threads, static_cast<unsigned>(parts.size())), c, a);
  for (const auto& trace_indexes : indexes) {
    for (const ctf::StreamIndex& index : trace_indexes) {
      for (const ctf::Packet& p : index.packets) {
        if (p.defect.empty()) continue;
        ++a.defective_packets;
        if (a.packet_defects.size() < kMaxDefectLines) a.packet_defects.push_back(p.defect);
      }
    }
  }

  if (!c.runs.empty()) {
    std::sort(c.runs.begin(), c.runs.end(),
              [](const auto& x, const auto& y) { return x.first < y.first; });
    for (const auto& [ts, r] : c.runs) a.run_pids.push_back(r.pid);
    const RunInfo* chosen = &c.runs.front().second;
    if (options.run_pid != 0) {
      chosen = nullptr;
      for (const auto& [ts, r] : c.runs) {
        if (r.pid == options.run_pid) chosen = &r;
      }
    }
    if (chosen != nullptr) {
      RunInfo run = *chosen;
      run.processes.insert(run.pid);
      run.processes.insert(options.extra_processes.begin(), options.extra_processes.end());
      for (const auto& [vpid, run_pid] : c.joins) {
        if (run_pid == run.pid) run.processes.insert(vpid);
      }
      for (const auto& [vpid, sent] : c.ends) {
        if (vpid == run.pid) {
          run.ended = true;
          run.sent_reported = sent;
        }
      }
      a.run = run;
    }
  }
  // The callback, topic and controller tables need the run's processes only: they are made on
  // another thread meanwhile (reading what was collected, each writing a table of its own).
  auto tables = std::async(std::launch::async, [&] {
    callback_durations(a, c, a.run);
    topic_latencies(a, c, a.run);
    return span_tables(a, c, a.run);
  });
  a.graph = traced_graph(c, a.run);
  if (options.timeline) timeline(a, c, a.run);
  // A path's latency only reads what was collected too: on a thread of its own meanwhile.
  std::future<PathLatency> path;
  if (!options.path.empty()) {
    check_path(a.graph, options.path);
    path = std::async(std::launch::async,
                      [&] { return path_latency(path_events(c, options.path, a.run)); });
  }
  if (a.run) {
    const MessageLookup lookup = summarise_run(a, c, *a.run);
    breakdown(a, c, *a.run, lookup);
  }
  const std::vector<Span> tf2 = tables.get();
  if (a.run) tf2_share(a, tf2);
  if (path.valid()) a.path = path.get();
  explain_missing_tables(a, c, options.run_pid);

  if (a.discarded_events > 0) {
    a.invalid_reasons.insert(
        a.invalid_reasons.begin(),
        "the tracer discarded " + std::to_string(a.discarded_events) +
            " events (sub-buffers too small for the event rate): the trace is incomplete");
  }
  if (a.lost_packets > 0) {
    a.invalid_reasons.insert(a.invalid_reasons.begin(),
                             "the tracer lost " + std::to_string(a.lost_packets) + " packets");
  }
  if (a.defective_packets > 0) {
    a.invalid_reasons.insert(
        a.invalid_reasons.begin(),
        "the trace is corrupt: the events of " + std::to_string(a.defective_packets) +
            (a.defective_packets == 1 ? " packet" : " packets") +
            " are left out, their times out of order (" + a.packet_defects.front() + ")");
  }
  if (!a.run && options.run_pid != 0) a.invalid_reasons.push_back(missing_run(a, options.run_pid));
  a.valid = a.invalid_reasons.empty();
  a.read_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return a;
}

namespace {

nlohmann::json path_json(const PathLatency& p) {
  nlohmann::json hops = nlohmann::json::array();
  for (const auto& h : p.hops) {
    hops.push_back({{"from", h.from},
                    {"node", h.node},
                    {"to", h.to},
                    {"transport_ms", metrics::to_json(h.transport, 1.0 / kNsPerMs, "ms")},
                    {"in_node_ms", metrics::to_json(h.in_node, 1.0 / kNsPerMs, "ms")},
                    {"inputs", h.inputs},
                    {"outputs", h.outputs},
                    {"by_callback", h.by_callback},
                    {"by_latest_input", h.by_latest},
                    {"unlinked", h.unlinked},
                    {"unused_inputs", h.unused},
                    {"reused_inputs", h.reused}});
  }
  return {{"topics", p.topics},
          {"end", p.ends_at_take ? "take" : "publish"},
          {"sources", p.sources},
          {"reached", p.reached},
          {"stopped_at", p.stopped_at},
          {"end_to_end_ms", metrics::to_json(p.end_to_end, 1.0 / kNsPerMs, "ms")},
          {"hops", hops}};
}

}  // namespace

nlohmann::json to_json(const TraceAnalysis& a) {
  using nlohmann::json;
  json hops = json::array();
  for (const auto& h : a.hops) {
    hops.push_back({{"kind", h.kind},
                    {"node", h.node},
                    {"from", h.from},
                    {"to", h.to},
                    {"label", h.label()},
                    {"mean_start_offset_ms", h.mean_start_offset_ns / kNsPerMs},
                    {"duration_ms", metrics::to_json(h.duration, 1.0 / kNsPerMs, "ms")}});
  }
  json callbacks = json::array();
  for (const auto& cb : a.callbacks) {
    callbacks.push_back({{"node", cb.node},
                         {"source", cb.source},
                         {"symbol", cb.symbol},
                         {"duration_ms", metrics::to_json(cb.duration, 1.0 / kNsPerMs, "ms")}});
  }
  json topics = json::array();
  for (const auto& t : a.topics) {
    topics.push_back({{"topic", t.topic},
                      {"publisher", t.publisher},
                      {"subscriber", t.subscriber},
                      {"latency_ms", metrics::to_json(t.latency, 1.0 / kNsPerMs, "ms")}});
  }
  json controller_updates = json::array();
  for (const auto& u : a.controller_updates) {
    controller_updates.push_back({{"node", u.node},
                                  {"controller", u.controller},
                                  {"duration_us", metrics::to_json(u.duration, 1e-3, "us")}});
  }
  json tf2_calls = json::array();
  for (const auto& t : a.tf2_calls) {
    tf2_calls.push_back({{"node", t.node},
                         {"operation", t.operation},
                         {"duration_us", metrics::to_json(t.duration, 1e-3, "us")}});
  }
  json j = {{"trace",
             {{"folders", a.traces},
              {"streams", a.streams},
              {"packets", a.packets},
              {"events", a.events},
              {"discarded_events", a.discarded_events},
              {"lost_packets", a.lost_packets},
              {"defective_packets", a.defective_packets},
              {"packet_defects", a.packet_defects},
              {"duration_s", static_cast<double>(a.last_ns - a.first_ns) * 1e-9},
              {"analysis_s", a.read_seconds}}},
            {"hops", hops},
            {"callbacks", callbacks},
            {"topics", topics},
            {"controller_updates", controller_updates},
            {"tf2_calls", tf2_calls},
            {"tf2_share", a.tf2_share ? json{{"calls", a.tf2_share->calls},
                                             {"calls_per_message", a.tf2_share->calls_per_message},
                                             {"per_message_us", a.tf2_share->per_message_ns * 1e-3},
                                             {"of_latency", a.tf2_share->of_latency}}
                                      : json(nullptr)},
            {"unavailable", a.unavailable}};
  if (a.path) j["path"] = path_json(*a.path);
  return j;
}

std::string breakdown_table(const TraceAnalysis& a) {
  std::ostringstream out;
  char line[512];
  auto header = [&](const char* title) {
    std::snprintf(line, sizeof line, "%-58s %8s %9s %9s %9s %9s\n", title, "count", "mean", "p50",
                  "p99", "max");
    out << line;
  };
  auto row = [&](const std::string& name, const metrics::SampleStats& s) {
    std::snprintf(line, sizeof line, "%-58s %8zu %9s %9s %9s %9s\n", name.c_str(), s.count,
                  ms(s.mean).c_str(), ms(s.p50).c_str(), ms(s.p99).c_str(), ms(s.max).c_str());
    out << line;
  };
  if (a.path) {
    const PathLatency& p = *a.path;
    std::string name;
    for (const auto& t : p.topics) name += (name.empty() ? "" : " -> ") + t;
    out << "path " << name << "\n";
    out << "  messages of " << p.topics.front() << ": " << p.sources << ", reached "
        << p.topics.back() << " (" << (p.ends_at_take ? "taken" : "published")
        << "): " << p.reached;
    for (std::size_t i = 0; i < p.stopped_at.size(); ++i) {
      if (p.stopped_at[i] == 0) continue;
      out << "; went no further than " << p.topics[i] << ": " << p.stopped_at[i];
    }
    out << "\n";
    header("path latency (ms), first arrival of each message");
    row("end to end", p.end_to_end);
    for (const auto& h : p.hops) {
      row("transport " + h.from + " -> " + h.node, h.transport);
      row("node " + h.node + " -> " + h.to, h.in_node);
    }
    out << "  links per hop (outputs: in their input's callback / latest input / none; inputs "
           "unused / reused):\n";
    for (const auto& h : p.hops) {
      out << "    " << h.from << " -> " << h.to << ": " << h.outputs
          << " outputs: " << h.by_callback << " / " << h.by_latest << " / " << h.unlinked << "; "
          << h.inputs << " inputs: " << h.unused << " / " << h.reused << "\n";
    }
    out << "\n";
  }
  if (!a.hops.empty()) {
    header("per-hop breakdown (ms), along the path");
    for (const auto& h : a.hops) row(h.kind + "  " + h.label(), h.duration);
    out << "\n";
  }
  if (!a.callbacks.empty()) {
    header("callback durations (ms)");
    for (const auto& cb : a.callbacks) {
      row(cb.node + "  " + cb.source, cb.duration);
      if (!cb.symbol.empty()) out << "    " << short_symbol(cb.symbol) << "\n";
    }
    out << "\n";
  }
  if (!a.topics.empty()) {
    header("publish -> take (ms), rmw_publish to rmw_take");
    for (const auto& t : a.topics)
      row(t.topic + ": " + t.publisher + " -> " + t.subscriber, t.latency);
    out << "\n";
  }
  // Spans of microseconds: their own unit.
  auto us_row = [&](const std::string& name, const metrics::SampleStats& s) {
    auto us = [](double ns) { return fixed(ns / 1e3, 1); };
    std::snprintf(line, sizeof line, "%-58s %8zu %9s %9s %9s %9s\n", name.c_str(), s.count,
                  us(s.mean).c_str(), us(s.p50).c_str(), us(s.p99).c_str(), us(s.max).c_str());
    out << line;
  };
  if (!a.controller_updates.empty()) {
    header("controller update durations (us)");
    for (const auto& u : a.controller_updates) us_row(u.node + "  " + u.controller, u.duration);
    out << "\n";
  }
  if (!a.tf2_calls.empty()) {
    header("tf2 set and lookup durations (us)");
    for (const auto& t : a.tf2_calls) us_row(t.node + "  " + t.operation, t.duration);
    if (a.tf2_share) {
      const Tf2Share& s = *a.tf2_share;
      out << "tf2 share: " << fixed(100 * s.of_latency, 2) << " % of the end-to-end latency ("
          << fixed(s.per_message_ns / 1e3, 1) << " us of tf2 calls per message, "
          << fixed(s.calls_per_message, 1) << " calls)\n";
    }
    out << "\n";
  }
  if (!a.unavailable.empty()) {
    out << "not in this trace:\n";
    for (const auto& line_text : a.unavailable) out << "  " << line_text << "\n";
    out << "\n";
  }
  if (!a.packet_defects.empty()) {
    out << "defective packets, their events left out:\n";
    for (const auto& line_text : a.packet_defects) out << "  " << line_text << "\n";
    if (a.defective_packets > a.packet_defects.size())
      out << "  and " << a.defective_packets - a.packet_defects.size() << " more\n";
    out << "\n";
  }
  out << "trace: " << a.events << " events in " << a.streams << " streams, " << a.packets
      << " packets; discarded events " << a.discarded_events << ", lost packets " << a.lost_packets;
  if (a.defective_packets > 0) out << ", defective packets " << a.defective_packets;
  out << "; analysed in " << fixed(a.read_seconds, 3) << " s\n";
  return out.str();
}

std::string analysis_summary(const TraceAnalysis& a) {
  std::ostringstream out;
  if (a.run) {
    const RunInfo& r = *a.run;
    out << r.benchmark << " · " << r.rmw << " · grey-box (trace) · process " << r.pid;
    if (r.processes.size() > 1) out << " + " << r.processes.size() - 1 << " node processes";
    out << "\n";
    out << "messages: sent " << a.sent << " (warm-up " << r.warmup << "), measured " << a.measured
        << ", matched " << a.matched << ", lost " << a.lost << " (" << fixed(a.loss_percent, 2)
        << " %)";
    if (a.duplicates) out << ", duplicates " << a.duplicates;
    if (a.repeats) out << ", state repeats " << a.repeats;
    if (a.unknown) out << ", unknown " << a.unknown;
    if (a.unobserved) out << ", unobserved " << a.unobserved << " (trace events discarded)";
    out << "\n\n";
    char line[256];
    std::snprintf(line, sizeof line, "%-24s %9s %9s %9s %9s %9s %9s %9s %9s\n", "latency (ms)",
                  "min", "mean", "rms", "p50", "p90", "p99", "p99.9", "max");
    out << line;
    auto row = [&](const char* name, const metrics::SampleStats& s) {
      std::snprintf(line, sizeof line, "%-24s %9s %9s %9s %9s %9s %9s %9s %9s\n", name,
                    ms(s.min).c_str(), ms(s.mean).c_str(), ms(s.rms).c_str(), ms(s.p50).c_str(),
                    ms(s.p90).c_str(), ms(s.p99).c_str(), ms(s.p999).c_str(), ms(s.max).c_str());
      out << line;
    };
    row("from scheduled send", a.latency_from_scheduled);
    row("from actual send", a.latency_from_sent);
    row("send lateness", a.send_lateness);
    out << "\nthroughput: " << fixed(a.throughput_hz, 3) << " Hz out, "
        << fixed(a.offered_rate_hz, 3) << " Hz offered\n\n";
  } else {
    out << "no robotperf run in this trace: callback durations and publish -> take latencies "
           "only\n\n";
  }
  out << breakdown_table(a);
  out << "result: " << (a.valid ? "VALID" : "INVALID");
  for (std::size_t i = 0; i < a.invalid_reasons.size(); ++i) {
    out << (i == 0 ? " — " : "; ") << a.invalid_reasons[i];
  }
  out << "\n";
  return out.str();
}

}  // namespace robotperf::tracing
