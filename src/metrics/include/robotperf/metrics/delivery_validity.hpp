// The rules DESIGN.md §3.5-3.6 set on a run's message counts, shared by black-box results and the
// grey-box trace analysis so that both call a run invalid for the same reasons in the same words.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace robotperf::metrics {

struct DeliveryCounts {
  std::size_t matched = 0;  // measured messages whose output arrived
  std::size_t duplicates = 0;
  std::size_t unknown = 0;  // receptions with IDs that were never sent
  double loss_percent = 0;
};

// One reason per broken rule: too few samples, loss above the bound, duplicates, unknown IDs.
std::vector<std::string> delivery_invalid_reasons(const DeliveryCounts& counts,
                                                  std::size_t min_samples, double max_loss_percent);

}  // namespace robotperf::metrics
