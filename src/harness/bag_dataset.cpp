// DataLoader for rosbag2 bags: the benchmark's input topics, undecoded, in memory.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <span>

#include "robotperf/bag/bag.hpp"
#include "robotperf/harness/benchmark_spec.hpp"
#include "robotperf/harness/dataset.hpp"
#include "robotperf/msgs/definitions.hpp"
#include "robotperf/msgs/dynamic.hpp"
#include "robotperf/msgs/known_types.hpp"
#include "robotperf/msgs/serialized_message.hpp"
#include "robotperf/plugin/content_hash.hpp"

namespace robotperf::harness {
namespace {

constexpr const char* kHeaderType = "std_msgs/msg/Header";

// Whether `topic`'s type starts with a std_msgs/Header: from the bag's own
// definition when it has one, else from the types compiled into robotperf.
bool starts_with_header(const bag::TopicInfo& topic) {
  std::string schema = topic.definition_encoding == "ros2msg" ? topic.definition : "";
  if (schema.empty()) schema = msgs::ros2msg_schema(topic.type).value_or("");
  if (!schema.empty()) {
    msgs::dynamic::TypeRegistry registry;
    registry.add_ros2msg(topic.type, schema);
    const auto& fields = registry.get(topic.type).fields;
    return !fields.empty() && fields[0].type.primitive == msgs::dynamic::Primitive::kMessage &&
           fields[0].type.message_type == kHeaderType &&
           fields[0].type.array == msgs::dynamic::ArrayKind::kNone;
  }
  bool stamped = false;
  if (!msgs::with_message_type(topic.type,
                               [&]<class T>() { stamped = msgs::type_support<T>().stamped(); })) {
    throw BenchmarkError("topic " + topic.name + ": the bag has no definition of " + topic.type +
                         ", so whether it starts with a std_msgs/Header is unknown");
  }
  return stamped;
}

// Decodes payloads of one bag topic fully, to find corrupt ones: with robotperf's codec for the
// types it has, else with the bag's own definition; a type with neither is not checked.
class PayloadCheck {
 public:
  explicit PayloadCheck(const bag::TopicInfo& topic) : type_(topic.type) {
    msgs::with_message_type(topic.type, [&]<class T>() {
      decode_ = [](std::span<const uint8_t> payload) {
        T msg;
        msgs::type_support<T>().deserialize(payload, &msg);
      };
    });
    if (!decode_ && topic.definition_encoding == "ros2msg") {
      registry_ = std::make_shared<msgs::dynamic::TypeRegistry>();
      registry_->add_ros2msg(topic.type, topic.definition);
      decode_ = [registry = registry_, type = type_](std::span<const uint8_t> payload) {
        (void)msgs::dynamic::decode(*registry, type, payload);
      };
    }
  }
  // Throws msgs::CdrError for a payload that does not decode.
  void check(std::span<const uint8_t> payload) const {
    if (decode_) decode_(payload);
  }

 private:
  std::string type_;
  std::shared_ptr<msgs::dynamic::TypeRegistry> registry_;
  std::function<void(std::span<const uint8_t>)> decode_;
};

struct Recorded {
  int64_t time_ns;   // bag timestamp (reception time)
  int64_t stamp_ns;  // header.stamp
  std::shared_ptr<msgs::SerializedMessage> payload;
};

// One time of the replay: a message of every input, with equal header stamps.
struct Frame {
  int64_t time_ns;
  std::vector<const Recorded*> parts;
};

// The bag topic each input is fed from (remapped as --remap says), each checked to be CDR, of
// the input's type and stamped.
std::vector<const bag::TopicInfo*> choose_sources(const BagSelection& selection,
                                                  const bag::BagInfo& info,
                                                  const std::vector<BoundaryTopic>& inputs) {
  const std::string path = selection.path.string();
  auto benchmark_topic = [&](const std::string& bag_topic) {
    auto it = selection.remaps.find(bag_topic);
    return it == selection.remaps.end() ? bag_topic : it->second;
  };
  for (const auto& remap : selection.remaps) {
    const std::string& from = remap.first;
    if (std::none_of(info.topics.begin(), info.topics.end(),
                     [&](const bag::TopicInfo& t) { return t.name == from; })) {
      throw BenchmarkError("--remap " + from + ":=" + remap.second + ": bag " + path +
                           " has no topic " + from);
    }
  }
  std::vector<const bag::TopicInfo*> sources;
  for (const auto& input : inputs) {
    const bag::TopicInfo* source = nullptr;
    for (const auto& t : info.topics) {
      if (benchmark_topic(t.name) != input.topic) continue;
      if (source != nullptr) {
        throw BenchmarkError("bag " + path + ": topics " + source->name + " and " + t.name +
                             " both map onto input " + input.topic);
      }
      source = &t;
    }
    if (source == nullptr) {
      std::string names;
      for (const auto& t : info.topics) names += (names.empty() ? "" : ", ") + t.name;
      throw BenchmarkError("bag " + path + " has nothing for input " + input.topic + " (" +
                           input.type + "); its topics: " + names +
                           "; map one onto it with --remap <bag topic>:=" + input.topic);
    }
    if (source->serialization_format != "cdr") {
      throw BenchmarkError("bag topic " + source->name + " is serialized as '" +
                           source->serialization_format +
                           "': robotperf replays CDR only (rosbag2's default format)");
    }
    if (!starts_with_header(*source)) {
      throw BenchmarkError("bag topic " + source->name + ": type " + source->type +
                           " does not start with a std_msgs/Header, so its messages cannot "
                           "carry message IDs; only stamped types can be replayed");
    }
    if (source->type != input.type) {
      throw BenchmarkError("bag topic " + source->name + " holds " + source->type + ", but input " +
                           input.topic + " expects " + input.type);
    }
    sources.push_back(source);
  }
  return sources;
}

// The sources' messages in the selected window, per input, the bytes as recorded. Every message
// is decoded once here, before timing, as the subscribers will decode it: one that cannot be
// would be dropped by the graph's first node and counted as lost. Those are left out, and
// `corrupt` (when given) gets a line per input that had any.
std::vector<std::vector<Recorded>> read_recorded(const BagSelection& selection,
                                                 const bag::BagInfo& info,
                                                 const std::vector<const bag::TopicInfo*>& sources,
                                                 std::vector<std::string>* corrupt) {
  bag::ReadOptions read;
  for (const auto* source : sources) read.topics.insert(source->name);
  if (selection.start_s) {
    read.start_time_ns = info.starting_time_ns + std::llround(*selection.start_s * 1e9);
  }
  if (selection.end_s) {
    read.end_time_ns = info.starting_time_ns + std::llround(*selection.end_s * 1e9);
  }
  std::map<std::string, std::size_t> input_of_topic;
  for (std::size_t i = 0; i < sources.size(); ++i) input_of_topic[sources[i]->name] = i;
  std::vector<std::vector<Recorded>> recorded(sources.size());
  std::vector<PayloadCheck> checks;
  for (const auto* source : sources) checks.emplace_back(*source);
  struct Corrupt {
    std::size_t count = 0;
    int64_t first_ns = 0;
    std::string why;
  };
  std::vector<Corrupt> corrupted(sources.size());
  bag::Reader reader(selection.path, read);
  bag::Message m;
  while (reader.next(m)) {
    const bag::TopicInfo& topic = reader.topics()[m.topic];
    const std::size_t i = input_of_topic.at(topic.name);
    int64_t stamp = 0;
    try {
      stamp = msgs::read_header_stamp_ns(m.data);
      checks[i].check(m.data);
    } catch (const msgs::CdrError& e) {
      if (corrupted[i].count++ == 0) {
        corrupted[i].first_ns = m.timestamp_ns;
        corrupted[i].why = e.what();
      }
      continue;
    }
    auto payload = std::make_shared<msgs::SerializedMessage>();
    payload->cdr = std::move(m.data);
    recorded[i].push_back({m.timestamp_ns, stamp, std::move(payload)});
  }
  for (std::size_t i = 0; i < sources.size(); ++i) {
    if (corrupted[i].count == 0 || corrupt == nullptr) continue;
    char first[64];
    std::snprintf(first, sizeof first, "%.9f", static_cast<double>(corrupted[i].first_ns) * 1e-9);
    corrupt->push_back(
        "bag " + selection.path.string() + ": " + std::to_string(corrupted[i].count) + " message" +
        (corrupted[i].count == 1 ? "" : "s") + " on " + sources[i]->name + " do not decode as " +
        sources[i]->type + " (the first at " + first + " s: " + corrupted[i].why +
        "); left out of the replay, neither sent nor counted as lost");
  }
  return recorded;
}

// Frames: the first input's messages in order, joined by equal header stamps with one unused
// message of every other input, in the order they were recorded.
std::vector<Frame> join_frames(const std::vector<std::vector<Recorded>>& recorded) {
  const std::size_t inputs = recorded.size();
  std::vector<std::multimap<int64_t, const Recorded*>> by_stamp(inputs);
  for (std::size_t i = 1; i < inputs; ++i) {
    for (const auto& r : recorded[i]) by_stamp[i].emplace(r.stamp_ns, &r);
  }
  std::vector<Frame> frames;
  for (const auto& first : recorded[0]) {
    Frame f{first.time_ns, {&first}};
    for (std::size_t i = 1; i < inputs && f.parts.size() == i; ++i) {
      auto it = by_stamp[i].find(first.stamp_ns);
      if (it == by_stamp[i].end()) break;
      f.time_ns = std::min(f.time_ns, it->second->time_ns);
      f.parts.push_back(it->second);
      by_stamp[i].erase(it);
    }
    if (f.parts.size() == inputs) frames.push_back(std::move(f));
  }
  std::stable_sort(frames.begin(), frames.end(),
                   [](const Frame& a, const Frame& b) { return a.time_ns < b.time_ns; });
  return frames;
}

}  // namespace

Dataset load_bag_dataset(const BagSelection& selection, const std::vector<BoundaryTopic>& inputs,
                         std::vector<std::string>* corrupt) {
  const std::string path = selection.path.string();
  if (inputs.empty()) throw BenchmarkError("a benchmark without inputs cannot replay bag " + path);
  // From a Reader, not read_info(): ROS 2 keeps the definitions the checks below judge types by in
  // the storage (MCAP schemas, sqlite3 message_definitions), not in metadata.yaml.
  const bag::BagInfo info = bag::Reader(selection.path).info();
  const std::vector<const bag::TopicInfo*> sources = choose_sources(selection, info, inputs);
  const std::vector<std::vector<Recorded>> recorded =
      read_recorded(selection, info, sources, corrupt);
  const std::vector<Frame> frames = join_frames(recorded);
  if (frames.empty()) {
    std::string topics;
    for (const auto* s : sources) topics += (topics.empty() ? "" : ", ") + s->name;
    throw BenchmarkError("bag " + path + " has no complete frame" +
                         (inputs.size() > 1
                              ? " (messages of " + topics + " with equal header stamps)"
                              : " on " + topics) +
                         (selection.start_s || selection.end_s ? " in the selected window" : ""));
  }

  Dataset d;
  d.name = path;
  d.description = "rosbag2 " + bag::to_string(info.storage) + " bag " + path;
  d.frames = frames.size();
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    DatasetStream s{
        inputs[i].stream, sources[i]->name, &msgs::serialized_type_support(sources[i]->type), {}};
    s.messages.reserve(frames.size());
    for (const auto& f : frames) s.messages.push_back(f.parts[i]->payload);
    d.streams.push_back(std::move(s));
  }
  for (const auto& f : frames) d.frame_times_ns.push_back(f.time_ns);
  const int64_t span = d.frame_times_ns.back() - d.frame_times_ns.front();
  d.rate_hz =
      span > 0 ? static_cast<double>(frames.size() - 1) * 1e9 / static_cast<double>(span) : 0.0;
  // The frames' times from the first are part of the data: --rate bag replays them, and bags
  // with the same messages at other times are other workloads.
  plugin::Fnv1a64 hash;
  hash.add_string(content_hash(d.streams));
  for (const int64_t t : d.frame_times_ns)
    hash.add_u64(static_cast<uint64_t>(t - d.frame_times_ns.front()));
  d.hash = hash.hex_digest();
  return d;
}

}  // namespace robotperf::harness
