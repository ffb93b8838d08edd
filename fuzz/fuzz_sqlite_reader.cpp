// The sqlite3 bag reader on arbitrary files: it either reads messages or throws BagError.
#include <cstdint>

#include "fuzz_bag.hpp"
#include "fuzz_scratch.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  namespace fz = robotperf::fuzz;
  const auto file = fz::write_scratch("bag.db3", data, size);
  fz::read_whole_bag(robotperf::bag::open_sqlite3, file, {});
  // A time window and a topic filter take the reader's other query.
  robotperf::bag::ReadOptions filtered;
  filtered.topics = {"/topic"};
  filtered.start_time_ns = 1;
  filtered.end_time_ns = INT64_MAX / 2;
  fz::read_whole_bag(robotperf::bag::open_sqlite3, file, filtered);
  return 0;
}
