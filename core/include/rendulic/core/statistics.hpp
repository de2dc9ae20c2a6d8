// Small order statistics shared by the calibration's starting values and the benchmarks'
// alternated rounds (docs/calibration.md "Two levels", docs/performance.md "Commands").
#pragma once

#include <algorithm>
#include <vector>

namespace rendulic {

// The median of v (the mean of the two middle values for an even count); 0 for an empty v.
inline double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace rendulic
