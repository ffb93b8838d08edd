// The MCAP reader on arbitrary files: it either reads messages or throws BagError.
#include <cstdint>

#include "fuzz_bag.hpp"
#include "fuzz_scratch.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  namespace fz = robotperf::fuzz;
  const auto file = fz::write_scratch("bag.mcap", data, size);
  fz::read_whole_bag(robotperf::bag::open_mcap, file, {});
  // Without CRC checks, corrupt chunks reach the decompressors and parsers.
  robotperf::bag::ReadOptions unchecked;
  unchecked.verify_crc = false;
  fz::read_whole_bag(robotperf::bag::open_mcap, file, unchecked);
  return 0;
}
