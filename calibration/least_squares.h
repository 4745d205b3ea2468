#pragma once
// Small least-squares tools shared by the calibration procedures: polynomial fits with
// the coefficients' covariance, and the Student-t factor that turns a standard
// uncertainty estimated from few residuals into one with the coverage of a known σ.
#include <span>
#include <vector>

namespace doorbench::calibration {

struct PolynomialFit {
  std::vector<double> coefficients;  // y ≈ Σ c[k] x^k
  // Covariance of the coefficients, row-major (degree+1)², from the residual variance.
  std::vector<double> covariance;
  std::vector<double> residuals;  // fitted − y, per point
  double residual_std = 0.0;      // sqrt(Σ r² / (n − p))
  int degrees_of_freedom = 0;     // n − p

  double value(double x) const;
  double coefficient_std(int k) const;  // sqrt(covariance[k][k])
  // Standard deviation of the fitted curve at x (the fit's own uncertainty there).
  double value_std(double x) const;
};

// Ordinary least squares (QR). Needs more points than coefficients; throws
// std::invalid_argument otherwise or when the x are degenerate.
PolynomialFit fit_polynomial(std::span<const double> x, std::span<const double> y, int degree);

// Two-sided 95 % Student-t quantile for `degrees_of_freedom` ≥ 1 (1.96 for ∞), i.e.
// the 0.975 quantile, from Boost.Math (to double precision). Throws
// std::invalid_argument for degrees_of_freedom < 1. Thread-safe.
double student_t_95(int degrees_of_freedom);

// The factor that scales a standard deviation estimated with ν degrees of freedom so that
// ±2 × (scaled value) covers like ±2σ for a known σ: t₉₅(ν) / z₉₅, z₉₅ = 1.959964…
// the normal distribution's 0.975 quantile (≥ 1).
double small_sample_factor(int degrees_of_freedom);

// Mean and (n − 1) standard deviation.
double mean_of(std::span<const double> values);
double std_of(std::span<const double> values);

}  // namespace doorbench::calibration
