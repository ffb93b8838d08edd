// The MCAP reader on arbitrary files: it either reads messages or throws BagError.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>

#include "robotperf/bag/bag.hpp"

namespace {

// The reader works on files: each input goes to one per-process scratch file.
const std::filesystem::path& scratch_file() {
  static const std::filesystem::path path =
      std::filesystem::temp_directory_path() /
      ("robotperf-fuzz-" + std::to_string(getpid()) + ".mcap");
  return path;
}

void read_all(const robotperf::bag::ReadOptions& options) {
  try {
    auto reader = robotperf::bag::open_mcap(scratch_file(), options);
    (void)reader->topics();
    robotperf::bag::Message m;
    while (reader->next(m)) {
    }
  } catch (const robotperf::bag::BagError&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::FILE* f = std::fopen(scratch_file().c_str(), "wb");
  if (f == nullptr) return 0;
  std::fwrite(data, 1, size, f);
  std::fclose(f);
  read_all({});
  // Without CRC checks, corrupt chunks reach the decompressors and parsers.
  robotperf::bag::ReadOptions unchecked;
  unchecked.verify_crc = false;
  read_all(unchecked);
  return 0;
}
