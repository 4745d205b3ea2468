#pragma once
// How far apart two doors' parameter values are, for tests that ask two fits to end at the same
// parameters. Header-only, test code.
#include <algorithm>
#include <cmath>

#include "analysis/model/door_model.h"

namespace doorbench::testing {

// The largest |a_i - b_i| / max(|a_i|, |b_i|) over the parameters (0 where both are 0). The two
// doors must have the same parameters.
inline double largest_relative_difference(const DoorModel& a, const DoorModel& b) {
  double largest = 0.0;
  for (int i = 0; i < a.parameter_count(); ++i) {
    const double x = a.parameter_values()[i];
    const double y = b.parameter_values()[i];
    const double scale = std::max(std::abs(x), std::abs(y));
    if (scale > 0) largest = std::max(largest, std::abs(x - y) / scale);
  }
  return largest;
}

}  // namespace doorbench::testing
