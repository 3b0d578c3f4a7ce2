#pragma once
// A percentile by rank: the value at 0-based rank floor(p * n) of n values, found by partly
// reordering them (std::nth_element, linear time). p = 0.05 gives a low value robust to outliers
// in 1 frame in 20 (a clip's floor, its standing ankle height: tracking/).
#include <algorithm>
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

}  // namespace embody
