#include "study/statistics/quasi_variance.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace doorbench::study::statistics {
namespace {

struct PairSystem {
  Eigen::MatrixXd design;        // one row per pair i < j: ones at i and j
  Eigen::VectorXd log_variance;  // ln v_ij
};

// Σ (ln v_ij − ln(q_i + q_j))², +infinity where some q_i + q_j is not positive.
double log_squares(const PairSystem& system, const Eigen::VectorXd& q) {
  const Eigen::VectorXd sums = system.design * q;
  if ((sums.array() <= 0.0).any()) return std::numeric_limits<double>::infinity();
  return (system.log_variance.array() - sums.array().log()).square().sum();
}

}  // namespace

Eigen::MatrixXd pairwise_variances(const Eigen::MatrixXd& covariance) {
  const Eigen::Index k = covariance.rows();
  Eigen::MatrixXd v = Eigen::MatrixXd::Zero(k, k);
  for (Eigen::Index i = 0; i < k; ++i)
    for (Eigen::Index j = 0; j < k; ++j)
      if (i != j) v(i, j) = covariance(i, i) + covariance(j, j) - 2.0 * covariance(i, j);
  return v;
}

std::optional<QuasiVariances> quasi_variances(const Eigen::MatrixXd& pair_variances) {
  const Eigen::Index k = pair_variances.rows();
  if (k < 3 || pair_variances.cols() != k) return std::nullopt;
  const Eigen::Index pairs = k * (k - 1) / 2;
  PairSystem system{Eigen::MatrixXd::Zero(pairs, k), Eigen::VectorXd(pairs)};
  Eigen::VectorXd variance(pairs);
  for (Eigen::Index i = 0, row = 0; i < k; ++i) {
    for (Eigen::Index j = i + 1; j < k; ++j, ++row) {
      const double v = pair_variances(i, j);
      if (!(v > 0.0) || !std::isfinite(v)) return std::nullopt;
      system.design(row, i) = system.design(row, j) = 1.0;
      variance[row] = v;
      system.log_variance[row] = std::log(v);
    }
  }
  // Start: q_i + q_j = v_ij by linear least squares, lifted where a sum would not be positive.
  Eigen::VectorXd q = system.design.colPivHouseholderQr().solve(variance);
  if (!std::isfinite(log_squares(system, q))) q = Eigen::VectorXd::Constant(k, variance.mean() / 2);
  double value = log_squares(system, q);
  bool converged = false;
  for (int iteration = 0; iteration < 200 && !converged; ++iteration) {
    const Eigen::VectorXd sums = system.design * q;
    const Eigen::VectorXd residual = system.log_variance.array() - sums.array().log();
    // The residuals' Jacobian in q: −1 / (q_i + q_j) at i and j.
    const Eigen::MatrixXd jacobian =
        -(sums.array().inverse().matrix().asDiagonal() * system.design);
    const Eigen::VectorXd step = jacobian.colPivHouseholderQr().solve(-residual);
    const double size = step.cwiseAbs().maxCoeff() / std::max(1e-300, q.cwiseAbs().maxCoeff());
    // Gauss–Newton converges linearly when the residuals are not 0: a relative step of
    // 1e-11 is far below what any use of q resolves (R's qvcalc stops at a deviance change
    // of 1e-8).
    if (size <= 1e-11) {
      converged = true;
      break;
    }
    double scale = 1.0;
    double next = log_squares(system, q + step);
    if (!(next < value) && size <= 1e-8) {  // at the minimum, to rounding
      converged = true;
      break;
    }
    while (!(next < value) && scale > 1e-12) {
      scale /= 2;
      next = log_squares(system, q + scale * step);
    }
    if (!(next < value)) break;
    q += scale * step;
    value = next;
  }
  if (!converged) return std::nullopt;
  QuasiVariances out;
  out.variances.assign(q.data(), q.data() + k);
  const Eigen::VectorXd sums = system.design * q;
  for (Eigen::Index row = 0; row < pairs; ++row)
    out.worst_relative_error =
        std::max(out.worst_relative_error, std::abs(std::sqrt(sums[row] / variance[row]) - 1.0));
  return out;
}

}  // namespace doorbench::study::statistics
