// Change points of a series of measurements: where its level moved, found by E-divisive means
// (Matteson & James, "A Nonparametric Approach for Multiple Change Point Analysis of Multivariate
// Data", JASA 2014), the method MongoDB's and DataStax's (Hunter) performance CI use to find the
// commit that made a benchmark slower (docs/design.md §8).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace robotperf::report {

struct ChangePointOptions {
  // A split is kept when its permutation-test p-value is at most this: on a series without a
  // change, the chance of reporting one (the false-positive rate per series) is about this.
  double significance = 0.01;
  std::size_t permutations = 499;  // p-values are multiples of 1 / (permutations + 1)
  std::size_t min_segment = 3;     // points on each side of a change, at least 2
  std::uint64_t seed = 1;          // the permutations are reproducible
};

struct ChangePoint {
  std::size_t index = 0;  // the first point of the new level
  double p_value = 1;
  double before = 0, after = 0;  // the medians of the segments on either side
  // (after - before) / |before| in percent; NaN when `before` is 0.
  double change_percent() const;
};

// The change points of `values`, in index order. Each is the split that maximises the energy
// distance between the two sides of its segment (alpha = 1), kept when a permutation test finds it
// significant; segments are split again until no split is. O(P n log n) per segment tested.
std::vector<ChangePoint> change_points(const std::vector<double>& values,
                                       const ChangePointOptions& options = {});

}  // namespace robotperf::report
