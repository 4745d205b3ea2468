#pragma once
// Gauss–Hermite quadrature: nodes x_k and weights w_k with
// ∫ e^{-x²} f(x) dx ≈ Σ w_k f(x_k), exact for polynomials of degree < 2n (Golub–Welsch:
// the eigenvalues of the Hermite recurrence's Jacobi matrix). Internal to study/statistics.
// Thread safety: pure.
#include <vector>

namespace doorbench::study::statistics {

struct GaussHermite {
  std::vector<double> nodes;
  std::vector<double> weights;
};

// n >= 1 nodes (n = 1: the node 0 with weight √π). Throws std::invalid_argument for n < 1.
GaussHermite gauss_hermite(int n);

}  // namespace doorbench::study::statistics
