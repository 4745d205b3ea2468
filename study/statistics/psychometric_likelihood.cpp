#include "study/statistics/psychometric_likelihood.h"

#include <algorithm>
#include <boost/math/distributions/normal.hpp>
#include <boost/math/tools/roots.hpp>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <numbers>
#include <stdexcept>

#include "study/statistics/logistic.h"

namespace doorbench::study::statistics {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// The Gumbel's z shift: its median is at z = ln ln 2.
double gumbel_shift() {
  return std::log(std::log(2.0));
}

// F's density f(z) and its derivative f'(z).
std::pair<double, double> density_and_slope(PsychometricShape shape, double z) {
  if (shape == PsychometricShape::kCumulativeNormal) {
    const double f = std::exp(-0.5 * z * z) / std::sqrt(2.0 * std::numbers::pi);
    return {f, -z * f};
  }
  if (z > 6.5) return {0.0, 0.0};  // e^z > 665: exp(z − e^z) underflows
  const double e = std::exp(z);
  const double f = std::exp(z - e);
  return {f, f * (1.0 - e)};
}

// P at one level with its gradient and Hessian over (pse, ln spread, lapse logit), all
// three whether fitted or not (the caller keeps the rows it fits).
struct LevelProbability {
  double p = 0.0, q = 0.0;  // P and 1 − P
  Eigen::Vector3d gradient = Eigen::Vector3d::Zero();
  Eigen::Matrix3d hessian = Eigen::Matrix3d::Zero();
};

LevelProbability level_probability(PsychometricShape shape, const PsychometricValues& v,
                                   const PsychometricLayout& layout, double level) {
  const double spread = std::exp(v.log_spread);
  const double z = psychometric_z(shape, level, v.pse, spread);
  const double centred = (level - v.pse) / spread;  // dz/d(ln spread) = −centred
  const auto [f_cdf, not_f] = psychometric_cdf_pair(shape, z);
  const auto [f, slope] = density_and_slope(shape, z);
  const double lapse = v.lapse;
  // dλ/dv and d²λ/dv² for λ = L·logistic(v).
  const double d_lapse = layout.fit_lapse ? lapse * (1.0 - lapse / layout.max_lapse) : 0.0;
  const double dd_lapse = layout.fit_lapse ? d_lapse * (1.0 - 2.0 * lapse / layout.max_lapse) : 0.0;
  LevelProbability out;
  out.p = lapse / 2.0 + (1.0 - lapse) * f_cdf;
  out.q = lapse / 2.0 + (1.0 - lapse) * not_f;
  const double keep = 1.0 - lapse;
  out.gradient << -keep * f / spread, -keep * f * centred, (0.5 - f_cdf) * d_lapse;
  Eigen::Matrix3d& h = out.hessian;
  h(0, 0) = keep * slope / (spread * spread);
  h(0, 1) = h(1, 0) = keep / spread * (slope * centred + f);
  h(1, 1) = keep * centred * (slope * centred + f);
  h(0, 2) = h(2, 0) = d_lapse * f / spread;
  h(1, 2) = h(2, 1) = d_lapse * f * centred;
  h(2, 2) = (0.5 - f_cdf) * dd_lapse;
  return out;
}

// The fitted parameters' positions among (pse, ln spread, lapse logit).
std::vector<int> fitted_indices(const PsychometricLayout& layout) {
  std::vector<int> indices;
  if (layout.fit_pse) indices.push_back(0);
  indices.push_back(1);
  if (layout.fit_lapse) indices.push_back(2);
  return indices;
}

double initial_lapse_logit(const PsychometricLayout& layout) {
  return std::log(0.02 / (layout.max_lapse - 0.02));
}

}  // namespace

std::pair<double, double> psychometric_cdf_pair(PsychometricShape shape, double z) {
  if (shape == PsychometricShape::kCumulativeNormal) {
    return {0.5 * std::erfc(-z / std::numbers::sqrt2), 0.5 * std::erfc(z / std::numbers::sqrt2)};
  }
  const double e = std::exp(z);
  return {-std::expm1(-e), std::exp(-e)};
}

double psychometric_z(PsychometricShape shape, double level, double pse, double spread) {
  const double z = (level - pse) / spread;
  return shape == PsychometricShape::kWeibull ? z + gumbel_shift() : z;
}

double quantile_above_median(PsychometricShape shape, double p) {
  if (shape == PsychometricShape::kCumulativeNormal) {
    return boost::math::quantile(boost::math::normal(), p);
  }
  return std::log(-std::log1p(-p)) - gumbel_shift();
}

PsychometricValues unpack(const Eigen::VectorXd& x, const PsychometricLayout& layout) {
  PsychometricValues v;
  int i = 0;
  if (layout.fit_pse) v.pse = x[i++];
  v.log_spread = x[i++];
  if (layout.fit_lapse) v.lapse = layout.max_lapse * logistic(x[i]);
  return v;
}

std::vector<LevelCount> count_levels(std::span<const StrongerObservation> trials) {
  std::map<double, LevelCount> by_level;
  for (const auto& t : trials) {
    LevelCount& c = by_level[t.level];
    c.level = t.level;
    ++c.trials;
    c.stronger += t.comparison_stronger ? 1 : 0;
  }
  std::vector<LevelCount> out;
  out.reserve(by_level.size());
  for (const auto& [level, count] : by_level) out.push_back(count);
  return out;
}

Derivatives psychometric_derivatives(const PsychometricProblem& problem, const Eigen::VectorXd& x) {
  Derivatives d;
  const PsychometricValues v = unpack(x, problem.layout);
  if (v.log_spread < -30.0 || v.log_spread > 30.0) {
    d.value = kInfinity;
    return d;
  }
  Eigen::Vector3d gradient = Eigen::Vector3d::Zero();
  Eigen::Matrix3d hessian = Eigen::Matrix3d::Zero();
  double value = 0.0;
  for (const LevelCount& c : problem.counts) {
    const LevelProbability l = level_probability(problem.shape, v, problem.layout, c.level);
    const double yes = c.stronger, no = c.trials - c.stronger;
    if (yes > 0) value -= yes * std::log(l.p);
    if (no > 0) value -= no * std::log(l.q);
    // d(−ℓ)/dP and d²(−ℓ)/dP² for this level's binomial term.
    const double first = (yes > 0 ? -yes / l.p : 0.0) + (no > 0 ? no / l.q : 0.0);
    const double second = (yes > 0 ? yes / (l.p * l.p) : 0.0) + (no > 0 ? no / (l.q * l.q) : 0.0);
    gradient += first * l.gradient;
    hessian += second * l.gradient * l.gradient.transpose() + first * l.hessian;
  }
  if (!std::isfinite(value)) {
    d.value = kInfinity;
    return d;
  }
  const std::vector<int> kept = fitted_indices(problem.layout);
  const auto n = static_cast<Eigen::Index>(kept.size());
  d.value = value;
  d.gradient.resize(n);
  d.hessian.resize(n, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    d.gradient[i] = gradient[kept[i]];
    for (Eigen::Index j = 0; j < n; ++j) d.hessian(i, j) = hessian(kept[i], kept[j]);
  }
  return d;
}

MinimizeResult fit_psychometric_free(const PsychometricProblem& problem, double level_range) {
  MinimizeResult best;
  best.value = kInfinity;
  const DerivativeObjective f = [&](const Eigen::VectorXd& x) {
    return psychometric_derivatives(problem, x);
  };
  for (const double spread : {0.1 * level_range, 0.5 * level_range, 2.0 * level_range}) {
    Eigen::VectorXd x0(problem.layout.size());
    int i = 0;
    if (problem.layout.fit_pse) x0[i++] = 0.0;
    x0[i++] = std::log(spread);
    if (problem.layout.fit_lapse) x0[i] = initial_lapse_logit(problem.layout);
    if (!std::isfinite(f(x0).value)) continue;
    auto result = minimize(f, x0);
    if (result.value < best.value) best = result;
  }
  if (!std::isfinite(best.value))
    throw std::invalid_argument("no start value has a finite likelihood");
  return best;
}

namespace {

// The profile at one ln spread: the other parameters maximised out, from `others`, which it
// updates to the maximiser.
double profile_at(const PsychometricProblem& problem, double log_spread, Eigen::VectorXd& others) {
  const int s = problem.layout.spread_index();
  const auto full = [&](const Eigen::VectorXd& o) {
    Eigen::VectorXd x(o.size() + 1);
    for (Eigen::Index i = 0, j = 0; i < x.size(); ++i) x[i] = i == s ? log_spread : o[j++];
    return x;
  };
  const DerivativeObjective f = [&](const Eigen::VectorXd& o) {
    Derivatives d = psychometric_derivatives(problem, full(o));
    if (!std::isfinite(d.value)) return d;
    Derivatives sub;
    sub.value = d.value;
    const Eigen::Index n = o.size();
    sub.gradient.resize(n);
    sub.hessian.resize(n, n);
    for (Eigen::Index i = 0, a = 0; i < n + 1; ++i) {
      if (i == s) continue;
      sub.gradient[a] = d.gradient[i];
      for (Eigen::Index j = 0, b = 0; j < n + 1; ++j) {
        if (j == s) continue;
        sub.hessian(a, b++) = d.hessian(i, j);
      }
      ++a;
    }
    return sub;
  };
  if (others.size() == 0) return f(others).value;
  if (!std::isfinite(f(others).value)) others.setZero();
  auto result = minimize(f, others);
  if (problem.layout.fit_lapse) {
    // A lapse rate driven to 0 saturates its logistic, where Newton steps stall: also start
    // from a lapse of 2 % and keep the better.
    Eigen::VectorXd reset = result.x;
    reset[reset.size() - 1] = initial_lapse_logit(problem.layout);
    if (std::isfinite(f(reset).value)) {
      auto second = minimize(f, reset);
      if (second.value < result.value) result = std::move(second);
    }
  }
  others = result.x;
  return result.value;
}

}  // namespace

double profile_limit(const PsychometricProblem& problem, const Eigen::VectorXd& optimum,
                     double minimum, double cut, int direction) {
  const int s = problem.layout.spread_index();
  Eigen::VectorXd others(optimum.size() - 1);
  for (Eigen::Index i = 0, j = 0; i < optimum.size(); ++i) {
    if (i != s) others[j++] = optimum[i];
  }
  const double centre = optimum[s];
  // Points computed so far (ln spread, the other parameters' maximiser): each new point
  // starts from the nearest.
  std::vector<std::pair<double, Eigen::VectorXd>> seen{{centre, others}};
  const auto rise = [&](double log_spread) {
    const auto nearest =
        std::min_element(seen.begin(), seen.end(), [&](const auto& a, const auto& b) {
          return std::abs(a.first - log_spread) < std::abs(b.first - log_spread);
        });
    Eigen::VectorXd warm = nearest->second;
    const double value = profile_at(problem, log_spread, warm) - minimum - cut;
    seen.emplace_back(log_spread, std::move(warm));
    return value;
  };
  double inside = centre, outside = centre;
  double inside_rise = -cut, outside_rise = 0.0;
  bool crossed = false;
  for (double distance = 0.1; distance <= 12.0; distance *= 1.5) {
    outside = centre + direction * distance;
    outside_rise = rise(outside);
    if (outside_rise > 0.0) {
      crossed = true;
      break;
    }
    inside = outside;
    inside_rise = outside_rise;
  }
  if (!crossed) return direction * kInfinity;
  std::uintmax_t iterations = 60;
  const bool ascending = inside < outside;
  const auto bracket = boost::math::tools::toms748_solve(
      rise, ascending ? inside : outside, ascending ? outside : inside,
      ascending ? inside_rise : outside_rise, ascending ? outside_rise : inside_rise,
      [](double a, double b) { return std::abs(a - b) <= 1e-7; }, iterations);
  return 0.5 * (bracket.first + bracket.second);
}

Eigen::Matrix3d psychometric_covariance(const PsychometricProblem& problem,
                                        const Eigen::VectorXd& optimum) {
  PsychometricLayout layout = problem.layout;
  const PsychometricValues v = unpack(optimum, layout);
  Eigen::VectorXd x = optimum;
  if (layout.fit_lapse &&
      (v.lapse < 1e-6 * layout.max_lapse || v.lapse > (1.0 - 1e-6) * layout.max_lapse)) {
    // The lapse at its bound: held there (its information vanishes).
    layout.fit_lapse = false;
    x = optimum.head(optimum.size() - 1);
  }
  PsychometricProblem held = problem;
  held.layout = layout;
  const Derivatives d = psychometric_derivatives(held, x);
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  if (!std::isfinite(d.value)) return covariance;
  const Eigen::MatrixXd inverse = d.hessian.inverse();
  if (!inverse.allFinite()) return covariance;
  const std::vector<int> kept = fitted_indices(layout);
  for (std::size_t i = 0; i < kept.size(); ++i)
    for (std::size_t j = 0; j < kept.size(); ++j)
      covariance(kept[i], kept[j]) = inverse(Eigen::Index(i), Eigen::Index(j));
  return covariance;
}

CurvePoint psychometric_curve_point(PsychometricShape shape, const PsychometricValues& values,
                                    const PsychometricLayout& layout,
                                    const Eigen::Matrix3d& covariance, double level, double z) {
  const LevelProbability l = level_probability(shape, values, layout, level);
  CurvePoint point;
  point.level = level;
  point.p = l.p;
  // logit P's gradient: ∇P / (P (1 − P)).
  const Eigen::Vector3d gradient = l.gradient / (l.p * l.q);
  const double sd = std::sqrt(std::max(0.0, gradient.dot(covariance * gradient)));
  const double logit = std::log(l.p) - std::log(l.q);
  point.low = logistic(logit - z * sd);
  point.high = logistic(logit + z * sd);
  return point;
}

}  // namespace doorbench::study::statistics
