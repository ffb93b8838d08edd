// The bag readers under fuzzing: every message of a file, or the reader's BagError.
#pragma once

#include <filesystem>

#include "robotperf/bag/bag.hpp"

namespace robotperf::fuzz {

// `open` is bag::open_mcap or bag::open_sqlite3.
template <class Open>
void read_whole_bag(Open open, const std::filesystem::path& file, const bag::ReadOptions& options) {
  try {
    auto reader = open(file, options);
    (void)reader->topics();
    bag::Message m;
    while (reader->next(m)) {
    }
  } catch (const bag::BagError&) {
  }
}

}  // namespace robotperf::fuzz
