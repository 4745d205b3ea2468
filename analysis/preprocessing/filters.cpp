// The filters of preprocessing.h: the zero-phase low-pass and the smoothing derivative, on
// uniform samples directly and on jittered ones through a uniform grid.
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "analysis/preprocessing/internal/prepare_stages.h"
#include "analysis/preprocessing/preprocessing.h"

namespace doorbench {

using namespace preprocessing_detail;

std::vector<double> zero_phase_lowpass(std::span<const double> values, double cutoff_hz,
                                       double sample_rate_hz) {
  if (!(sample_rate_hz > 0) || !(cutoff_hz > 0) || !(cutoff_hz < 0.5 * sample_rate_hz) ||
      !std::isfinite(sample_rate_hz)) {
    throw std::invalid_argument("zero_phase_lowpass: cut-off " + text(cutoff_hz) +
                                " Hz must be > 0 and below half the sample rate " +
                                text(sample_rate_hz) + " Hz");
  }
  const std::size_t n = values.size();
  if (n < 2) return std::vector<double>(values.begin(), values.end());
  // 2nd-order Butterworth by the bilinear transform, pre-warped: −3 dB at the cut-off per
  // pass, DC gain 1.
  const double k = std::tan(std::numbers::pi * cutoff_hz / sample_rate_hz);
  const double norm = 1.0 / (1.0 + std::numbers::sqrt2 * k + k * k);
  const double b0 = k * k * norm, b1 = 2.0 * b0, b2 = b0;
  const double a1 = 2.0 * (k * k - 1.0) * norm;
  const double a2 = (1.0 - std::numbers::sqrt2 * k + k * k) * norm;
  // Odd reflection about the end samples: a straight line continues as itself.
  const std::size_t pad =
      std::min(n - 1, static_cast<std::size_t>(std::ceil(3.0 * sample_rate_hz / cutoff_hz)));
  std::vector<double> x(n + 2 * pad);
  for (std::size_t i = 0; i < pad; ++i) {
    x[i] = 2.0 * values[0] - values[pad - i];
    x[pad + n + i] = 2.0 * values[n - 1] - values[n - 2 - i];
  }
  std::copy(values.begin(), values.end(), x.begin() + static_cast<std::ptrdiff_t>(pad));
  auto run = [&](std::vector<double>& signal) {
    // Direct form II transposed, started in the steady state of the first value.
    const double first = signal.front();
    double z1 = (1.0 - b0) * first, z2 = (b2 - a2) * first;
    for (double& v : signal) {
      const double in = v;
      const double out = b0 * in + z1;
      z1 = b1 * in - a1 * out + z2;
      z2 = b2 * in - a2 * out;
      v = out;
    }
  };
  run(x);
  std::reverse(x.begin(), x.end());
  run(x);
  std::reverse(x.begin(), x.end());
  return std::vector<double>(x.begin() + static_cast<std::ptrdiff_t>(pad),
                             x.begin() + static_cast<std::ptrdiff_t>(pad + n));
}

double auto_derivative_cutoff_hz(double sample_rate_hz) {
  return std::min(30.0, 0.25 * sample_rate_hz);
}

namespace {

// Whether every interval is within kJitterFraction of 1 / sample_rate_hz.
bool uniform_times(std::span<const double> time_s, double sample_rate_hz) {
  const double interval = 1.0 / sample_rate_hz;
  for (std::size_t i = 1; i < time_s.size(); ++i) {
    if (std::abs(time_s[i] - time_s[i - 1] - interval) > kJitterFraction * interval) return false;
  }
  return true;
}

// Linear interpolation of (x, y) at the increasing times `at` (held beyond the ends).
// Not interpolate_held (acquisition/session/interpolation.h): at a time equal to an
// interior x_k that returns y_k, this y_{k-1} + (y_k - y_{k-1}), which may differ from y_k
// in the last bit, and this walks the sorted times once instead of searching for each.
std::vector<double> interpolate_sorted(std::span<const double> x, std::span<const double> y,
                                       std::span<const double> at) {
  std::vector<double> out(at.size());
  std::size_t k = 1;
  for (std::size_t i = 0; i < at.size(); ++i) {
    if (at[i] <= x.front()) {
      out[i] = y.front();
      continue;
    }
    if (at[i] >= x.back()) {
      out[i] = y.back();
      continue;
    }
    while (x[k] < at[i]) ++k;
    const double s = (at[i] - x[k - 1]) / (x[k] - x[k - 1]);
    out[i] = y[k - 1] + s * (y[k] - y[k - 1]);
  }
  return out;
}

// The uniform grid time_s[0] + k / sample_rate_hz up to the last time.
std::vector<double> uniform_grid(std::span<const double> time_s, double sample_rate_hz) {
  const double span_s = time_s.back() - time_s.front();
  const auto count = static_cast<std::size_t>(std::floor(span_s * sample_rate_hz + 1e-9)) + 1;
  std::vector<double> grid(std::max<std::size_t>(count, 2));
  for (std::size_t k = 0; k < grid.size(); ++k) {
    grid[k] = time_s.front() + static_cast<double>(k) / sample_rate_hz;
  }
  return grid;
}

}  // namespace

namespace preprocessing_detail {

std::vector<double> uniform_derivative(std::span<const double> time_s,
                                       std::span<const double> values, double cutoff_hz,
                                       double sample_rate_hz) {
  const std::size_t n = values.size();
  std::vector<double> derivative(n, 0.0);
  if (n < 2) return derivative;
  const std::vector<double> smooth = zero_phase_lowpass(values, cutoff_hz, sample_rate_hz);
  derivative[0] = (smooth[1] - smooth[0]) / (time_s[1] - time_s[0]);
  derivative[n - 1] = (smooth[n - 1] - smooth[n - 2]) / (time_s[n - 1] - time_s[n - 2]);
  for (std::size_t i = 1; i + 1 < n; ++i) {
    derivative[i] = (smooth[i + 1] - smooth[i - 1]) / (time_s[i + 1] - time_s[i - 1]);
  }
  return derivative;
}

}  // namespace preprocessing_detail

namespace {

// `operation(times, values)` (samples in, samples out) on samples at `time_s`: directly when
// they are uniform, else on the uniform grid (values interpolated there, the result
// interpolated back). `name` is the caller's, for the message on mismatched lengths.
template <typename Operation>
std::vector<double> on_uniform_times(std::span<const double> time_s, std::span<const double> values,
                                     double sample_rate_hz, const char* name, Operation operation) {
  if (time_s.size() != values.size()) {
    throw std::invalid_argument(std::string(name) + ": as many times as values needed");
  }
  if (values.size() < 2 || uniform_times(time_s, sample_rate_hz)) {
    return operation(time_s, values);
  }
  const std::vector<double> grid = uniform_grid(time_s, sample_rate_hz);
  const std::vector<double> on_grid = interpolate_sorted(time_s, values, grid);
  return interpolate_sorted(grid, operation(grid, on_grid), time_s);
}

}  // namespace

std::vector<double> zero_phase_lowpass_at(std::span<const double> time_s,
                                          std::span<const double> values, double cutoff_hz,
                                          double sample_rate_hz) {
  return on_uniform_times(time_s, values, sample_rate_hz, "zero_phase_lowpass_at",
                          [&](std::span<const double>, std::span<const double> samples) {
                            return zero_phase_lowpass(samples, cutoff_hz, sample_rate_hz);
                          });
}

std::vector<double> smoothing_derivative(std::span<const double> time_s,
                                         std::span<const double> values, double cutoff_hz,
                                         double sample_rate_hz) {
  return on_uniform_times(time_s, values, sample_rate_hz, "smoothing_derivative",
                          [&](std::span<const double> times, std::span<const double> samples) {
                            return uniform_derivative(times, samples, cutoff_hz, sample_rate_hz);
                          });
}

}  // namespace doorbench
