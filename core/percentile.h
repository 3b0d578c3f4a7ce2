#pragma once
// Percentiles, both found by partly reordering the values (std::nth_element, linear time):
// - percentileByRank: the value at 0-based rank floor(p * n) of n values. p = 0.05 gives a low
//   value robust to outliers in 1 frame in 20 (a clip's floor, its standing ankle height:
//   tracking/).
// - percentileNearestRank: the nearest-rank definition, the value at 1-based rank ceil(p% * n),
//   for the figures the runtime's stats and embody eval report (p95, p99).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <vector>

namespace embody {

// NaN for no values; `values` is reordered.
inline double percentileByRank(std::vector<double>& values, double p) {
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  const size_t rank = std::min(values.size() - 1, size_t(std::clamp(p, 0.0, 1.0) * double(values.size())));
  const auto k = values.begin() + std::ptrdiff_t(rank);
  std::nth_element(values.begin(), k, values.end());
  return *k;
}

// p in percent (0..100); 0 for no values; `values` is reordered.
inline double percentileNearestRank(std::vector<double>& values, double p) {
  if (values.empty()) return 0.0;
  const double rank = std::ceil(std::clamp(p, 0.0, 100.0) / 100.0 * double(values.size()));
  const auto k = values.begin() + std::ptrdiff_t(std::max(rank, 1.0)) - 1;
  std::nth_element(values.begin(), k, values.end());
  return *k;
}

}  // namespace embody
