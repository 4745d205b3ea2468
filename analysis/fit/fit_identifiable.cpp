// The identifiable free set (docs/fitting.md, "Identifiable parameters"): backward
// elimination along the weakest direction of the information at the optimum.
#include <Eigen/Dense>
#include <cmath>

#include "analysis/fit/fit_problem.h"

namespace doorbench {

namespace {

// The reduced system restricted to the free parameters `kept` (indices into its rows): the
// same windows with the other parameters held where they are.
ReducedSystem restrict_system(const ReducedSystem& system, const std::vector<int>& kept) {
  const auto n = static_cast<Eigen::Index>(kept.size());
  auto sub_matrix = [&](const Eigen::MatrixXd& m) {
    Eigen::MatrixXd out(n, n);
    for (Eigen::Index r = 0; r < n; ++r) {
      for (Eigen::Index c = 0; c < n; ++c) out(r, c) = m(kept[r], kept[c]);
    }
    return out;
  };
  auto sub_vector = [&](const Eigen::VectorXd& v) {
    Eigen::VectorXd out(n);
    for (Eigen::Index r = 0; r < n; ++r) out(r) = v(kept[r]);
    return out;
  };
  ReducedSystem out;
  out.information = sub_matrix(system.information);
  out.gradient = sub_vector(system.gradient);
  for (const Eigen::MatrixXd& h : system.window_information) {
    out.window_information.push_back(sub_matrix(h));
  }
  for (const Eigen::VectorXd& g : system.window_scores) out.window_scores.push_back(sub_vector(g));
  out.sum_of_squares = system.sum_of_squares;
  out.residuals = system.residuals;
  out.windows = system.windows;
  out.window_parameters = system.window_parameters;
  return out;
}

// The eigenvector of H's weakest direction, in normalized coordinates (unit diagonal).
Eigen::VectorXd weakest_direction(const Eigen::MatrixXd& information) {
  const Eigen::Index p = information.rows();
  Eigen::VectorXd unit(p);
  for (Eigen::Index k = 0; k < p; ++k) {
    unit(k) = information(k, k) > 0 ? 1.0 / std::sqrt(information(k, k)) : 0.0;
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(unit.asDiagonal() * information *
                                                             unit.asDiagonal());
  return eigen.eigenvectors().col(0);  // eigenvalues ascend
}

}  // namespace

std::vector<int> identifiable_subset(const ReducedSystem& system, const Eigen::VectorXd& x,
                                     bool robust, double relative_limit) {
  std::vector<int> kept;
  for (Eigen::Index k = 0; k < system.information.rows(); ++k) kept.push_back(static_cast<int>(k));
  while (!kept.empty()) {
    const ReducedSystem sub = restrict_system(system, kept);
    const InformationInverse inverse = invert_information(sub.information);
    const Eigen::VectorXd sigma = standard_uncertainties(sub, robust);
    std::vector<char> undetermined(kept.size(), 0);
    bool any = false;
    for (std::size_t k = 0; k < kept.size(); ++k) {
      const auto i = static_cast<Eigen::Index>(k);
      undetermined[k] =
          inverse.undetermined[k] || !(sigma(i) <= relative_limit * std::abs(x(kept[k])));
      any = any || undetermined[k];
    }
    if (!any) break;
    // Of the undetermined, the one with the largest part in the weakest direction.
    const Eigen::VectorXd weakest = weakest_direction(sub.information);
    std::size_t drop = kept.size();
    for (std::size_t k = 0; k < kept.size(); ++k) {
      if (!undetermined[k]) continue;
      const auto i = static_cast<Eigen::Index>(k);
      if (drop == kept.size() ||
          std::abs(weakest(i)) > std::abs(weakest(static_cast<Eigen::Index>(drop)))) {
        drop = k;
      }
    }
    kept.erase(kept.begin() + static_cast<std::ptrdiff_t>(drop));
  }
  return kept;
}

}  // namespace doorbench
