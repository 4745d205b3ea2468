#pragma once
// The phase of a sine of known frequency in samples, for the timing tests: the least-squares
// fit of y = a·sin(ωt) + b·cos(ωt) + c, whose phase φ is that of R·sin(ωt + φ).
#include <cmath>
#include <vector>

namespace doorbench::testing {

inline double sine_phase(const std::vector<double>& t, const std::vector<double>& y, double omega) {
  // Normal equations of the three basis functions, solved by Gauss-Jordan (the matrix is
  // well conditioned over whole periods).
  double m[3][4] = {};
  for (std::size_t i = 0; i < t.size(); ++i) {
    const double f[3] = {std::sin(omega * t[i]), std::cos(omega * t[i]), 1.0};
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) m[r][c] += f[r] * f[c];
      m[r][3] += f[r] * y[i];
    }
  }
  for (int p = 0; p < 3; ++p) {
    for (int r = 0; r < 3; ++r) {
      if (r == p) continue;
      const double k = m[r][p] / m[p][p];
      for (int c = p; c < 4; ++c) m[r][c] -= k * m[p][c];
    }
  }
  return std::atan2(m[1][3] / m[1][1], m[0][3] / m[0][0]);
}

}  // namespace doorbench::testing
