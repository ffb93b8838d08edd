// A compact latency distribution for the results JSON: counts in logarithmically spaced bins, so a
// run of a million messages is stored in a few hundred integers and the report can still draw its
// CDF with a relative resolution of a few percent.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <vector>

namespace robotperf::report {

// Bin i covers [edge(first_index + i), edge(first_index + i + 1)) with
// edge(k) = 10^(k / bins_per_decade). Samples <= 0 have no logarithmic bin and are counted in
// `nonpositive`.
struct LogHistogram {
  int bins_per_decade = 50;
  int first_index = 0;
  std::vector<std::uint64_t> counts;
  std::uint64_t nonpositive = 0;

  double lower_edge(std::size_t bin) const;
  double upper_edge(std::size_t bin) const;
  std::uint64_t total() const;
};

// Throws std::invalid_argument when bins_per_decade < 1 or a sample is not finite.
LogHistogram make_log_histogram(std::span<const double> samples, int bins_per_decade = 50);

// {"scale": "log10", "bins_per_decade", "first_index", "first_edge", "counts", "nonpositive"}
nlohmann::json to_json(const LogHistogram& histogram);

// std::nullopt when `j` is null (older files have no histogram). Throws ReportError for another
// scale, bins_per_decade < 1 or edges beyond double's range, and nlohmann::json::exception for a
// missing or wrong-typed field.
std::optional<LogHistogram> log_histogram_from_json(const nlohmann::json& j);

}  // namespace robotperf::report
