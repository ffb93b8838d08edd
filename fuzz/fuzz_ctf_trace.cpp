// The CTF reader and the grey-box analysis on arbitrary traces. The input is a 4-byte
// little-endian length, that many bytes of metadata (text or packetised), and one stream file.
// analyze_trace either analyses or throws CtfError (unreadable) or invalid_argument (no trace).
// Whatever the times in the input, the events the reader gives go forward in time within their
// stream and lie inside their packets' times, and an analysis that left packets out is invalid:
// the target aborts when one does not hold.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

#include "fuzz_scratch.hpp"
#include "robotperf/tracing/analysis.hpp"
#include "robotperf/tracing/ctf.hpp"

namespace {

namespace ctf = robotperf::tracing::ctf;

[[noreturn]] void broken(const char* invariant, uint64_t value, uint64_t bound) {
  std::fprintf(stderr, "fuzz_ctf_trace: %s (%llu, %llu)\n", invariant,
               static_cast<unsigned long long>(value), static_cast<unsigned long long>(bound));
  std::abort();
}

// The reader's time checks, stream by stream: all packets read at once (the events go forward),
// then each packet with a clock alone (its events lie in its begin..end).
void check_event_times(const std::filesystem::path& dir) {
  const ctf::Trace trace(dir);
  const ctf::Metadata& md = trace.metadata();
  const uint64_t freq = md.clocks.empty() ? 1'000'000'000 : md.clocks.front().freq;
  // A packet's bound in nanoseconds, as the reader converts event times (rounding down).
  auto ns = [&](uint64_t cycles) {
    return static_cast<unsigned __int128>(cycles) * 1'000'000'000 / freq;
  };
  for (std::size_t s = 0; s < trace.stream_count(); ++s) {
    ctf::StreamIndex index = trace.index_stream(s);
    uint64_t previous = 0;
    trace.read_packets(s, index.packets, [&](const ctf::Event& e) {
      if (e.timestamp < previous)
        broken("an event before the one before it", e.timestamp, previous);
      previous = e.timestamp;
    });
    for (ctf::Packet& p : index.packets) {
      if (!p.has_clock) continue;
      trace.read_packets(s, std::span(&p, 1), [&](const ctf::Event& e) {
        if (e.timestamp < ns(p.timestamp_begin))
          broken("an event before its packet's begin", e.timestamp, p.timestamp_begin);
        if (e.timestamp > ns(p.timestamp_end))
          broken("an event after its packet's end", e.timestamp, p.timestamp_end);
      });
    }
  }
}

}  // namespace

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
    if (analysis.defective_packets > 0 && analysis.valid)
      broken("an analysis without some packets' events valid", analysis.defective_packets, 0);
    // As the results writer dumps it: bytes that are not UTF-8 are replaced, not refused.
    (void)robotperf::tracing::to_json(analysis).dump(-1, ' ', false,
                                                     nlohmann::json::error_handler_t::replace);
    (void)robotperf::tracing::analysis_summary(analysis);
    check_event_times(dir);
  } catch (const robotperf::tracing::ctf::CtfError&) {
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
