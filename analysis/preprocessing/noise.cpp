// The noise estimate of prepare() (docs/preprocessing.md, "Noise"): robust white-noise
// levels, the trusted still periods' pooled scatter, and the floor of a quantised angle.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>

#include "analysis/preprocessing/internal/prepare_stages.h"

namespace doorbench {

using namespace preprocessing_detail;

namespace {

// Robust white-noise estimate: residuals of a straight line fitted to blocks of this many
// samples (short enough that smooth motion is a line within a block).
constexpr std::size_t kNoiseBlock = 16;
// Median of χ²(k)/k for k = kNoiseBlock − 2 = 14 degrees of freedom (Wilson–Hilferty:
// (1 − 2/(9k))³ = 0.9531): the median block variance is this × σ².
constexpr double kChiSquareMedianRatio = 0.9531;
// Estimated noise levels never go below this fraction of the fallback (bench) figures.
constexpr double kNoiseFloorFraction = 0.01;

// Pooled standard deviation about a straight line (in time) fitted to each range.
std::optional<double> pooled_detrended_std(const std::vector<Range>& ranges,
                                           const std::vector<double>& time_s,
                                           const std::vector<double>& values) {
  double squares = 0, degrees = 0;
  for (const Range& r : ranges) {
    const std::size_t m = r.last - r.first + 1;
    if (m < 3) continue;
    double t_mean = 0, v_mean = 0;
    for (std::size_t i = r.first; i <= r.last; ++i) {
      t_mean += time_s[i];
      v_mean += values[i];
    }
    t_mean /= static_cast<double>(m);
    v_mean /= static_cast<double>(m);
    double stt = 0, stv = 0;
    for (std::size_t i = r.first; i <= r.last; ++i) {
      stt += (time_s[i] - t_mean) * (time_s[i] - t_mean);
      stv += (time_s[i] - t_mean) * (values[i] - v_mean);
    }
    const double slope = stt > 0 ? stv / stt : 0.0;
    for (std::size_t i = r.first; i <= r.last; ++i) {
      const double e = values[i] - v_mean - slope * (time_s[i] - t_mean);
      squares += e * e;
    }
    degrees += static_cast<double>(m - 2);
  }
  if (degrees <= 0) return std::nullopt;
  return std::sqrt(squares / degrees);
}

// The step of a quantised angle: the smallest non-zero change between successive samples,
// when every value is a whole multiple of it (within 1e-6 of a step); nullopt otherwise.
std::optional<double> angle_quantum(const std::vector<double>& angle) {
  double step = std::numeric_limits<double>::infinity();
  for (std::size_t i = 1; i < angle.size(); ++i) {
    const double change = std::abs(angle[i] - angle[i - 1]);
    if (change > 0) step = std::min(step, change);
  }
  if (!std::isfinite(step)) return std::nullopt;
  for (double value : angle) {
    const double multiple = value / step;
    if (std::abs(multiple - std::round(multiple)) > 1e-6) return std::nullopt;
  }
  return step;
}

// The standard deviation of smoothing_derivative's output for white noise of unit standard
// deviation on a uniform grid: the root of the sum of the squares of its impulse response.
double derivative_noise_gain(double cutoff_hz, double sample_rate_hz) {
  const auto half = static_cast<std::size_t>(std::ceil(20.0 * sample_rate_hz / cutoff_hz)) + 2;
  std::vector<double> time_s(2 * half + 1), impulse(2 * half + 1, 0.0);
  for (std::size_t i = 0; i < time_s.size(); ++i) {
    time_s[i] = static_cast<double>(i) / sample_rate_hz;
  }
  impulse[half] = 1.0;
  double squares = 0.0;
  for (double value : uniform_derivative(time_s, impulse, cutoff_hz, sample_rate_hz)) {
    squares += value * value;
  }
  return std::sqrt(squares);
}

}  // namespace

namespace preprocessing_detail {

double robust_noise(const std::vector<double>& values, const std::vector<std::uint8_t>& faults) {
  std::vector<double> variances;
  const double k_mean = 0.5 * static_cast<double>(kNoiseBlock - 1);
  double k_sq = 0;
  for (std::size_t k = 0; k < kNoiseBlock; ++k) {
    k_sq += (static_cast<double>(k) - k_mean) * (static_cast<double>(k) - k_mean);
  }
  for (std::size_t start = 0; start + kNoiseBlock <= values.size(); start += kNoiseBlock) {
    bool faulty = false;
    double mean = 0;
    for (std::size_t k = 0; k < kNoiseBlock; ++k) {
      faulty = faulty || faults[start + k] != 0;
      mean += values[start + k];
    }
    if (faulty) continue;
    mean /= static_cast<double>(kNoiseBlock);
    double slope = 0;
    for (std::size_t k = 0; k < kNoiseBlock; ++k) {
      slope += (static_cast<double>(k) - k_mean) * (values[start + k] - mean);
    }
    slope /= k_sq;
    double residual = 0;
    for (std::size_t k = 0; k < kNoiseBlock; ++k) {
      const double r = values[start + k] - mean - slope * (static_cast<double>(k) - k_mean);
      residual += r * r;
    }
    variances.push_back(residual / static_cast<double>(kNoiseBlock - 2));
  }
  if (variances.empty()) return std::nan("");
  return std::sqrt(median(std::move(variances)) / kChiSquareMedianRatio);
}

void estimate_noise(const Input& in, const Stillness& still, const std::vector<Range>& trusted,
                    const std::vector<Anchor>& anchors, const std::vector<double>& tested_rate,
                    const PreprocessingOptions& options, PreparedData& data) {
  if (still.periods.empty()) {
    data.notes.push_back("no still period: noise levels are the bench's figures");
  }
  const std::optional<double> rate_noise = pooled_detrended_std(trusted, in.t, tested_rate);
  data.rate_noise_rad_s =
      rate_noise ? std::max(*rate_noise, kNoiseFloorFraction * options.fallback_rate_noise_rad_s)
                 : options.fallback_rate_noise_rad_s;
  std::optional<double> angle_noise;
  if (in.mode == Mode::kFused) {
    std::vector<Range> regions;
    for (const Anchor& anchor : anchors) regions.push_back(anchor.region);
    angle_noise = pooled_detrended_std(regions, in.t, in.incl);
  } else if (in.mode == Mode::kRateOnly) {
    data.notes.push_back("angle noise: the fallback figure (no absolute angle sensor)");
  } else {
    angle_noise = pooled_detrended_std(trusted, in.t, in.angle);
  }
  data.angle_noise_rad =
      angle_noise ? std::max(*angle_noise, kNoiseFloorFraction * options.fallback_angle_noise_rad)
                  : options.fallback_angle_noise_rad;
}

void apply_quantisation_floor(const Input& in, double derivative_cutoff_hz, PreparedData& data) {
  if (in.angle.empty()) return;
  const std::optional<double> q = angle_quantum(in.angle);
  if (!q) return;
  const double quantisation_rad = *q / std::sqrt(12.0);
  if (!(quantisation_rad > data.angle_noise_rad)) return;
  data.angle_noise_rad = quantisation_rad;
  if (in.mode == Mode::kAngleOnly) {
    const double rate_floor =
        quantisation_rad * derivative_noise_gain(derivative_cutoff_hz, in.rate_hz);
    data.rate_noise_rad_s = std::max(data.rate_noise_rad_s, rate_floor);
  }
  data.notes.push_back("angle_rad is quantised in steps of " + text(*q) +
                       " rad: its noise is taken as at least the quantisation's (step / "
                       "sqrt(12))" +
                       (in.mode == Mode::kAngleOnly ? ", and the rate's as that through the "
                                                      "smoothing derivative"
                                                    : ""));
}

}  // namespace preprocessing_detail

}  // namespace doorbench
