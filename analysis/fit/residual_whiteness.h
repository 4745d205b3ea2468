#pragma once
// Is the rate residual noise or unmodelled dynamics? The residual's autocorrelation and its
// cross-correlation with the input (the handle force), with the 99 % band of a white
// sequence, as system-identification tools show them: a model that explains the data leaves
// a residual whose correlations stay inside the band at every lag but 0.
//
// Each stroke is one segment: products are summed within strokes only (a lag never
// reaches across two strokes), the means are removed per stroke, and the sums are
// normalised by the whole residual's (and force's) sum of squares, so r(0) = 1. The band is
// ±2.576 / √N with N the samples used (the large-sample distribution of a white sequence's
// correlation). Non-finite samples are left out (the pair at that lag is skipped).
//
// Pure functions: safe from any thread.
#include <cstddef>
#include <string>
#include <vector>

namespace doorbench {

struct ResidualWhiteness {
  double lag_step_s = 0.0;  // the samples' interval (lags are multiples of it)
  std::size_t samples = 0;  // N
  double band = 0.0;        // 2.576 / √N
  // Lags 0 … max_lag of the residual's autocorrelation (value[0] = 1).
  std::vector<double> autocorrelation;
  // Lags −max_lag … max_lag of the cross-correlation of the force leading the residual:
  // cross_correlation[max_lag + k] pairs force[i] with residual[i + k].
  std::vector<double> cross_correlation;
  int auto_outside = 0;   // lags 1 … max_lag outside the band
  int cross_outside = 0;  // lags −max_lag … max_lag outside the band
  // "residual autocorrelation: 3 of 50 lags outside the 99 % band (±0.012); cross-correlation
  // with the force: 0 of 101" — for reports.
  std::string summary() const;
  // One line for the fit's and the loop's text reports: each correlation's lags outside the
  // band, its largest |r| (lag 0 of the autocorrelation left out) and where, and the verdict
  // (kWhitenessOutsideShare, kWhitenessPeakBands), e.g. "residual whiteness: autocorrelation
  // outside the 99 % band (±0.012) at 12 of 50 lags (largest |r| 0.63 at lag 0.005 s);
  // cross-correlation with the force outside it at 0 of 101 lags (largest |r| 0.0081 at
  // lag -0.12 s); verdict: not white: ...". It says whether the residual is systematic, not
  // how large it is.
  std::string report_line() const;
};

// The verdict's rule: a correlation is not white when more than kWhitenessOutsideShare of
// its lags are outside the band (a white sequence leaves about 1 % outside a 99 % band by
// chance, and neighbouring lags of a finite record are themselves correlated) or its largest
// |r| is more than kWhitenessPeakBands times the band (one clear peak, e.g. a delay: 5.2
// standard deviations of a white sequence's correlation, which its largest of 1000 lags
// reaches with a probability below 1e-3).
inline constexpr double kWhitenessOutsideShare = 0.05;
inline constexpr double kWhitenessPeakBands = 2.0;

// The lags reports and the viewer show: 0.5 s of samples `step_s` apart, 10 … 500 lags.
int whiteness_max_lag(double step_s);

// `residual[s]` and `force[s]`: stroke s's samples (same lengths), `lag_step_s` apart.
// Throws std::invalid_argument when lengths differ, max_lag < 1, or fewer than
// 2 · max_lag finite samples are given.
ResidualWhiteness residual_whiteness(const std::vector<std::vector<double>>& residual,
                                     const std::vector<std::vector<double>>& force,
                                     double lag_step_s, int max_lag);

}  // namespace doorbench
