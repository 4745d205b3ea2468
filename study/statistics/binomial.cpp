#include "study/statistics/binomial.h"

#include <algorithm>
#include <boost/math/distributions/binomial.hpp>
#include <stdexcept>
#include <string>

namespace doorbench::study {

double binomial_two_sided_p(long k, long n) {
  if (n < 0 || k < 0 || k > n) {
    throw std::invalid_argument("binomial test: need 0 <= k <= n, got k = " + std::to_string(k) +
                                ", n = " + std::to_string(n));
  }
  const long m = std::min(k, n - k);
  // At the centre every outcome is at least as far from n/2: p = 1.
  if (2 * m == n || n == 0) return 1.0;
  // The distribution is symmetric: p = 2 P(X <= m), m the nearer tail's end.
  const boost::math::binomial_distribution<double> chance(static_cast<double>(n), 0.5);
  return std::min(2.0 * boost::math::cdf(chance, static_cast<double>(m)), 1.0);
}

}  // namespace doorbench::study
