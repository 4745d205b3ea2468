#include "calibration/least_squares.h"

#include <Eigen/Dense>
#include <boost/math/distributions/normal.hpp>
#include <boost/math/distributions/students_t.hpp>
#include <cmath>
#include <stdexcept>

namespace doorbench::calibration {

double PolynomialFit::value(double x) const {
  double y = 0.0;
  for (auto it = coefficients.rbegin(); it != coefficients.rend(); ++it) y = y * x + *it;
  return y;
}

double PolynomialFit::coefficient_std(int k) const {
  const std::size_t p = coefficients.size();
  return std::sqrt(covariance[static_cast<std::size_t>(k) * p + static_cast<std::size_t>(k)]);
}

double PolynomialFit::value_std(double x) const {
  const std::size_t p = coefficients.size();
  std::vector<double> basis(p, 1.0);
  for (std::size_t k = 1; k < p; ++k) basis[k] = basis[k - 1] * x;
  double variance = 0.0;
  for (std::size_t i = 0; i < p; ++i) {
    for (std::size_t j = 0; j < p; ++j) variance += basis[i] * covariance[i * p + j] * basis[j];
  }
  return std::sqrt(std::max(variance, 0.0));
}

PolynomialFit fit_polynomial(std::span<const double> x, std::span<const double> y, int degree) {
  if (degree < 0) throw std::invalid_argument("fit_polynomial: degree must be >= 0");
  if (x.size() != y.size()) throw std::invalid_argument("fit_polynomial: x and y differ in length");
  const auto n = static_cast<Eigen::Index>(x.size());
  const Eigen::Index p = degree + 1;
  if (n <= p) {
    throw std::invalid_argument("fit_polynomial: " + std::to_string(n) + " points for " +
                                std::to_string(p) + " coefficients (need more points)");
  }
  Eigen::MatrixXd design(n, p);
  Eigen::VectorXd target(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    double power = 1.0;
    for (Eigen::Index k = 0; k < p; ++k) {
      design(i, k) = power;
      power *= x[static_cast<std::size_t>(i)];
    }
    target(i) = y[static_cast<std::size_t>(i)];
  }
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(design);
  if (qr.rank() < p) throw std::invalid_argument("fit_polynomial: the x values are degenerate");
  const Eigen::VectorXd c = qr.solve(target);
  const Eigen::VectorXd residual = design * c - target;

  PolynomialFit fit;
  fit.degrees_of_freedom = static_cast<int>(n - p);
  fit.residual_std = std::sqrt(residual.squaredNorm() / static_cast<double>(n - p));
  fit.coefficients.assign(c.data(), c.data() + p);
  fit.residuals.assign(residual.data(), residual.data() + n);
  const Eigen::MatrixXd normal_inverse =
      (design.transpose() * design).inverse() * (fit.residual_std * fit.residual_std);
  fit.covariance.resize(static_cast<std::size_t>(p * p));
  for (Eigen::Index i = 0; i < p; ++i) {
    for (Eigen::Index j = 0; j < p; ++j) {
      fit.covariance[static_cast<std::size_t>(i * p + j)] = normal_inverse(i, j);
    }
  }
  return fit;
}

double student_t_95(int degrees_of_freedom) {
  if (degrees_of_freedom < 1)
    throw std::invalid_argument("student_t_95: needs >= 1 degree of freedom");
  const boost::math::students_t_distribution<double> t(degrees_of_freedom);
  return boost::math::quantile(boost::math::complement(t, 0.025));
}

double small_sample_factor(int degrees_of_freedom) {
  static const double z_95 = boost::math::quantile(
      boost::math::complement(boost::math::normal_distribution<double>(), 0.025));
  return student_t_95(degrees_of_freedom) / z_95;
}

double mean_of(std::span<const double> values) {
  if (values.empty()) return 0.0;
  double sum = 0.0;
  for (double v : values) sum += v;
  return sum / static_cast<double>(values.size());
}

double std_of(std::span<const double> values) {
  if (values.size() < 2) return 0.0;
  const double mean = mean_of(values);
  double sum = 0.0;
  for (double v : values) sum += (v - mean) * (v - mean);
  return std::sqrt(sum / static_cast<double>(values.size() - 1));
}

}  // namespace doorbench::calibration
