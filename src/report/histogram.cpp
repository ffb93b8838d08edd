#include "robotperf/report/histogram.hpp"

#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>

#include "robotperf/report/run_store.hpp"

namespace robotperf::report {
namespace {

int bin_index(double x, int bins_per_decade) {
  return static_cast<int>(std::floor(std::log10(x) * bins_per_decade));
}

}  // namespace

double LogHistogram::lower_edge(std::size_t bin) const {
  return std::pow(10.0, (first_index + static_cast<double>(bin)) / bins_per_decade);
}

double LogHistogram::upper_edge(std::size_t bin) const {
  return lower_edge(bin + 1);
}

std::uint64_t LogHistogram::total() const {
  return std::accumulate(counts.begin(), counts.end(), nonpositive);
}

LogHistogram make_log_histogram(std::span<const double> samples, int bins_per_decade) {
  if (bins_per_decade < 1) throw std::invalid_argument("histogram: bins_per_decade must be >= 1");
  LogHistogram h;
  h.bins_per_decade = bins_per_decade;
  int lowest = 0, highest = 0;
  bool any = false;
  for (double x : samples) {
    if (!std::isfinite(x)) throw std::invalid_argument("histogram: sample is not finite");
    if (x <= 0) continue;
    const int k = bin_index(x, bins_per_decade);
    lowest = any ? std::min(lowest, k) : k;
    highest = any ? std::max(highest, k) : k;
    any = true;
  }
  if (any) {
    h.first_index = lowest;
    h.counts.assign(static_cast<std::size_t>(highest - lowest + 1), 0);
  }
  for (double x : samples) {
    if (x <= 0) {
      ++h.nonpositive;
    } else {
      ++h.counts[static_cast<std::size_t>(bin_index(x, bins_per_decade) - lowest)];
    }
  }
  return h;
}

nlohmann::json to_json(const LogHistogram& h) {
  return {
      {"scale", "log10"},
      {"bins_per_decade", h.bins_per_decade},
      {"first_index", h.first_index},
      {"first_edge", h.counts.empty() ? nlohmann::json(nullptr) : nlohmann::json(h.lower_edge(0))},
      {"counts", h.counts},
      {"nonpositive", h.nonpositive}};
}

std::optional<LogHistogram> log_histogram_from_json(const nlohmann::json& j) {
  if (j.is_null()) return std::nullopt;
  if (j.at("scale") != "log10")
    throw ReportError("histogram scale " + j.at("scale").dump() + ", expected \"log10\"");
  LogHistogram h;
  h.bins_per_decade = j.at("bins_per_decade").get<int>();
  h.first_index = j.at("first_index").get<int>();
  h.counts = j.at("counts").get<std::vector<std::uint64_t>>();
  if (const auto it = j.find("nonpositive"); it != j.end())
    h.nonpositive = it->get<std::uint64_t>();
  if (h.bins_per_decade < 1) throw ReportError("histogram bins_per_decade must be >= 1");
  // Edges outside double's range would put infinities on the report's axes.
  if (!h.counts.empty() &&
      !(h.lower_edge(0) > 0 && std::isfinite(h.upper_edge(h.counts.size() - 1)))) {
    throw ReportError("histogram bins from 10^(" + std::to_string(h.first_index) + "/" +
                      std::to_string(h.bins_per_decade) + ") are beyond the range of a double");
  }
  return h;
}

}  // namespace robotperf::report
