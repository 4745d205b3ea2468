#pragma once
// The logistic function 1 / (1 + e^-x), the link of the cumulative-logit rating model and of
// the psychometric function's lapse parameterisation.
#include <cmath>

namespace doorbench::study {

inline double logistic(double x) {
  return 1.0 / (1.0 + std::exp(-x));
}

}  // namespace doorbench::study
