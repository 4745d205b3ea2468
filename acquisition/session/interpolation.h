#pragma once
// Piecewise-linear interpolation of samples, shared by everything that puts one channel's
// samples on another's times (the inclinometer's delay corrected on read, calibration,
// preprocessing). Header-only: no state.
#include <algorithm>
#include <cstddef>
#include <vector>

namespace doorbench {

// Through (x_k, y_k) with x strictly increasing; held at the first and last value beyond
// the ends; 0 when there are no samples.
inline double interpolate_held(const std::vector<double>& x, const std::vector<double>& y,
                               double at) {
  if (x.empty()) return 0.0;
  if (at <= x.front()) return y.front();
  if (at >= x.back()) return y.back();
  const auto upper = std::upper_bound(x.begin(), x.end(), at);
  const auto k = static_cast<std::size_t>(upper - x.begin());
  const double s = (at - x[k - 1]) / (x[k] - x[k - 1]);
  return y[k - 1] + s * (y[k] - y[k - 1]);
}

}  // namespace doorbench
