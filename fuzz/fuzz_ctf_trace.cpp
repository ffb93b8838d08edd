// The CTF reader and the grey-box analysis on arbitrary traces. The input is a 4-byte
// little-endian length, that many bytes of metadata (text or packetised), and one stream file.
// analyze_trace either analyses or throws CtfError (unreadable) or invalid_argument (no trace).
#include <cstdint>
#include <cstring>
#include <stdexcept>

#include "fuzz_scratch.hpp"
#include "robotperf/tracing/analysis.hpp"
#include "robotperf/tracing/ctf.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  namespace fz = robotperf::fuzz;
  if (size < 4) return 0;
  uint32_t metadata_size = 0;
  std::memcpy(&metadata_size, data, 4);
  if (metadata_size > size - 4) metadata_size = static_cast<uint32_t>(size - 4);
  const auto dir = fz::scratch_dir() / "trace";
  std::filesystem::create_directories(dir);
  fz::write_scratch("trace/metadata", data + 4, metadata_size);
  fz::write_scratch("trace/stream_0", data + 4 + metadata_size, size - 4 - metadata_size);
  try {
    const auto analysis = robotperf::tracing::analyze_trace(dir);
    // As the results writer dumps it: bytes that are not UTF-8 are replaced, not refused.
    (void)robotperf::tracing::to_json(analysis).dump(-1, ' ', false,
                                                     nlohmann::json::error_handler_t::replace);
    (void)robotperf::tracing::analysis_summary(analysis);
  } catch (const robotperf::tracing::ctf::CtfError&) {
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
