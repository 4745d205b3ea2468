#pragma once
// The psychometric function's likelihood (study/statistics/thresholds.h) on binomial counts
// per comparison level, with its analytic gradient and Hessian; the maximum-likelihood fit,
// the profile likelihood's ends in ln spread, and the fitted curve's pointwise band.
//
// Parameters, in this order (a parameter not fitted is left out): pse, ln spread, and the
// lapse's logit v, lapse = max_lapse · logistic(v). The likelihood of k "stronger" answers of
// n at level x is P^k (1 − P)^(n − k) with P = lapse/2 + (1 − lapse) F(z), z = (x − pse) /
// spread (plus ln ln 2 for the Gumbel, so that pse is its median). Counting the answers per
// level makes each evaluation cost one term per level, not per trial.
//
// Internal to study/statistics (thresholds.cpp). Thread safety: pure functions.
#include <Eigen/Dense>
#include <span>
#include <utility>
#include <vector>

#include "study/statistics/numeric_minimize.h"
#include "study/statistics/thresholds.h"

namespace doorbench::study::statistics {

// F(z) and 1 − F(z), each computed directly so that neither tail loses digits.
std::pair<double, double> psychometric_cdf_pair(PsychometricShape shape, double z);
// z of a level: (level − pse) / spread, shifted by ln ln 2 for the Gumbel.
double psychometric_z(PsychometricShape shape, double level, double pse, double spread);
// The lapse-free F's quantile in units of spread, relative to its median.
double quantile_above_median(PsychometricShape shape, double p);

struct PsychometricLayout {
  bool fit_pse = true;
  bool fit_lapse = true;
  double max_lapse = 0.1;
  int size() const { return 1 + (fit_pse ? 1 : 0) + (fit_lapse ? 1 : 0); }
  int spread_index() const { return fit_pse ? 1 : 0; }
};

struct PsychometricValues {
  double pse = 0.0, log_spread = 0.0, lapse = 0.0;
};
PsychometricValues unpack(const Eigen::VectorXd& x, const PsychometricLayout& layout);

struct PsychometricProblem {
  std::vector<LevelCount> counts;  // by level ascending
  PsychometricShape shape = PsychometricShape::kCumulativeNormal;
  PsychometricLayout layout;
};

// The answers counted per level.
std::vector<LevelCount> count_levels(std::span<const StrongerObservation> trials);

// The negative log-likelihood at x with its analytic gradient and Hessian (+inf, and no
// derivatives, where it is not finite: ln spread outside ±30, a probability of 0).
Derivatives psychometric_derivatives(const PsychometricProblem& problem, const Eigen::VectorXd& x);

// The maximum-likelihood fit: the best of damped Newton runs from three spreads (0.1, 0.5 and
// 2 × `level_range`) at pse 0 and a lapse of 2 %. Throws std::invalid_argument when no start
// has a finite likelihood.
MinimizeResult fit_psychometric_free(const PsychometricProblem& problem, double level_range);

// Where the profile negative log-likelihood of ln spread rises by `cut` above `minimum`,
// going from `optimum` in `direction` (+1 / −1): bracketed by steps growing 1.5-fold from
// 0.1, then found by TOMS 748 (boost::math::tools::toms748_solve); each profile point is
// warm-started from the nearest point computed before. ±infinity when the profile stays
// below the cut within 12 units of ln spread.
double profile_limit(const PsychometricProblem& problem, const Eigen::VectorXd& optimum,
                     double minimum, double cut, int direction);

// The covariance of (pse, ln spread, lapse logit) at the optimum, the inverse of the observed
// information over the parameters fitted; a parameter not fitted, or a lapse at its bound
// (within 1e-6 of 0 or max_lapse, where the information about it vanishes), has zero rows.
Eigen::Matrix3d psychometric_covariance(const PsychometricProblem& problem,
                                        const Eigen::VectorXd& optimum);

// P(stronger | level) and its pointwise interval (`z` the normal quantile of its
// confidence): the delta method on logit P with the covariance above, back-transformed (so
// the band stays inside 0..1).
CurvePoint psychometric_curve_point(PsychometricShape shape, const PsychometricValues& values,
                                    const PsychometricLayout& layout,
                                    const Eigen::Matrix3d& covariance, double level, double z);

}  // namespace doorbench::study::statistics
