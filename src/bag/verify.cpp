// `bag info --verify`: what a bag's storage holds, read message by message, against what its
// metadata.yaml (or a lone storage file's summary) states.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <map>

#include "robotperf/bag/bag.hpp"

namespace robotperf::bag {
namespace {

std::string seconds(int64_t ns) {
  char text[48];
  std::snprintf(text, sizeof(text), "%s%lld.%09lld s", ns < 0 ? "-" : "",
                static_cast<long long>(std::abs(ns / 1'000'000'000)),
                static_cast<long long>(std::abs(ns % 1'000'000'000)));
  return text;
}

std::string messages(uint64_t n) {
  return std::to_string(n) + (n == 1 ? " message" : " messages");
}

}  // namespace

std::vector<std::string> verify(const std::filesystem::path& path) {
  const BagInfo stated = read_info(path);
  const std::string source =
      stated.metadata_version > 0 ? "metadata.yaml" : "the storage file's own summary";
  std::map<std::string, uint64_t> counted;  // by topic name
  uint64_t total = 0;
  int64_t first_ns = 0;
  int64_t last_ns = 0;
  try {
    Reader reader(path);
    Message m;
    while (reader.next(m)) {
      ++counted[reader.topics()[m.topic].name];
      first_ns = total == 0 ? m.timestamp_ns : std::min(first_ns, m.timestamp_ns);
      last_ns = total == 0 ? m.timestamp_ns : std::max(last_ns, m.timestamp_ns);
      ++total;
    }
  } catch (const BagError& e) {
    // Counts and times read up to here would only restate that the rest is missing.
    return {"the storage is unreadable after " + messages(total) + " (" + source + " says " +
            std::to_string(stated.message_count) + "): " + e.what()};
  }

  std::vector<std::string> disagreements;
  for (const TopicInfo& topic : stated.topics) {
    const auto found = counted.find(topic.name);
    const uint64_t held = found == counted.end() ? 0 : found->second;
    if (held != topic.message_count) {
      disagreements.push_back("topic " + topic.name + ": " + source + " says " +
                              messages(topic.message_count) + ", the storage holds " +
                              std::to_string(held));
    }
    if (found != counted.end()) counted.erase(found);
  }
  for (const auto& [name, held] : counted) {
    disagreements.push_back("topic " + name + ": the storage holds " + messages(held) + ", " +
                            source + " does not list the topic");
  }
  if (total != stated.message_count) {
    disagreements.push_back("total: " + source + " says " + messages(stated.message_count) +
                            ", the storage holds " + std::to_string(total));
  }
  if (total > 0 && first_ns != stated.starting_time_ns) {
    disagreements.push_back("start: " + source + " says " + seconds(stated.starting_time_ns) +
                            ", the first message is at " + seconds(first_ns));
  }
  const int64_t stated_end_ns = stated.starting_time_ns + stated.duration_ns;
  if (total > 0 && last_ns != stated_end_ns) {
    disagreements.push_back("end: " + source + " says " + seconds(stated_end_ns) +
                            " (start + duration), the last message is at " + seconds(last_ns));
  }
  return disagreements;
}

}  // namespace robotperf::bag
