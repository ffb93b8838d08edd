#include "robotperf/harness/dataset.hpp"

#include <mutex>
#include <stdexcept>
#include <utility>

#include "robotperf/plugin/content_hash.hpp"
#include "robotperf/plugin/registry.hpp"

namespace robotperf::harness {
namespace {

// What a generator produced, checked against its description: a plug-in's mistake is reported
// naming it, never played as data of another shape.
void check_generated(const plugin::DatasetEntry& entry, const std::vector<DatasetStream>& streams) {
  const auto& info = entry.info;
  const std::string who = "dataset " + info.name + " (" + entry.origin + ")";
  if (streams.size() != info.streams.size()) {
    throw std::runtime_error(who + " generated " + std::to_string(streams.size()) +
                             " streams, its description has " +
                             std::to_string(info.streams.size()));
  }
  for (std::size_t i = 0; i < streams.size(); ++i) {
    const auto& s = streams[i];
    const auto& declared = info.streams[i];
    if (s.name != declared.name || s.type == nullptr || s.type->ros_type != declared.type) {
      throw std::runtime_error(who + " generated stream " + std::to_string(i) + " as '" + s.name +
                               "' (" + (s.type ? s.type->ros_type : std::string("no type")) +
                               "), its description says '" + declared.name + "' (" + declared.type +
                               ")");
    }
    if (s.messages.size() != streams.front().messages.size()) {
      throw std::runtime_error(who + " generated " + std::to_string(s.messages.size()) +
                               " messages on stream " + s.name + " but " +
                               std::to_string(streams.front().messages.size()) + " on " +
                               streams.front().name + ": every stream has one per frame");
    }
    for (const auto& m : s.messages) {
      if (!m) throw std::runtime_error(who + " generated an empty message on stream " + s.name);
    }
  }
  if (streams.front().messages.empty()) throw std::runtime_error(who + " generated no frame");
}

std::string workload_owner(const plugin::DatasetInfo& info) {
  return "dataset " + info.name + " workload";
}

// The workload read against the dataset's declarations, each value within its bounds and the
// values together within the dataset's limits.
plugin::Parameters checked_workload(const plugin::DatasetInfo& info,
                                    const std::map<std::string, std::string>& workload) {
  plugin::Parameters parameters(info.workload, workload, workload_owner(info));
  if (info.check_workload) {
    try {
      info.check_workload(parameters);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(workload_owner(info) + ": " + e.what());
    }
  }
  return parameters;
}

Dataset generate(const plugin::DatasetEntry& entry,
                 const std::map<std::string, std::string>& workload) {
  const auto& info = entry.info;
  const plugin::Parameters parameters = checked_workload(info, workload);
  Dataset d;
  d.streams = entry.generate(parameters);
  check_generated(entry, d.streams);
  d.name = info.name;
  d.description = info.description;
  d.rate_hz = info.rate_hz;
  d.frames = d.streams.front().messages.size();
  d.parameters = parameters.effective();
  d.hash = content_hash(d.streams);
  return d;
}

const plugin::DatasetEntry& find_dataset(const std::string& name) {
  const plugin::DatasetEntry* entry = plugin::registry().find_dataset(name);
  if (entry == nullptr) {
    throw std::invalid_argument("unknown dataset '" + name + "' (registered: " +
                                plugin::names_of(plugin::registry().datasets()) + ")");
  }
  return *entry;
}

}  // namespace

std::string content_hash(const std::vector<DatasetStream>& streams) {
  plugin::Fnv1a64 hash;
  std::vector<uint8_t> buffer;
  for (const auto& s : streams) {
    hash.add_string(s.name).add_string(s.type->ros_type);
    for (const auto& m : s.messages) {
      buffer.resize(s.type->serialized_size(m.get()));
      s.type->serialize(m.get(), buffer);
      hash.add_bytes(buffer);
    }
  }
  return hash.hex_digest();
}

void check_workload(const std::string& name, const std::map<std::string, std::string>& workload) {
  checked_workload(find_dataset(name).info, workload);
}

Dataset load_dataset(const std::string& name, const std::map<std::string, std::string>& workload) {
  const plugin::DatasetEntry* entry = &find_dataset(name);
  // Generated datasets are immutable and take seconds to render: a process that runs a benchmark
  // again (tests, sweeps) reuses them.
  static std::mutex mutex;
  static std::map<std::string, Dataset> cache;
  std::lock_guard lock(mutex);
  std::string key = name;
  for (const auto& [k, v] : workload) key += "\n" + k + "=" + v;
  if (auto it = cache.find(key); it != cache.end()) return it->second;
  return cache.emplace(key, generate(*entry, workload)).first->second;
}

}  // namespace robotperf::harness
