#include "robotperf/metrics/delivery_validity.hpp"

#include <cstdio>

namespace robotperf::metrics {

std::vector<std::string> delivery_invalid_reasons(const DeliveryCounts& c, std::size_t min_samples,
                                                  double max_loss_percent) {
  std::vector<std::string> out;
  if (c.matched == 0 && c.unknown > 0) {
    // Not loss: the graph answered, but with stamps that are none of the inputs'.
    out.push_back("all " + std::to_string(c.unknown) +
                  " outputs carry a header.stamp that no input had: the graph does not copy its "
                  "input's header into its output, and robotperf's message IDs travel in the "
                  "stamp (see the README, \"a node that does not copy the header\")");
    return out;
  }
  if (c.matched < min_samples) {
    out.push_back(std::to_string(c.matched) + " matched samples, fewer than the " +
                  std::to_string(min_samples) + " required");
  }
  if (c.loss_percent > max_loss_percent) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "%.2f %% lost, above the %.2f %% bound", c.loss_percent,
                  max_loss_percent);
    out.emplace_back(buf);
  }
  if (c.duplicates > 0) out.push_back(std::to_string(c.duplicates) + " duplicate receptions");
  if (c.unknown > 0)
    out.push_back(std::to_string(c.unknown) + " receptions with unknown message IDs");
  return out;
}

}  // namespace robotperf::metrics
