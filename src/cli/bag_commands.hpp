// The `bag` and `dataset generate` verbs of the robotperf command.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace robotperf::cli {

// Like `ros2 bag info`: storage, files, duration, per-topic counts, types, QoS. With `verify`,
// also reads every message and reports, one line each, where the storage disagrees with what
// metadata.yaml states: kExitUsage when it does.
int bag_info(const std::string& path, bool verify);

struct EchoOptions {
  std::vector<std::string> topics;    // empty: all
  std::optional<std::size_t> limit;   // messages to print
  std::vector<std::string> msg_dirs;  // .msg folders for types the bag has no definition of
  std::size_t max_array = 64;         // longer arrays are summarised
};
int bag_echo(const std::string& path, const EchoOptions& options);

struct ConvertOptions {
  std::string storage = "mcap";
  std::string compression = "zstd";
  std::size_t chunk_size = 4 * 1024 * 1024;
  double max_file_mib = 0;
  std::vector<std::string> msg_dirs;  // .msg files for types the bag has no definition of
};
int bag_convert(const std::string& in, const std::string& out, const ConvertOptions& options);
// `bag reindex <dir>`: metadata.yaml for a bag directory without one.
int bag_reindex(const std::string& dir);

struct GenerateOptions {
  std::string out;  // default: the dataset name with '/' replaced by '_'
  std::string storage = "mcap";
  std::string compression = "zstd";
};
int dataset_generate(const std::string& name, const GenerateOptions& options);

}  // namespace robotperf::cli
