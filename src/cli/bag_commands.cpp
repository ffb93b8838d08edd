#include "bag_commands.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <iostream>
#include <set>
#include <sstream>
#include <stdexcept>

#include "robotperf/bag/bag.hpp"
#include "robotperf/bag/qos.hpp"
#include "robotperf/cli/exit_codes.hpp"
#include "robotperf/harness/dataset.hpp"
#include "robotperf/msgs/definitions.hpp"
#include "robotperf/msgs/dynamic.hpp"

namespace robotperf::cli {
namespace {

namespace fs = std::filesystem;

std::string human_bytes(uint64_t n) {
  const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB"};
  double v = static_cast<double>(n);
  int u = 0;
  while (v >= 1024 && u < 4) {
    v /= 1024;
    ++u;
  }
  char buf[32];
  std::snprintf(buf, sizeof(buf), u ? "%.1f %s" : "%.0f %s", v, units[u]);
  return buf;
}

std::string seconds(int64_t ns) {
  char buf[48];
  std::snprintf(buf, sizeof(buf), "%lld.%09lld", static_cast<long long>(ns / 1'000'000'000),
                static_cast<long long>(ns % 1'000'000'000));
  return buf;
}

std::string utc_time(int64_t ns) {
  const std::time_t t = static_cast<std::time_t>(ns / 1'000'000'000);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[64];
  std::strftime(buf, sizeof(buf), "%Y-%m-%d %H:%M:%S", &tm);
  return std::string(buf) + " UTC (" + seconds(ns) + ")";
}

std::string qos_summary(const std::string& yaml) {
  if (yaml.empty()) return "none recorded";
  try {
    std::string out;
    for (const auto& p : bag::parse_qos_profiles(yaml))
      out += (out.empty() ? "" : "; ") + bag::describe_qos(p);
    return out.empty() ? "none recorded" : out;
  } catch (const std::invalid_argument& e) {
    return std::string("unreadable (") + e.what() + ")";
  }
}

}  // namespace

int bag_info(const std::string& path, bool verify) {
  const bag::BagInfo info = bag::read_info(path);
  std::string files;
  for (const auto& f : info.files) files += (files.empty() ? "" : ", ") + f.path.string();
  std::cout << "Files:             " << files << "\n"
            << "Bag size:          " << human_bytes(info.bytes) << "\n"
            << "Storage id:        " << bag::to_string(info.storage) << "\n";
  if (info.metadata_version) std::cout << "Metadata version:  " << info.metadata_version << "\n";
  if (!info.ros_distro.empty()) std::cout << "ROS distro:        " << info.ros_distro << "\n";
  if (!info.compression_format.empty())
    std::cout << "Compression:       " << info.compression_format << " (" << info.compression_mode
              << ")\n";
  std::cout << "Duration:          " << seconds(info.duration_ns) << " s\n"
            << "Start:             " << utc_time(info.starting_time_ns) << "\n"
            << "End:               " << utc_time(info.starting_time_ns + info.duration_ns) << "\n"
            << "Messages:          " << info.message_count << "\n"
            << "Topics:            " << info.topics.size() << "\n";
  std::size_t width = 0;
  for (const auto& t : info.topics) width = std::max(width, t.name.size());
  for (const auto& t : info.topics) {
    std::printf("  %-*s  %8llu msgs  %s  [%s]  QoS: %s\n", static_cast<int>(width), t.name.c_str(),
                static_cast<unsigned long long>(t.message_count), t.type.c_str(),
                t.serialization_format.c_str(), qos_summary(t.offered_qos_profiles).c_str());
  }
  if (!verify) return kExitOk;
  std::cout.flush();
  const std::vector<std::string> disagreements = bag::verify(path);
  for (const auto& line : disagreements) std::cerr << "robotperf: " << path << ": " << line << "\n";
  if (!disagreements.empty()) {
    // What to do depends on what stated the wrong thing: metadata.yaml, or the file's summary.
    std::cerr << "robotperf: " << path
              << ": the storage does not hold what the bag states: it may be damaged or cut short, "
              << (info.metadata_version > 0
                      ? "or its metadata.yaml stale (if the storage is whole, moving metadata.yaml "
                        "away and running `robotperf bag reindex` writes it anew)\n"
                      : "or its summary wrong (if the messages are whole, `robotperf bag convert` "
                        "writes a copy whose summary matches them)\n");
    return kExitUsage;
  }
  std::cout << "Verified:          every message read; counts and times agree\n";
  return kExitOk;
}

int bag_echo(const std::string& path, const EchoOptions& options) {
  bag::ReadOptions read;
  read.topics.insert(options.topics.begin(), options.topics.end());
  bag::Reader reader(path, read);
  for (const auto& t : options.topics) {
    if (std::none_of(reader.topics().begin(), reader.topics().end(),
                     [&](const bag::TopicInfo& b) { return b.name == t; })) {
      throw bag::BagError(path + ": has no topic " + t);
    }
  }
  msgs::dynamic::TypeRegistry registry;
  for (const auto& dir : options.msg_dirs) registry.add_directory(dir);
  for (const auto& t : reader.topics()) {
    // An empty ros2msg text is a definition too: a type without fields (std_msgs/msg/Empty).
    if (t.definition_encoding == "ros2msg") {
      try {
        registry.add_ros2msg(t.type, t.definition);
      } catch (const msgs::dynamic::DefinitionError& e) {
        throw bag::BagError(path + ": the definition of " + t.name +
                            "'s type stored in the bag: " + e.what());
      }
    } else if (auto builtin = msgs::ros2msg_schema(t.type); builtin && !registry.contains(t.type)) {
      registry.add_ros2msg(t.type, *builtin);
    }
    registry.adopt(t.type);
  }
  bag::Message m;
  std::size_t printed = 0;
  std::set<std::size_t> warned;
  while ((!options.limit || printed < *options.limit) && reader.next(m)) {
    const bag::TopicInfo& topic = reader.topics()[m.topic];
    if (topic.serialization_format != "cdr") {
      throw bag::BagError(path + ": topic " + topic.name + " is serialized as '" +
                          topic.serialization_format + "': robotperf decodes CDR only");
    }
    msgs::dynamic::Value value;
    try {
      value = msgs::dynamic::decode(registry, topic.type, m.data);
      // A definition that leaves bytes over is not the one the message was written with (CDR
      // pads to 4 at most): say so once per topic rather than print misread fields silently.
      const std::size_t used = msgs::dynamic::encode(registry, topic.type, value).size();
      if (m.data.size() >= used + 4 && warned.insert(m.topic).second) {
        std::cerr << "robotperf: warning: " << topic.name << ": the definition of " << topic.type
                  << " accounts for " << used << " of the " << m.data.size()
                  << " bytes of its messages; it is probably not the type they were written "
                     "with, and the fields below may be misread\n";
      }
    } catch (const msgs::dynamic::DefinitionError& e) {
      throw msgs::dynamic::DefinitionError(std::string(e.what()) + "; the bag carries none for " +
                                           topic.name + ", pass --msg-dir with its .msg files");
    } catch (const msgs::CdrError& e) {
      throw bag::BagError(path + ": message on " + topic.name + " at " + seconds(m.timestamp_ns) +
                          " does not decode as " + topic.type + ": " + e.what());
    }
    std::cout << "--- " << topic.name << " [" << topic.type << "] at " << seconds(m.timestamp_ns)
              << "\n"
              << msgs::dynamic::to_yaml(value, options.max_array);
    ++printed;
  }
  return 0;
}

int bag_convert(const std::string& in, const std::string& out, const ConvertOptions& options) {
  bag::WriteOptions w;
  w.storage = bag::storage_from_string(options.storage);
  w.compression = bag::compression_from_string(options.compression);
  w.chunk_size = options.chunk_size;
  // 2^44 MiB is 2^64 bytes, beyond the writer's byte count; NaN fails both comparisons.
  constexpr double kMaxFileMib = 17592186044416.0;
  if (!(options.max_file_mib >= 0 && options.max_file_mib < kMaxFileMib)) {
    std::ostringstream got;
    got << options.max_file_mib;
    throw std::invalid_argument(
        "--max-file-size: must be a number of MiB, 0 (one file) or more, under 2^44 (got " +
        got.str() + ")");
  }
  // Rounded up, so that a size below a byte still splits rather than meaning one file.
  w.max_file_bytes = static_cast<uint64_t>(std::ceil(options.max_file_mib * 1024 * 1024));
  // Topics the bag carries no definition for get robotperf's, or one from --msg-dir, so that the
  // converted bag can be decoded; those for which none is found are named.
  msgs::dynamic::TypeRegistry registry;
  for (const auto& dir : options.msg_dirs) registry.add_directory(dir);
  std::set<std::string> undefined;
  const auto complete = [&](bag::TopicInfo& topic) {
    if (!topic.definition_encoding.empty()) return;
    if (auto builtin = msgs::ros2msg_schema(topic.type)) {
      topic.definition_encoding = "ros2msg";
      topic.definition = *builtin;
      return;
    }
    registry.adopt(topic.type);
    try {
      topic.definition = registry.ros2msg_schema(topic.type);
      topic.definition_encoding = "ros2msg";
    } catch (const msgs::dynamic::DefinitionError&) {
      undefined.insert(topic.type + " (" + topic.name + ")");
    }
  };
  const uint64_t n = bag::convert(in, out, w, complete);
  for (const auto& what : undefined) {
    std::cerr << "robotperf: warning: no definition of " << what
              << " in the bag, in robotperf or under --msg-dir: it is written as 'unknown', and "
                 "readers cannot decode its messages without the .msg files\n";
  }
  std::cout << "wrote " << n << " messages to " << out << " (" << bag::to_string(w.storage)
            << (w.storage == bag::Storage::kMcap ? ", " + bag::to_string(w.compression) : "")
            << ")\n";
  return 0;
}

int bag_reindex(const std::string& dir) {
  const bag::BagInfo info = bag::reindex(dir);
  std::cout << "wrote " << (fs::path(dir) / "metadata.yaml").string() << ": " << info.files.size()
            << " file" << (info.files.size() == 1 ? "" : "s") << ", " << info.topics.size()
            << " topic" << (info.topics.size() == 1 ? "" : "s") << ", " << info.message_count
            << " messages\n";
  return 0;
}

int dataset_generate(const std::string& name, const GenerateOptions& options) {
  const harness::Dataset dataset = harness::load_dataset(name);
  std::string out = options.out;
  if (out.empty()) {
    out = name;
    std::replace(out.begin(), out.end(), '/', '_');
  }
  bag::WriteOptions w;
  w.storage = bag::storage_from_string(options.storage);
  w.compression = bag::compression_from_string(options.compression);
  bag::Writer writer(out, w);
  // A ROS 2 default publisher: keep last 10, reliable, volatile.
  bag::QosProfile qos;
  qos.history = 1;
  qos.depth = 10;
  qos.reliability = 1;
  qos.durability = 2;
  qos.liveliness = 1;
  std::vector<std::size_t> ids;
  for (const auto& s : dataset.streams) {
    bag::TopicInfo t;
    t.name = s.topic;
    t.type = s.type->ros_type;
    t.offered_qos_profiles = bag::qos_profiles_to_yaml({qos});
    t.definition_encoding = "ros2msg";
    t.definition = msgs::ros2msg_schema(t.type).value_or("");
    ids.push_back(writer.add_topic(t));
  }
  // Frame k is recorded, and stamped, k periods after a fixed epoch: the bag
  // is the same on every machine and looks like a live recording.
  const int64_t period_ns = static_cast<int64_t>(1e9 / dataset.rate_hz);
  const int64_t epoch_ns = 1'700'000'000'000'000'000;
  std::vector<uint8_t> buffer;
  for (std::size_t k = 0; k < dataset.frames; ++k) {
    const int64_t time_ns = epoch_ns + static_cast<int64_t>(k) * period_ns;
    for (std::size_t i = 0; i < dataset.streams.size(); ++i) {
      const auto& s = dataset.streams[i];
      std::shared_ptr<const void> msg = s.messages[k];
      if (s.type->stamped()) msg = s.type->copy_with_stamp_ns(msg.get(), time_ns);
      buffer.resize(s.type->serialized_size(msg.get()));
      s.type->serialize(msg.get(), buffer);
      writer.write(ids[i], time_ns, buffer);
    }
  }
  writer.close();
  std::cout << "wrote " << dataset.name << " (" << dataset.frames << " frames, "
            << dataset.streams.size() << " topics) to " << out << "\n";
  return 0;
}

}  // namespace robotperf::cli
