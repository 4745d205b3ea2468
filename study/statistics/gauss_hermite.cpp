#include "study/statistics/gauss_hermite.h"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace doorbench::study::statistics {

GaussHermite gauss_hermite(int n) {
  if (n < 1) throw std::invalid_argument("gauss_hermite: n must be at least 1");
  Eigen::MatrixXd jacobi = Eigen::MatrixXd::Zero(n, n);
  for (int k = 1; k < n; ++k) jacobi(k, k - 1) = jacobi(k - 1, k) = std::sqrt(k / 2.0);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(jacobi);
  GaussHermite rule;
  for (int k = 0; k < n; ++k) {
    rule.nodes.push_back(solver.eigenvalues()[k]);
    const double v0 = solver.eigenvectors()(0, k);
    rule.weights.push_back(std::sqrt(std::numbers::pi) * v0 * v0);
  }
  return rule;
}

}  // namespace doorbench::study::statistics
