#pragma once
// Quasi-variances (Firth & de Menezes 2004, "Quasi-variances", Biometrika 91, 65–80): one
// variance q_k per level of a factor such that the variance of any difference of two levels'
// estimates is approximately q_i + q_j. With them any two levels can be compared from one
// plot, not only each against the reference level (whose estimate is fixed at 0 and whose
// own variance is therefore 0, though its quasi-variance is not).
//
// Fitted as R's qvcalc does: least squares on the log scale over every pair i < j,
//   minimise Σ (ln v_ij − ln(q_i + q_j))²,
// v_ij the variance of the difference; by Gauss–Newton from the linear least-squares solution
// of q_i + q_j = v_ij, with step halving so that every q_i + q_j stays positive. The relative
// error of a pair is sqrt((q_i + q_j) / v_ij) − 1 (qvcalc's relerrs).
//
// Internal to study/statistics. Thread safety: pure functions.
#include <Eigen/Dense>
#include <optional>
#include <vector>

namespace doorbench::study::statistics {

struct QuasiVariances {
  std::vector<double> variances;      // q_k, one per level
  double worst_relative_error = 0.0;  // the largest |relative error| over the pairs
};

// The variance of every difference of two levels, v_ij = C_ii + C_jj − 2 C_ij, from a
// covariance matrix over all levels (the reference's row and column 0).
Eigen::MatrixXd pairwise_variances(const Eigen::MatrixXd& covariance);

// The quasi-variances fitted to `pair_variances` (symmetric; the diagonal ignored). nullopt
// for fewer than 3 levels (they are not determined), for a pair whose variance is not
// positive and finite, or when the fit does not converge.
std::optional<QuasiVariances> quasi_variances(const Eigen::MatrixXd& pair_variances);

}  // namespace doorbench::study::statistics
