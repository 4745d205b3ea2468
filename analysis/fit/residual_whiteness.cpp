#include "analysis/fit/residual_whiteness.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/number_format.h"

namespace doorbench {

namespace {

constexpr double kZ99 = 2.576;  // two-sided 99 % of the standard normal

// Each stroke's samples less its mean over the finite ones (non-finite ones stay NaN); the
// sum of squares and the count of finite samples are added to `sum_sq` and `count`.
std::vector<std::vector<double>> centred(const std::vector<std::vector<double>>& strokes,
                                         double& sum_sq, std::size_t& count) {
  std::vector<std::vector<double>> out;
  for (const std::vector<double>& values : strokes) {
    double sum = 0.0;
    std::size_t n = 0;
    for (double v : values) {
      if (std::isfinite(v)) {
        sum += v;
        ++n;
      }
    }
    const double mean = n > 0 ? sum / double(n) : 0.0;
    std::vector<double> c(values.size());
    for (std::size_t i = 0; i < values.size(); ++i) {
      c[i] = std::isfinite(values[i]) ? values[i] - mean : NAN;
      if (std::isfinite(c[i])) sum_sq += c[i] * c[i];
    }
    count += n;
    out.push_back(std::move(c));
  }
  return out;
}

// Σ over strokes and i of a[i] · b[i + lag] (lag may be negative), finite pairs only.
double lagged_sum(const std::vector<std::vector<double>>& a,
                  const std::vector<std::vector<double>>& b, int lag) {
  double sum = 0.0;
  for (std::size_t s = 0; s < a.size(); ++s) {
    const long n = long(a[s].size());
    for (long i = std::max(0L, -long(lag)); i < n && i + lag < n; ++i) {
      const double p = a[s][std::size_t(i)] * b[s][std::size_t(i + lag)];
      if (std::isfinite(p)) sum += p;
    }
  }
  return sum;
}

}  // namespace

int whiteness_max_lag(double step_s) {
  return step_s > 0 ? std::clamp(int(std::lround(0.5 / step_s)), 10, 500) : 10;
}

std::string ResidualWhiteness::summary() const {
  return printf_text(
      "residual autocorrelation: %d of %zu lags outside the 99 %% band (±%.3g); "
      "cross-correlation with the force: %d of %zu",
      auto_outside, autocorrelation.empty() ? std::size_t(0) : autocorrelation.size() - 1, band,
      cross_outside, cross_correlation.size());
}

namespace {

// One correlation's lags values[first …], lag (i − zero_index) · step_s.
struct Lags {
  const std::vector<double>& values;
  std::size_t first;
  std::size_t zero_index;
  int outside;

  std::size_t count() const { return values.size() > first ? values.size() - first : 0; }
  std::size_t largest() const {
    std::size_t at = first;
    for (std::size_t i = first; i < values.size(); ++i) {
      if (std::abs(values[i]) > std::abs(values[at])) at = i;
    }
    return at;
  }
  double largest_abs() const {
    return largest() < values.size() ? std::abs(values[largest()]) : 0.0;
  }
  // The verdict's rule (kWhitenessOutsideShare, kWhitenessPeakBands).
  bool white(double band) const {
    return outside <= kWhitenessOutsideShare * double(count()) &&
           largest_abs() <= kWhitenessPeakBands * band;
  }
  // "12 of 50 lags (largest |r| 0.63 at lag 0.005 s)"
  std::string text(double step_s) const {
    return printf_text("%d of %zu lags (largest |r| %.2g at lag %.3g s)", outside, count(),
                       largest_abs(), (double(largest()) - double(zero_index)) * step_s);
  }
};

}  // namespace

std::string ResidualWhiteness::report_line() const {
  const Lags autos{autocorrelation, 1, 0, auto_outside};
  const Lags cross{cross_correlation, 0, cross_correlation.size() / 2, cross_outside};
  const char* verdict =
      !cross.white(band) ? "not white: the residual follows the force (dynamics the model does not "
                           "reproduce, whatever the residual's size)"
      : !autos.white(band)
          ? "not white: correlated in time but not with the force (coloured noise such as the "
            "rate's filtering, or dynamics the force does not drive)"
          : "white: consistent with noise";
  return printf_text("residual whiteness: autocorrelation outside the 99 %% band (±%.3g) at ",
                     band) +
         autos.text(lag_step_s) + "; cross-correlation with the force outside it at " +
         cross.text(lag_step_s) + "; verdict: " + verdict;
}

ResidualWhiteness residual_whiteness(const std::vector<std::vector<double>>& residual,
                                     const std::vector<std::vector<double>>& force,
                                     double lag_step_s, int max_lag) {
  if (residual.size() != force.size()) {
    throw std::invalid_argument("residual whiteness: " + std::to_string(residual.size()) +
                                " residual strokes but " + std::to_string(force.size()) +
                                " force strokes");
  }
  for (std::size_t s = 0; s < residual.size(); ++s) {
    if (residual[s].size() != force[s].size()) {
      throw std::invalid_argument("residual whiteness: stroke " + std::to_string(s) + " has " +
                                  std::to_string(residual[s].size()) + " residuals but " +
                                  std::to_string(force[s].size()) + " forces");
    }
  }
  if (max_lag < 1) throw std::invalid_argument("residual whiteness: max_lag must be >= 1");
  double rr = 0.0, ff = 0.0;
  std::size_t n_r = 0, n_f = 0;
  const auto r = centred(residual, rr, n_r);
  const auto f = centred(force, ff, n_f);
  if (n_r < 2 * std::size_t(max_lag) || !(rr > 0.0) || !(ff > 0.0)) {
    throw std::invalid_argument("residual whiteness: " + std::to_string(n_r) +
                                " finite samples (not constant) needed at least " +
                                std::to_string(2 * max_lag));
  }
  ResidualWhiteness w;
  w.lag_step_s = lag_step_s;
  w.samples = n_r;
  w.band = kZ99 / std::sqrt(double(n_r));
  for (int k = 0; k <= max_lag; ++k) {
    w.autocorrelation.push_back(lagged_sum(r, r, k) / rr);
    if (k > 0 && std::abs(w.autocorrelation.back()) > w.band) ++w.auto_outside;
  }
  const double norm = std::sqrt(rr * ff);
  for (int k = -max_lag; k <= max_lag; ++k) {
    w.cross_correlation.push_back(lagged_sum(f, r, k) / norm);
    if (std::abs(w.cross_correlation.back()) > w.band) ++w.cross_outside;
  }
  return w;
}

}  // namespace doorbench
