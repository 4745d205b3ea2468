#include "analysis/preprocessing/preprocessing.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <optional>

#include "acquisition/session/interpolation.h"
#include "acquisition/session/session_csv.h"
#include "acquisition/session/session_file.h"
#include "core/number_format.h"
#include "core/units.h"

namespace doorbench {

namespace {

constexpr std::size_t kMinimumSamples = 10;
// Robust white-noise estimate: residuals of a straight line fitted to blocks of this many
// samples (short enough that smooth motion is a line within a block).
constexpr std::size_t kNoiseBlock = 16;
// Median of χ²(k)/k for k = kNoiseBlock − 2 = 14 degrees of freedom (Wilson–Hilferty:
// (1 − 2/(9k))³ = 0.9531): the median block variance is this × σ².
constexpr double kChiSquareMedianRatio = 0.9531;
// Estimated noise levels never go below this fraction of the fallback (bench) figures.
constexpr double kNoiseFloorFraction = 0.01;

std::string text(double value, int digits = 3) {
  char buffer[48];
  std::snprintf(buffer, sizeof buffer, "%.*g", digits, value);
  return buffer;
}

std::string seconds(double value) {
  char buffer[48];
  std::snprintf(buffer, sizeof buffer, "%.3f s", value);
  return buffer;
}

// Sample fault kinds (bits).
enum Fault : std::uint8_t {
  kSaturated = 1,
  kRateNonFinite = 2,
  kAngleNonFinite = 4,
  kForceNonFinite = 8,
  kGapBefore = 16,   // the interval ending at this sample is a gap
  kLost = 32,        // every measured column missing: a scan lost in recording (a gap)
  kImpossible = 64,  // a value beyond the physical limits (PreprocessingOptions::max_abs_*)
};

std::string describe_faults(std::uint8_t kinds, double gyro_limit_rad_s) {
  std::string out;
  auto add = [&out](const std::string& what) { out += (out.empty() ? "" : ", ") + what; };
  if (kinds & kSaturated) {
    add("gyroscope saturated (|rate_rad_s| >= " + text(gyro_limit_rad_s / kRadPerDeg, 4) + " deg/s)");
  }
  if (kinds & kRateNonFinite) add("non-finite rate_rad_s");
  if (kinds & kAngleNonFinite) add("non-finite angle_rad");
  if (kinds & kForceNonFinite) add("non-finite force_N");
  if (kinds & kGapBefore) add("gap in time_s");
  if (kinds & kLost) add("recording gap (samples lost)");
  if (kinds & kImpossible) add("physically impossible values");
  return out;
}

// Replaces non-finite values by linear interpolation in time between the nearest finite
// neighbours (the nearest one at the ends). Returns false when no value is finite.
bool fill_non_finite(std::vector<double>& values, const std::vector<double>& time_s) {
  const std::size_t n = values.size();
  std::size_t previous = n;  // index of the last finite value seen, n = none
  std::size_t i = 0;
  while (i < n) {
    if (std::isfinite(values[i])) {
      previous = i++;
      continue;
    }
    std::size_t next = i;
    while (next < n && !std::isfinite(values[next])) ++next;
    if (previous == n && next == n) return false;
    for (std::size_t k = i; k < next; ++k) {
      if (previous == n) {
        values[k] = values[next];
      } else if (next == n) {
        values[k] = values[previous];
      } else {
        const double s = (time_s[k] - time_s[previous]) / (time_s[next] - time_s[previous]);
        values[k] = values[previous] + s * (values[next] - values[previous]);
      }
    }
    i = next;
  }
  return true;
}

double median(std::vector<double> values) {
  const std::size_t middle = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(middle),
                   values.end());
  double result = values[middle];
  if (values.size() % 2 == 0) {
    result =
        0.5 * (result + *std::max_element(values.begin(),
                                          values.begin() + static_cast<std::ptrdiff_t>(middle)));
  }
  return result;
}

// Robust white-noise level of a signal: the median over blocks of kNoiseBlock samples
// (skipping blocks with faulty samples) of the variance about a fitted straight line.
// NaN when no block qualifies.
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

struct Range {
  std::size_t first = 0, last = 0;  // inclusive sample indices
};

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

double mean_over(const std::vector<double>& values, const Range& r) {
  double sum = 0;
  for (std::size_t i = r.first; i <= r.last; ++i) sum += values[i];
  return sum / static_cast<double>(r.last - r.first + 1);
}

std::size_t first_at_or_after(const std::vector<double>& time_s, double t) {
  return static_cast<std::size_t>(std::lower_bound(time_s.begin(), time_s.end(), t) -
                                  time_s.begin());
}

std::size_t last_at_or_before(const std::vector<double>& time_s, double t) {
  const auto after = std::upper_bound(time_s.begin(), time_s.end(), t);
  return after == time_s.begin() ? 0 : static_cast<std::size_t>(after - time_s.begin()) - 1;
}

// The still window used: still_window_s, never fewer than kStillWindowSamples samples.
double still_window_used_s(const PreprocessingOptions& options, double sample_rate_hz) {
  return std::max(options.still_window_s, kStillWindowSamples / sample_rate_hz);
}

// The stillness test (PreprocessingOptions): runs of quiet samples lasting
// still_min_duration_s or more.
std::vector<Range> find_still_periods(const std::vector<double>& time_s,
                                      const std::vector<double>& rate,
                                      const std::vector<double>& force,
                                      const std::vector<std::uint8_t>& faults,
                                      double rate_std_limit, double sample_rate_hz,
                                      const PreprocessingOptions& options) {
  const std::size_t n = time_s.size();
  const auto half = static_cast<std::size_t>(std::max(
      1.0, std::round(0.5 * still_window_used_s(options, sample_rate_hz) * sample_rate_hz)));
  // Prefix sums, the rate centred on its mean to keep the variance's cancellation small.
  double centre = 0;
  for (double r : rate) centre += r;
  centre /= static_cast<double>(n);
  std::vector<double> s1(n + 1, 0.0), s2(n + 1, 0.0), sf(n + 1, 0.0);
  std::vector<std::size_t> sb(n + 1, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const double r = rate[i] - centre;
    s1[i + 1] = s1[i] + r;
    s2[i + 1] = s2[i] + r * r;
    sf[i + 1] = sf[i] + std::abs(force[i]);
    sb[i + 1] = sb[i] + (faults[i] != 0);
  }
  std::vector<Range> periods;
  std::size_t run_start = n;  // n = not in a run
  auto close_run = [&](std::size_t end_exclusive) {
    if (run_start < end_exclusive) {
      // Trimmed by the guard at both ends (a motion that starts gently passes the test for
      // a while), then long enough?
      const std::size_t first =
          first_at_or_after(time_s, time_s[run_start] + options.still_guard_s);
      const std::size_t last =
          last_at_or_before(time_s, time_s[end_exclusive - 1] - options.still_guard_s);
      if (first < last && time_s[last] - time_s[first] >= options.still_min_duration_s) {
        periods.push_back({first, last});
      }
    }
    run_start = n;
  };
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t lo = i >= half ? i - half : 0;
    const std::size_t hi = std::min(n - 1, i + half);
    const double m = static_cast<double>(hi - lo + 1);
    const double mean = (s1[hi + 1] - s1[lo]) / m;
    const double variance = std::max(0.0, (s2[hi + 1] - s2[lo]) / m - mean * mean);
    const bool quiet = sb[hi + 1] == sb[lo] && std::sqrt(variance) < rate_std_limit &&
                       std::abs(mean + centre) < options.still_rate_limit_rad_s &&
                       (sf[hi + 1] - sf[lo]) / m < options.still_force_N;
    if (quiet && run_start == n) run_start = i;
    if (!quiet) close_run(i);
  }
  close_run(n);
  return periods;
}

enum class Mode { kFused, kRateOnly, kAngleAndRate, kAngleOnly };

struct Anchor {
  Range period;  // the still period (bias from here)
  Range region;  // where the absolute angle is compared (offset from here)
  double time_s = 0;
  std::size_t index = 0;  // the region's middle sample
  double bias = 0;
  bool has_bias = true;
  double offset = 0;
};

struct Candidate {
  Range range;
  int id = 0;
};

// Motion segments of ω (see PreprocessingOptions, segmentation). Segments too short to be
// strokes go to `excluded`. Ids are 1, 2, … in time order.
std::vector<Candidate> segment_strokes(const std::vector<double>& time_s,
                                       const std::vector<double>& theta,
                                       const std::vector<double>& omega, double edge_rate,
                                       const PreprocessingOptions& options,
                                       std::vector<ExcludedSegment>& excluded) {
  const std::size_t n = time_s.size();
  struct Run {
    std::size_t lo, hi;
    int sign;
  };
  std::vector<Run> runs;
  std::size_t i = 0;
  while (i < n) {
    if (std::abs(omega[i]) <= options.motion_rate_rad_s) {
      ++i;
      continue;
    }
    const int sign = omega[i] > 0 ? 1 : -1;
    std::size_t lo = i, hi = i;
    while (hi + 1 < n && sign * omega[hi + 1] > options.motion_rate_rad_s) ++hi;
    i = hi + 1;
    while (lo > 0 && sign * omega[lo - 1] > edge_rate) --lo;
    while (hi + 1 < n && sign * omega[hi + 1] > edge_rate) ++hi;
    if (!runs.empty() && runs.back().sign == sign && lo <= runs.back().hi + 1) {
      runs.back().hi = std::max(runs.back().hi, hi);
    } else {
      runs.push_back({lo, hi, sign});
    }
    i = std::max(i, hi + 1);
  }

  auto net = [&](const Run& r) { return theta[r.hi] - theta[r.lo]; };
  auto tiny = [&](const Run& r) { return std::abs(net(r)) < options.min_stroke_angle_rad; };
  std::vector<Run> merged;
  for (const Run& run : runs) {
    if (!merged.empty()) {
      Run& current = merged.back();
      const double gap_s = time_s[run.lo] - time_s[current.hi];
      const bool same_way = (net(current) > 0) == (net(run) > 0);
      if (gap_s < options.merge_gap_s && (same_way || tiny(current) || tiny(run))) {
        current.hi = run.hi;
        continue;
      }
    }
    merged.push_back(run);
  }

  std::vector<Run> kept;
  for (const Run& run : merged) {
    const double duration_s = time_s[run.hi] - time_s[run.lo];
    const double angle = net(run);
    if (duration_s < options.min_stroke_duration_s ||
        std::abs(angle) < options.min_stroke_angle_rad) {
      excluded.push_back({time_s[run.lo], time_s[run.hi],
                          "movement too short for a stroke (" + text(duration_s) + " s, " +
                              text(angle / kRadPerDeg) +
                              " deg; a stroke needs >= " + text(options.min_stroke_duration_s) +
                              " s and >= " + text(options.min_stroke_angle_rad / kRadPerDeg) + " deg)"});
    } else {
      kept.push_back(run);
    }
  }

  // The margins of rest before and after, never past the middle of the gap to a neighbour.
  std::vector<Candidate> strokes;
  for (std::size_t k = 0; k < kept.size(); ++k) {
    std::size_t lo = first_at_or_after(time_s, time_s[kept[k].lo] - options.stroke_margin_s);
    std::size_t hi = last_at_or_before(time_s, time_s[kept[k].hi] + options.stroke_margin_s);
    if (k > 0) lo = std::max(lo, (kept[k - 1].hi + kept[k].lo) / 2 + 1);
    if (k + 1 < kept.size()) hi = std::min(hi, (kept[k].hi + kept[k + 1].lo) / 2);
    strokes.push_back({{lo, hi}, static_cast<int>(k + 1)});
  }
  return strokes;
}

std::vector<Candidate> strokes_from_column(const std::vector<int>& stroke) {
  std::vector<Candidate> strokes;
  std::size_t i = 0;
  while (i < stroke.size()) {
    if (stroke[i] == 0) {
      ++i;
      continue;
    }
    std::size_t last = i;
    while (last + 1 < stroke.size() && stroke[last + 1] == stroke[i]) ++last;
    strokes.push_back({{i, last}, stroke[i]});
    i = last + 1;
  }
  return strokes;
}

std::optional<std::size_t> find_inclinometer(const Recording& recording,
                                             const PreprocessingOptions& options) {
  for (std::size_t e = 0; e < recording.extra_names.size(); ++e) {
    const std::string& name = recording.extra_names[e];
    if (!options.inclinometer_column.empty()) {
      if (name == options.inclinometer_column) return e;
      continue;
    }
    const bool ends_rad = name.size() > 4 && name.compare(name.size() - 4, 4, "_rad") == 0;
    const bool ends_deg = name.size() > 4 && name.compare(name.size() - 4, 4, "_deg") == 0;
    if (name.rfind("inclinometer", 0) == 0 && (ends_rad || ends_deg)) return e;
  }
  return std::nullopt;
}

void check_length(const Recording& recording, const std::string& column, std::size_t size) {
  if (size != recording.size()) {
    throw PreprocessingError(recording.source + ": column " + column + " has " +
                             std::to_string(size) + " values, time_s has " +
                             std::to_string(recording.size()));
  }
}

}  // namespace

std::string PreprocessingOptions::validate() const {
  struct Rule {
    const char* name;
    double value;
    bool strictly_positive;  // else >= 0
  };
  const Rule rules[] = {
      {"still_window_s", still_window_s, true},
      {"still_min_duration_s", still_min_duration_s, true},
      {"still_guard_s", still_guard_s, false},
      {"still_noise_factor", still_noise_factor, true},
      {"still_rate_std_floor_rad_s", still_rate_std_floor_rad_s, false},
      {"still_rate_limit_rad_s", still_rate_limit_rad_s, true},
      {"still_force_N", still_force_N, true},
      {"bias_consistency_rad_s", bias_consistency_rad_s, true},
      {"gyro_range_rad_s", gyro_range_rad_s, true},
      {"gyro_saturation_fraction", gyro_saturation_fraction, false},
      {"inclinometer_range_rad", inclinometer_range_rad, true},
      {"inclinometer_margin_rad", inclinometer_margin_rad, false},
      {"inclinometer_settle_s", inclinometer_settle_s, false},
      {"derivative_cutoff_hz", derivative_cutoff_hz, false},
      {"min_sample_rate_hz", min_sample_rate_hz, true},
      {"force_cutoff_hz", force_cutoff_hz, false},
      {"motion_rate_rad_s", motion_rate_rad_s, true},
      {"edge_rate_rad_s", edge_rate_rad_s, false},
      {"merge_gap_s", merge_gap_s, false},
      {"stroke_margin_s", stroke_margin_s, false},
      {"min_stroke_duration_s", min_stroke_duration_s, false},
      {"min_stroke_angle_rad", min_stroke_angle_rad, false},
      {"max_gap_factor", max_gap_factor, true},
      {"max_bridged_loss_s", max_bridged_loss_s, false},
      {"max_abs_force_N", max_abs_force_N, true},
      {"max_abs_angle_rad", max_abs_angle_rad, true},
      {"impossible_factor", impossible_factor, true},
      {"fallback_angle_noise_rad", fallback_angle_noise_rad, true},
      {"fallback_rate_noise_rad_s", fallback_rate_noise_rad_s, true},
  };
  for (const Rule& rule : rules) {
    const std::string head =
        std::string("preprocessing ") + rule.name + " = " + format_number(rule.value) + " must be ";
    if (!std::isfinite(rule.value)) return head + "finite";
    if (rule.strictly_positive && !(rule.value > 0)) return head + "> 0";
    if (!rule.strictly_positive && !(rule.value >= 0)) return head + ">= 0";
  }
  if (gyro_saturation_fraction >= 1) {
    return "preprocessing gyro_saturation_fraction = " + format_number(gyro_saturation_fraction) +
           " must be < 1";
  }
  if (inclinometer_margin_rad >= inclinometer_range_rad) {
    return "preprocessing inclinometer_margin_rad = " + format_number(inclinometer_margin_rad) +
           " must be < inclinometer_range_rad = " + format_number(inclinometer_range_rad);
  }
  if (edge_rate_rad_s > motion_rate_rad_s) {
    return "preprocessing edge_rate_rad_s = " + format_number(edge_rate_rad_s) +
           " must be <= motion_rate_rad_s = " + format_number(motion_rate_rad_s);
  }
  if (max_gap_factor <= 1) {
    return "preprocessing max_gap_factor = " + format_number(max_gap_factor) + " must be > 1";
  }
  return "";
}

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

}  // namespace

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

namespace {

// The recording's columns, checked, with the method chosen, faults marked and non-finite
// values bridged (they are never used as values: a stroke holding one is left out).
struct Input {
  std::string source;
  Mode mode = Mode::kFused;
  bool has_rate = false;
  std::vector<double> t, force, rate, angle, incl;  // rate, angle, incl: empty when absent
  std::string inclinometer_name;
  std::vector<std::uint8_t> fault;
  std::vector<std::string> warnings;       // physically impossible samples, per channel
  std::vector<std::uint8_t> motion_fault;  // fault without a bad force alone (stillness test)
  // unknown[i] counts the intervals in (0, i] over which the rate is unknown: saturated or
  // non-finite at either end, or a gap.
  std::vector<std::size_t> unknown;
  double median_interval_s = 0;
  double min_interval_s = 0, max_interval_s = 0;
  bool jittered = false;  // an interval differs from the median by more than kJitterFraction
  double rate_hz = 0;     // 1 / median interval: what the filters use
  double saturation_limit = 0;

  std::size_t size() const { return t.size(); }
  void check_cutoff(double cutoff_hz, const char* name) const {
    if (!(cutoff_hz < 0.5 * rate_hz)) {
      throw PreprocessingError(source + ": " + name + " " + text(cutoff_hz) +
                               " Hz is not below half the sample rate (" + text(0.5 * rate_hz) +
                               " Hz)");
    }
  }
};

// The columns' lengths, at least one motion column, finite and strictly increasing times.
void check_columns(const Recording& recording) {
  const std::string& source = recording.source;
  const std::size_t n = recording.size();
  if (n < kMinimumSamples) {
    throw PreprocessingError(source + ": too few samples to prepare (" + std::to_string(n) +
                             "; at least " + std::to_string(kMinimumSamples) + " needed)");
  }
  check_length(recording, "force_N", recording.force_N.size());
  if (!recording.rate_rad_s && !recording.angle_rad) {
    throw PreprocessingError(source +
                             ": neither rate_rad_s nor angle_rad (at least one is needed)");
  }
  if (recording.rate_rad_s) check_length(recording, "rate_rad_s", recording.rate_rad_s->size());
  if (recording.angle_rad) check_length(recording, "angle_rad", recording.angle_rad->size());
  if (recording.stroke) check_length(recording, "stroke", recording.stroke->size());
  const std::vector<double>& t = recording.time_s;
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(t[i]) || (i > 0 && !(t[i] > t[i - 1]))) {
      throw PreprocessingError(source + ": time_s must be finite and strictly increasing (row " +
                               std::to_string(i + 1) + " of the data)");
    }
  }
}

// The method from the columns there: angle and rate, angle only, rate fused with an
// inclinometer, or rate only; the inclinometer's column in radians when fused.
void choose_mode(const Recording& recording, const PreprocessingOptions& options, Input& in) {
  const std::optional<std::size_t> inclinometer = find_inclinometer(recording, options);
  if (!options.inclinometer_column.empty() && !inclinometer) {
    throw PreprocessingError(in.source + ": no column " + options.inclinometer_column +
                             " (the inclinometer_column option)");
  }
  if (inclinometer) {
    in.inclinometer_name = recording.extra_names[*inclinometer];
    check_length(recording, in.inclinometer_name, recording.extra_columns[*inclinometer].size());
  }
  if (recording.rate_rad_s && recording.angle_rad) {
    in.mode = Mode::kAngleAndRate;
  } else if (recording.angle_rad) {
    in.mode = Mode::kAngleOnly;
  } else if (inclinometer) {
    in.mode = Mode::kFused;
  } else {
    in.mode = Mode::kRateOnly;
  }
  in.has_rate = in.mode != Mode::kAngleOnly;
  if (in.mode == Mode::kFused) {
    in.incl = recording.extra_columns[*inclinometer];
    const std::string& name = in.inclinometer_name;
    if (name.compare(name.size() - 4, 4, "_deg") == 0) {
      for (double& v : in.incl) v *= kRadPerDeg;
    }
  }
}

// The median interval (the filters' rate) and the spread of the intervals, gaps (which
// are listed as faults) left out. Throws for a rate below min_sample_rate_hz.
void measure_intervals(const PreprocessingOptions& options, Input& in) {
  const std::vector<double>& t = in.t;
  std::vector<double> intervals(t.size() - 1);
  for (std::size_t i = 1; i < t.size(); ++i) intervals[i - 1] = t[i] - t[i - 1];
  in.median_interval_s = median(intervals);
  in.rate_hz = 1.0 / in.median_interval_s;
  in.min_interval_s = in.median_interval_s;
  in.max_interval_s = in.median_interval_s;
  for (double interval : intervals) {
    if (interval > options.max_gap_factor * in.median_interval_s) continue;
    in.min_interval_s = std::min(in.min_interval_s, interval);
    in.max_interval_s = std::max(in.max_interval_s, interval);
  }
  in.jittered =
      std::max(in.max_interval_s - in.median_interval_s, in.median_interval_s - in.min_interval_s) >
      kJitterFraction * in.median_interval_s;
  if (in.rate_hz < options.min_sample_rate_hz) {
    // Enough digits that the two rates differ (issue 33: "at 20 Hz, below the 20 Hz").
    int digits = 3;
    while (digits < 12 && text(in.rate_hz, digits) == text(options.min_sample_rate_hz, digits)) {
      ++digits;
    }
    throw PreprocessingError(in.source + ": sampled at " + text(in.rate_hz, digits) +
                             " Hz (1 / the median interval), below the " +
                             text(options.min_sample_rate_hz, digits) +
                             " Hz preprocessing supports by default; rates from " +
                             text(options.min_sample_rate_hz, digits) +
                             " Hz up are used as they are (give --min-sample-rate-hz to "
                             "accept a slower recording, at the cost of the fastest motion)");
  }
}

// Physically impossible values (|value| > limit) of one column: replaced by NaN, marked
// kImpossible in in.fault (and in `motion_impossible` when given), said in a warning
// (channel, time, value).
void exclude_impossible(std::vector<double>& values, const std::string& name, double limit,
                        const char* unit, Input& in, std::vector<bool>* motion_impossible) {
  std::size_t count = 0, first = 0;
  double largest = 0.0;
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!std::isfinite(values[i]) || std::abs(values[i]) <= limit) continue;
    if (count++ == 0) first = i;
    if (std::abs(values[i]) > std::abs(largest)) largest = values[i];
    values[i] = std::numeric_limits<double>::quiet_NaN();
    in.fault[i] |= kImpossible;
    if (motion_impossible != nullptr) (*motion_impossible)[i] = true;
  }
  if (count == 0) return;
  char line[300];
  std::snprintf(line, sizeof line,
                "%s: %zu physically impossible sample%s (|value| > %.6g %s) from %.3f s, "
                "the largest %.6g %s: not used",
                name.c_str(), count, count == 1 ? "" : "s", limit, unit, in.t[first], largest,
                unit);
  in.warnings.emplace_back(line);
}

// Impossible values in every column: never used, always said. Returns, per sample,
// whether the rate or the angle was impossible.
std::vector<bool> exclude_impossible_values(const PreprocessingOptions& options, Input& in) {
  std::vector<bool> motion_impossible(in.size(), false);
  exclude_impossible(in.force, "force_N", options.max_abs_force_N, "N", in, nullptr);
  if (in.has_rate) {
    exclude_impossible(in.rate, "rate_rad_s", options.impossible_factor * options.gyro_range_rad_s,
                       "rad/s", in, &motion_impossible);
  }
  if (!in.angle.empty()) {
    exclude_impossible(in.angle, "angle_rad", options.max_abs_angle_rad, "rad", in,
                       &motion_impossible);
  }
  if (!in.incl.empty()) {
    const std::vector<std::uint8_t> before = in.fault;
    exclude_impossible(in.incl, in.inclinometer_name,
                       options.impossible_factor * options.inclinometer_range_rad, "rad", in,
                       nullptr);
    in.fault = before;  // an inclinometer sample is no stroke's fault: it only anchors
  }
  return motion_impossible;
}

// Each sample's faults: non-finite (an impossible value, now NaN, counts as unknown like
// a non-finite one and is described as impossible), saturated, a gap before it, lost.
void mark_faults(const Recording& recording, const PreprocessingOptions& options, Input& in) {
  const std::vector<double>& t = in.t;
  for (std::size_t i = 0; i < in.size(); ++i) {
    std::uint8_t& f = in.fault[i];
    const bool impossible = (f & kImpossible) != 0;
    if (!std::isfinite(in.force[i]) && !(impossible && std::isfinite(recording.force_N[i]))) {
      f |= kForceNonFinite;
    }
    if (in.has_rate && !std::isfinite(in.rate[i])) {
      f |= impossible && std::isfinite((*recording.rate_rad_s)[i]) ? kImpossible : kRateNonFinite;
    }
    if (in.has_rate && std::abs(in.rate[i]) >= in.saturation_limit) f |= kSaturated;
    if (!in.angle.empty() && !std::isfinite(in.angle[i]) &&
        !(impossible && std::isfinite((*recording.angle_rad)[i]))) {
      f |= kAngleNonFinite;
    }
    if (i > 0 && t[i] - t[i - 1] > options.max_gap_factor * in.median_interval_s) f |= kGapBefore;
    // A lost scan (a session's gap, an export's empty cells) is missing on every channel.
    const bool lost = !std::isfinite(in.force[i]) && (!in.has_rate || !std::isfinite(in.rate[i])) &&
                      (in.angle.empty() || !std::isfinite(in.angle[i])) &&
                      (in.incl.empty() || !std::isfinite(in.incl[i]));
    if (lost) f |= kLost;
  }
}

// Non-finite values bridged in every column; a column without any finite value throws.
void fill_non_finite_values(Input& in) {
  if (!fill_non_finite(in.force, in.t)) {
    throw PreprocessingError(in.source + ": no finite force_N value");
  }
  if (in.has_rate && !fill_non_finite(in.rate, in.t)) {
    throw PreprocessingError(in.source + ": no finite rate_rad_s value");
  }
  if (!in.angle.empty() && !fill_non_finite(in.angle, in.t)) {
    throw PreprocessingError(in.source + ": no finite angle_rad value");
  }
}

// A short run of lost scans (a ring overflow of a few blocks) is bridged: the rate
// interpolated across it stands for the rate, so the drift between the anchors around it
// is still removed and the strokes beside it keep their accuracy. (The strokes holding it
// are left out all the same.) A longer loss, like any other fault, makes the rate unknown.
// Returns, per sample, whether it is bridged.
std::vector<bool> bridged_losses(const PreprocessingOptions& options, const Input& in) {
  const std::vector<double>& t = in.t;
  const std::size_t n = in.size();
  std::vector<bool> bridged(n, false);
  for (std::size_t i = 0; i < n;) {
    if (!(in.fault[i] & kLost)) {
      ++i;
      continue;
    }
    std::size_t end = i;
    while (end < n && (in.fault[end] & kLost)) ++end;
    const double lost_s = (end < n ? t[end] : t[n - 1]) - (i > 0 ? t[i - 1] : t[0]);
    if (i > 0 && end < n && lost_s <= options.max_bridged_loss_s + 0.5 * in.median_interval_s) {
      for (std::size_t k = i; k < end; ++k) bridged[k] = true;
    }
    i = end;
  }
  return bridged;
}

// What the stillness test may not look through: every fault but a missing or impossible
// force alone (the rate still says whether the door moves; the force there is bridged).
std::vector<std::uint8_t> motion_faults(const Input& in,
                                        const std::vector<bool>& motion_impossible) {
  std::vector<std::uint8_t> motion_fault = in.fault;
  for (std::size_t i = 0; i < in.size(); ++i) {
    const std::uint8_t others = in.fault[i] & ~(kForceNonFinite | kImpossible);
    if (others == 0 && !motion_impossible[i]) motion_fault[i] = 0;
  }
  return motion_fault;
}

// unknown[i]: the intervals in (0, i] over which the rate is unknown (a rate fault not
// bridged at either end, or a gap).
std::vector<std::size_t> count_unknown_intervals(const Recording& recording,
                                                 const PreprocessingOptions& options,
                                                 const Input& in,
                                                 const std::vector<bool>& bridged) {
  const std::size_t n = in.size();
  std::vector<std::size_t> unknown(n, 0);
  if (!in.has_rate) return unknown;
  std::vector<bool> rate_impossible(n, false);
  for (std::size_t i = 0; i < n; ++i) {
    rate_impossible[i] =
        std::isfinite((*recording.rate_rad_s)[i]) &&
        std::abs((*recording.rate_rad_s)[i]) > options.impossible_factor * options.gyro_range_rad_s;
  }
  const std::uint8_t rate_faults = kSaturated | kRateNonFinite;
  auto rate_fault = [&](std::size_t i) {
    return ((in.fault[i] & rate_faults) || rate_impossible[i]) && !bridged[i];
  };
  for (std::size_t i = 1; i < n; ++i) {
    const bool u = rate_fault(i) || (in.fault[i] & kGapBefore) || rate_fault(i - 1);
    unknown[i] = unknown[i - 1] + (u ? 1 : 0);
  }
  return unknown;
}

Input read_input(const Recording& recording, const PreprocessingOptions& options) {
  check_columns(recording);
  Input in;
  in.source = recording.source;
  in.t = recording.time_s;
  choose_mode(recording, options, in);
  measure_intervals(options, in);
  in.force = recording.force_N;
  if (in.has_rate) in.rate = *recording.rate_rad_s;
  if (recording.angle_rad) in.angle = *recording.angle_rad;
  in.saturation_limit = (1.0 - options.gyro_saturation_fraction) * options.gyro_range_rad_s;
  in.fault.assign(in.size(), 0);
  const std::vector<bool> motion_impossible = exclude_impossible_values(options, in);
  mark_faults(recording, options, in);
  fill_non_finite_values(in);
  const std::vector<bool> bridged = bridged_losses(options, in);
  in.motion_fault = motion_faults(in, motion_impossible);
  in.unknown = count_unknown_intervals(recording, options, in, bridged);
  return in;
}

struct Stillness {
  double noise_estimate = 0;  // σ̂ of the tested rate (NaN when no block qualified)
  double rate_std_limit = 0;
  std::vector<Range> periods;
  std::string rule;  // the test with its thresholds, for messages
};

Stillness find_stillness(const Input& in, const std::vector<double>& rate,
                         const PreprocessingOptions& options) {
  Stillness still;
  still.noise_estimate = robust_noise(rate, in.motion_fault);
  still.rate_std_limit =
      std::max(options.still_noise_factor *
                   (std::isfinite(still.noise_estimate) ? still.noise_estimate : 0.0),
               options.still_rate_std_floor_rad_s);
  still.periods = find_still_periods(in.t, rate, in.force, in.motion_fault, still.rate_std_limit,
                                     in.rate_hz, options);
  still.rule = "still: over " + text(still_window_used_s(options, in.rate_hz)) +
               " s windows the rate's std < " + text(still.rate_std_limit / kRadPerDeg) +
               " deg/s, |mean rate| < " + text(options.still_rate_limit_rad_s / kRadPerDeg) +
               " deg/s and mean |force| < " + text(options.still_force_N) +
               " N, for >= " + text(options.still_min_duration_s) + " s";
  return still;
}

// Anchors: still periods where the absolute angle is known (for the rate only: the still
// periods with a consistent bias), each with a bias sample (the mean rate over the period).
// Throws when the method needs an anchor and there is none.
std::vector<Anchor> find_anchors(const Input& in, const Stillness& still,
                                 const PreprocessingOptions& options) {
  const std::vector<double>& t = in.t;
  auto make_anchor = [&](const Range& period, const Range& region) {
    Anchor anchor;
    anchor.period = period;
    anchor.region = region;
    anchor.index = (region.first + region.last) / 2;
    anchor.time_s = t[anchor.index];
    anchor.bias = in.has_rate ? mean_over(in.rate, period) : 0.0;
    return anchor;
  };
  std::vector<Anchor> anchors;
  if (in.mode == Mode::kFused) {
    const double limit = options.inclinometer_range_rad - options.inclinometer_margin_rad;
    for (const Range& period : still.periods) {
      const Range region{first_at_or_after(t, t[period.first] + options.inclinometer_settle_s),
                         period.last};
      if (region.first + 2 > region.last) continue;
      bool valid = true;
      for (std::size_t i = region.first; i <= region.last && valid; ++i) {
        valid = std::isfinite(in.incl[i]) && std::abs(in.incl[i]) < limit;
      }
      if (valid) anchors.push_back(make_anchor(period, region));
    }
    if (anchors.empty()) {
      throw PreprocessingError(
          in.source + ": no still period with the inclinometer (" + in.inclinometer_name +
          ") inside +-" + text(limit / kRadPerDeg) + " deg to anchor the integrated gyroscope to (" +
          std::to_string(still.periods.size()) + " still periods found; " + still.rule + ")");
    }
  } else if (in.mode == Mode::kAngleAndRate) {
    for (const Range& period : still.periods) anchors.push_back(make_anchor(period, period));
    if (anchors.empty()) {
      // No still period: the recording's first and last windows, without bias samples.
      const std::size_t n = in.size();
      const auto w = static_cast<std::size_t>(std::clamp(
          std::round(options.still_window_s * in.rate_hz), 1.0, static_cast<double>(n / 2)));
      for (const Range r : {Range{0, w - 1}, Range{n - w, n - 1}}) {
        Anchor anchor = make_anchor(r, r);
        anchor.has_bias = false;
        anchors.push_back(anchor);
      }
    }
  } else if (in.mode == Mode::kRateOnly) {
    if (still.periods.empty()) {
      throw PreprocessingError(in.source +
                               ": rate_rad_s only, and no still period to estimate the "
                               "gyroscope bias and start theta = 0 from (" +
                               still.rule + ")");
    }
    std::vector<double> means;
    for (const Range& period : still.periods) means.push_back(mean_over(in.rate, period));
    const double typical = median(means);
    std::size_t closest = 0;
    for (std::size_t p = 0; p < means.size(); ++p) {
      if (std::abs(means[p] - typical) <= options.bias_consistency_rad_s) {
        anchors.push_back(make_anchor(still.periods[p], still.periods[p]));
      }
      if (std::abs(means[p] - typical) < std::abs(means[closest] - typical)) closest = p;
    }
    if (anchors.empty()) {
      anchors.push_back(make_anchor(still.periods[closest], still.periods[closest]));
    }
  }
  return anchors;
}

struct Motion {
  std::vector<double> theta, omega;
  double mean_bias = 0;  // of the bias removed from the rate
};

// The bias piecewise-linear through the anchors' bias samples, the rate integrated
// (trapezoid), and the drift removed between the anchors (docs/preprocessing.md). Sets each
// anchor's offset; for the rate only, keeps just the first anchor (theta = 0 there).
Motion integrate_and_anchor(const Input& in, std::vector<Anchor>& anchors) {
  const std::vector<double>& t = in.t;
  const std::size_t n = in.size();
  std::vector<double> bias_t, bias_v;
  for (const Anchor& anchor : anchors) {
    if (!anchor.has_bias) continue;
    bias_t.push_back(0.5 * (t[anchor.period.first] + t[anchor.period.last]));
    bias_v.push_back(anchor.bias);
  }
  Motion motion;
  motion.omega.resize(n);
  std::vector<double> bias(n), integrated(n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    bias[i] = interpolate_held(bias_t, bias_v, t[i]);
    motion.omega[i] = in.rate[i] - bias[i];
    if (i > 0) {
      integrated[i] =
          integrated[i - 1] + 0.5 * (motion.omega[i - 1] + motion.omega[i]) * (t[i] - t[i - 1]);
    }
  }

  if (in.mode == Mode::kRateOnly) {
    anchors.resize(1);
    anchors[0].offset = -mean_over(integrated, anchors[0].region);
  } else {
    const std::vector<double>& absolute = in.mode == Mode::kFused ? in.incl : in.angle;
    for (Anchor& anchor : anchors) {
      anchor.offset = mean_over(absolute, anchor.region) - mean_over(integrated, anchor.region);
    }
  }

  // The correction: the nearest anchor's offset beyond the first and the last; between two
  // anchors linear in time, or, where the rate is unknown in between, carried by the unknown
  // intervals alone (the angle a saturated gyroscope lost stays where it was lost). Its
  // slope is a bias correction and goes into ω too.
  std::vector<double> correction(n), slope(n, 0.0);
  for (std::size_t i = 0; i <= anchors.front().index; ++i) correction[i] = anchors.front().offset;
  for (std::size_t i = anchors.back().index; i < n; ++i) correction[i] = anchors.back().offset;
  for (std::size_t k = 0; k + 1 < anchors.size(); ++k) {
    const Anchor& a = anchors[k];
    const Anchor& b = anchors[k + 1];
    const std::size_t lost = in.unknown[b.index] - in.unknown[a.index];
    const double step = b.offset - a.offset;
    for (std::size_t i = a.index + 1; i <= b.index; ++i) {
      if (lost > 0) {
        correction[i] = a.offset + step * static_cast<double>(in.unknown[i] - in.unknown[a.index]) /
                                       static_cast<double>(lost);
      } else {
        slope[i] = step / (b.time_s - a.time_s);
        correction[i] = a.offset + slope[i] * (t[i] - a.time_s);
      }
    }
  }
  motion.theta.resize(n);
  double bias_sum = 0;
  std::size_t bias_count = 0;
  for (std::size_t i = 0; i < n; ++i) {
    motion.omega[i] += slope[i];
    motion.theta[i] = in.mode == Mode::kAngleAndRate ? in.angle[i] : integrated[i] + correction[i];
    if (in.fault[i] & (kSaturated | kRateNonFinite)) continue;
    bias_sum += bias[i] - slope[i];
    ++bias_count;
  }
  motion.mean_bias = bias_count > 0 ? bias_sum / static_cast<double>(bias_count) : 0.0;
  return motion;
}

// Cuts the strokes out of the motion: one candidate at a time (cut()), leaving out (and
// listing) those with faults, with an unknown angle, or too short; then lists the faulty
// samples outside every stroke (list_faults_outside()).
class StrokeCutter {
 public:
  StrokeCutter(const Input& in, const Motion& motion, const std::vector<Anchor>& anchors,
               const PreprocessingOptions& options, PreparedData& data,
               std::vector<ExcludedSegment>& excluded)
      : in_(in),
        t_(in.t),
        motion_(motion),
        anchors_(anchors),
        options_(options),
        data_(data),
        excluded_(excluded),
        covered_(in.size(), false) {}

  void cut(const Candidate& candidate);
  void list_faults_outside();

 private:
  // The candidate's name, direction and faults (a gap before its first sample is outside).
  struct Faults {
    std::uint8_t kinds = 0;
    std::size_t count = 0;
    std::size_t first = 0;
  };
  std::uint8_t fault_at(const Range& r, std::size_t i) const {
    return i == r.first ? static_cast<std::uint8_t>(in_.fault[i] & ~kGapBefore) : in_.fault[i];
  }
  Faults faults_in(const Range& r) const;
  bool angle_known(std::size_t first, std::size_t last) const;
  bool long_enough(const Range& piece) const {
    return t_[piece.last] - t_[piece.first] >= options_.min_stroke_duration_s &&
           std::abs(motion_.theta[piece.last] - motion_.theta[piece.first]) >=
               options_.min_stroke_angle_rad;
  }
  void exclude_lost(const Range& r, const std::string& name);
  std::optional<Range> keep_good_part(const Range& r, const std::string& name,
                                      const Faults& faults);
  std::string reason_to_leave_out(const Range& r, const std::string& name, double net) const;
  void keep(const Candidate& candidate, const Range& r, StrokeDirection direction);

  const Input& in_;
  const std::vector<double>& t_;
  const Motion& motion_;
  const std::vector<Anchor>& anchors_;
  const PreprocessingOptions& options_;
  PreparedData& data_;
  std::vector<ExcludedSegment>& excluded_;
  std::vector<bool> covered_;
};

StrokeCutter::Faults StrokeCutter::faults_in(const Range& r) const {
  Faults faults;
  faults.first = in_.size();
  for (std::size_t i = r.first; i <= r.last; ++i) {
    const std::uint8_t f = fault_at(r, i);
    if (f == 0) continue;
    faults.kinds |= f;
    ++faults.count;
    faults.first = std::min(faults.first, i);
  }
  return faults;
}

// Whether the angle on [first, last] is known: joined to an anchor by a known rate. Before
// the first anchor and after the last the angle is only as good as the rate between the
// stroke and that anchor (with the rate only, that is everywhere).
bool StrokeCutter::angle_known(std::size_t first, std::size_t last) const {
  const bool anchored = in_.mode == Mode::kFused || in_.mode == Mode::kRateOnly;
  if (!anchored) return true;
  const Anchor* left = nullptr;
  const Anchor* right = nullptr;
  for (const Anchor& anchor : anchors_) {
    if (anchor.index <= first) left = &anchor;
    if (anchor.index >= last && right == nullptr) right = &anchor;
  }
  return (left != nullptr && in_.unknown[last] == in_.unknown[left->index]) ||
         (right != nullptr && in_.unknown[right->index] == in_.unknown[first]);
}

// Scans lost in recording: the stroke is cut there, and neither part is fitted, so that a
// fit sees the recording as if the stroke had not been made.
void StrokeCutter::exclude_lost(const Range& r, const std::string& name) {
  std::size_t first_lost = r.first, lost_count = 0;
  while (!(fault_at(r, first_lost) & kLost)) ++first_lost;
  std::size_t last_lost = first_lost;
  for (std::size_t i = r.first; i <= r.last; ++i) {
    if (!(fault_at(r, i) & kLost)) continue;
    ++lost_count;
    last_lost = i;
  }
  excluded_.push_back({t_[r.first], t_[r.last],
                       name + ": recording gap: " + std::to_string(lost_count) +
                           " samples lost from " + seconds(t_[first_lost]) + " to " +
                           seconds(t_[last_lost]) +
                           "; the stroke is cut there and neither part is fitted",
                       true});
}

// A brisk stroke saturates the gyroscope for part of its course: its longest fault-free
// part whose angle is known (before the faults, from the anchor before it; after them,
// from the anchor after it) is kept, the rest listed. nullopt: no part is.
std::optional<Range> StrokeCutter::keep_good_part(const Range& r, const std::string& name,
                                                  const Faults& faults) {
  const std::string described = describe_faults(faults.kinds, in_.saturation_limit) + " in " +
                                std::to_string(faults.count) + " samples from " +
                                seconds(t_[faults.first]);
  std::optional<Range> best;
  std::size_t i = r.first;
  while (i <= r.last) {
    if (fault_at(r, i) != 0 && !(i > r.first && in_.fault[i] == kGapBefore)) {
      ++i;
      continue;
    }
    // A gap before i ends the previous piece but i itself is a good sample.
    Range piece{i, i};
    while (piece.last + 1 <= r.last && in_.fault[piece.last + 1] == 0) ++piece.last;
    if (angle_known(piece.first, piece.last) && long_enough(piece) &&
        (!best || piece.last - piece.first > best->last - best->first)) {
      best = piece;
    }
    i = piece.last + 1;
  }
  if (!best) {
    excluded_.push_back({t_[r.first], t_[r.last], name + ": " + described});
    return std::nullopt;
  }
  if (best->first > r.first) {
    excluded_.push_back(
        {t_[r.first], t_[best->first - 1], name + ", before the part kept: " + described});
  }
  if (best->last < r.last) {
    excluded_.push_back(
        {t_[best->last + 1], t_[r.last], name + ", after the part kept: " + described});
  }
  return best;
}

// Why a fault-free stroke is left out: its angle is unknown, or it is too short ("" when
// it is kept).
std::string StrokeCutter::reason_to_leave_out(const Range& r, const std::string& name,
                                              double net) const {
  if (!angle_known(r.first, r.last)) {
    return name +
           ": angle unknown: the gyroscope's rate is unknown (saturated, non-finite "
           "or a gap) between this stroke and the " +
           std::string(in_.mode == Mode::kFused ? "nearest inclinometer anchor"
                                                : "still period where theta = 0");
  }
  if (!long_enough(r)) {
    return name + ": too short (" + text(t_[r.last] - t_[r.first]) + " s, " + text(net / kRadPerDeg) +
           " deg; a stroke needs >= " + text(options_.min_stroke_duration_s) +
           " s and >= " + text(options_.min_stroke_angle_rad / kRadPerDeg) + " deg)";
  }
  return "";
}

void StrokeCutter::keep(const Candidate& candidate, const Range& r, StrokeDirection direction) {
  Stroke stroke;
  stroke.id = candidate.id;
  stroke.direction = direction;
  const auto begin = static_cast<std::ptrdiff_t>(r.first);
  const auto end = static_cast<std::ptrdiff_t>(r.last + 1);
  stroke.time_s.assign(t_.begin() + begin, t_.begin() + end);
  stroke.force_N.assign(in_.force.begin() + begin, in_.force.begin() + end);
  stroke.theta_rad.assign(motion_.theta.begin() + begin, motion_.theta.begin() + end);
  stroke.omega_rad_s.assign(motion_.omega.begin() + begin, motion_.omega.begin() + end);
  data_.strokes.push_back(std::move(stroke));
}

void StrokeCutter::cut(const Candidate& candidate) {
  Range r = candidate.range;
  for (std::size_t i = r.first; i <= r.last; ++i) covered_[i] = true;
  const double net = motion_.theta[r.last] - motion_.theta[r.first];
  const StrokeDirection direction = net > 0 ? StrokeDirection::kOpening : StrokeDirection::kClosing;
  const std::string name = "stroke " + std::to_string(candidate.id) + " (" +
                           (direction == StrokeDirection::kOpening ? "opening" : "closing") + ")";
  const Faults faults = faults_in(r);
  if (faults.kinds & kLost) {
    exclude_lost(r, name);
    return;
  }
  if (faults.kinds != 0) {
    const std::optional<Range> part = keep_good_part(r, name, faults);
    if (!part) return;
    r = *part;
  } else if (const std::string reason = reason_to_leave_out(r, name, net); !reason.empty()) {
    excluded_.push_back({t_[r.first], t_[r.last], reason});
    return;
  }
  keep(candidate, r, direction);
}

void StrokeCutter::list_faults_outside() {
  const std::size_t n = in_.size();
  std::size_t i = 0;
  while (i < n) {
    const std::uint8_t f = covered_[i] ? 0 : in_.fault[i];
    if (f == 0) {
      ++i;
      continue;
    }
    std::size_t last = i;
    std::uint8_t kinds = f;
    while (last + 1 < n && !covered_[last + 1] && in_.fault[last + 1] != 0) {
      kinds |= in_.fault[++last];
    }
    const std::size_t first = (f & kGapBefore) && i > 0 ? i - 1 : i;  // a gap starts before
    excluded_.push_back({t_[first], t_[last],
                         "outside the strokes: " + describe_faults(kinds, in_.saturation_limit),
                         (kinds & kLost) != 0});
    i = last + 1;
  }
}

void cut_strokes(const Input& in, const Motion& motion, const std::vector<Anchor>& anchors,
                 const std::vector<Candidate>& candidates, const PreprocessingOptions& options,
                 PreparedData& data, std::vector<ExcludedSegment>& excluded) {
  StrokeCutter cutter(in, motion, anchors, options, data, excluded);
  for (const Candidate& candidate : candidates) cutter.cut(candidate);
  cutter.list_faults_outside();
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

std::string milliseconds(double value_s) {
  return text(1000.0 * value_s) + " ms";
}

// PreparedData::rate_summary: the rate, its jitter, the derivative's cut-off, and what the
// rate does not resolve (docs/preprocessing.md, "Any sample rate").
std::string describe_rate(const Input& in, double derivative_cutoff_hz, bool cutoff_auto) {
  std::string line = "sample rate " + text(in.rate_hz) + " Hz (median interval " +
                     milliseconds(in.median_interval_s);
  if (in.jittered) {
    line += ", intervals " + milliseconds(in.min_interval_s) + " to " +
            milliseconds(in.max_interval_s) + ": jittered, filtered on a uniform " +
            milliseconds(in.median_interval_s) + " grid";
  }
  line += ")";
  double resolved_hz = 0.5 * in.rate_hz;
  if (derivative_cutoff_hz > 0) {
    line += "; the rate is angle_rad's derivative, low-passed at " + text(derivative_cutoff_hz) +
            " Hz" + (cutoff_auto ? " (min(30 Hz, rate / 4))" : " (as asked)");
    resolved_hz = derivative_cutoff_hz;
  }
  line += "; motion faster than " + text(resolved_hz) + " Hz is not resolved";
  if (in.rate_hz < kLatchDetailRate_hz) {
    line += "; below " + text(kLatchDetailRate_hz) +
            " Hz the latch's details (release, snap and force edges lasting a few ms) are not "
            "resolved: they are averaged over two samples (" +
            milliseconds(2.0 * in.median_interval_s) +
            ") of travel, so latch angles and stiffnesses are approximate";
  }
  return line;
}

// Where the data come from: the source, the handle's radius and its origin, the sample
// rate, how the angle is obtained.
void describe_source(const Recording& recording, const Input& in, PreparedData& data) {
  data.source = recording.source;
  data.warnings = in.warnings;
  data.handle_radius_m = recording.handle_radius_m.value_or(0.0);
  for (const auto& [key, value] : recording.metadata) {
    if (key == kGeometryCalibrationKey) data.geometry_calibration_id = value;
  }
  if (data.handle_radius_m > 0) {
    data.handle_radius_origin =
        data.geometry_calibration_id.empty()
            ? "the recording's handle_radius_m"
            : "geometry record " + data.geometry_calibration_id +
                  " (the force corrected for the load cell's mounting angle)";
  }
  data.sample_rate_hz = recording.sample_rate_hz.value_or(in.rate_hz);
  switch (in.mode) {
    case Mode::kFused:
      data.angle_source = "rate_rad_s integrated, anchored to " + in.inclinometer_name;
      break;
    case Mode::kRateOnly:
      data.angle_source = "rate_rad_s integrated from theta = 0 at the first still period";
      break;
    case Mode::kAngleAndRate:
      data.angle_source = "angle_rad (full range); rate_rad_s with its bias taken from angle_rad";
      if (!in.inclinometer_name.empty()) {
        data.notes.push_back(in.inclinometer_name + " not used: angle_rad is the full-range angle");
      }
      break;
    case Mode::kAngleOnly:
      data.angle_source = "angle_rad (full range); rate: its zero-phase smoothed derivative";
      break;
  }
}

// The still periods trusted for the bias and the noise: the anchors' (in the
// inclinometer's range, or with a consistent bias), not a door creeping to rest at the
// open position; all still periods when no anchor has a bias.
std::vector<Range> trusted_periods(const std::vector<Anchor>& anchors, const Stillness& still) {
  std::vector<Range> trusted;
  for (const Anchor& anchor : anchors) {
    if (anchor.has_bias) trusted.push_back(anchor.period);
  }
  if (trusted.empty()) trusted = still.periods;
  return trusted;
}

// θ and ω: the rate integrated and anchored (which sets the anchors' offsets), or
// angle_rad and its derivative; and the note saying how.
Motion motion_of(const Input& in, std::vector<Anchor>& anchors,
                 const std::vector<double>& derived_rate, double derivative_cutoff_hz,
                 bool cutoff_auto, PreparedData& data) {
  Motion motion;
  if (in.has_rate) {
    motion = integrate_and_anchor(in, anchors);
  } else {
    motion.theta = in.angle;
    motion.omega = derived_rate;
  }
  data.gyro_bias_rad_s = motion.mean_bias;
  if (in.mode == Mode::kFused) {
    data.notes.push_back("theta anchored to " + in.inclinometer_name + " at " +
                         std::to_string(anchors.size()) + " still periods");
  } else if (in.mode == Mode::kRateOnly) {
    data.notes.push_back("no absolute angle: theta = 0 at the still period from " +
                         seconds(in.t[anchors.front().period.first]) +
                         ", taken for the closed door; the angle drifts with the bias error "
                         "from there");
  } else if (in.mode == Mode::kAngleOnly) {
    data.notes.push_back("rate: derivative of angle_rad after a zero-phase low-pass at " +
                         text(derivative_cutoff_hz) + " Hz" +
                         (cutoff_auto ? " (the rate's rule: min(30 Hz, sample rate / 4))" : ""));
  }
  return motion;
}

// Noise levels from the trusted still periods, else the bench's figures.
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

// A quantised angle (an encoder's steps) that stands still reads no noise at all: its
// noise is at least the quantisation's, q / sqrt(12), and so is the derivative's.
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

// The strokes to cut: the recording's stroke column (when used), else the motion's
// segments (those too short to be strokes go to `excluded`).
std::vector<Candidate> stroke_candidates(const Recording& recording, const Input& in,
                                         const Motion& motion, const Stillness& still,
                                         const PreprocessingOptions& options,
                                         std::vector<ExcludedSegment>& excluded) {
  if (recording.stroke && options.use_stroke_column) {
    return strokes_from_column(*recording.stroke);
  }
  const double noise = std::isfinite(still.noise_estimate) ? still.noise_estimate : 0.0;
  const double edge =
      std::min(options.motion_rate_rad_s, std::max(options.edge_rate_rad_s, 4.0 * noise));
  return segment_strokes(in.t, motion.theta, motion.omega, edge, options, excluded);
}

}  // namespace

PreparedData prepare(const Recording& recording, const PreprocessingOptions& options) {
  if (std::string problem = options.validate(); !problem.empty()) {
    throw std::invalid_argument(problem);
  }
  Input in = read_input(recording, options);
  PreparedData data;
  describe_source(recording, in, data);

  // The rate the stillness test looks at: the gyroscope's (bias included), or the
  // derivative of angle_rad.
  std::vector<double> derived_rate;
  const bool cutoff_auto = !(options.derivative_cutoff_hz > 0);
  const double derivative_cutoff_hz =
      cutoff_auto ? auto_derivative_cutoff_hz(in.rate_hz) : options.derivative_cutoff_hz;
  if (in.mode == Mode::kAngleOnly) {
    in.check_cutoff(derivative_cutoff_hz, "derivative_cutoff_hz");
    derived_rate = smoothing_derivative(in.t, in.angle, derivative_cutoff_hz, in.rate_hz);
    data.derivative_cutoff_hz = derivative_cutoff_hz;
  }
  data.interval_median_s = in.median_interval_s;
  data.interval_min_s = in.min_interval_s;
  data.interval_max_s = in.max_interval_s;
  data.jittered = in.jittered;
  data.rate_summary = describe_rate(in, data.derivative_cutoff_hz, cutoff_auto);
  const std::vector<double>& tested_rate = in.has_rate ? in.rate : derived_rate;
  const Stillness still = find_stillness(in, tested_rate, options);
  std::vector<Anchor> anchors = find_anchors(in, still, options);
  const std::vector<Range> trusted = trusted_periods(anchors, still);
  const Motion motion =
      motion_of(in, anchors, derived_rate, derivative_cutoff_hz, cutoff_auto, data);
  estimate_noise(in, still, trusted, anchors, tested_rate, options, data);
  apply_quantisation_floor(in, derivative_cutoff_hz, data);

  if (options.force_cutoff_hz > 0) {
    in.check_cutoff(options.force_cutoff_hz, "force_cutoff_hz");
    in.force = zero_phase_lowpass_at(in.t, in.force, options.force_cutoff_hz, in.rate_hz);
  }
  std::vector<ExcludedSegment> excluded;
  const std::vector<Candidate> candidates =
      stroke_candidates(recording, in, motion, still, options, excluded);
  cut_strokes(in, motion, anchors, candidates, options, data, excluded);
  std::stable_sort(
      excluded.begin(), excluded.end(),
      [](const ExcludedSegment& a, const ExcludedSegment& b) { return a.start_s < b.start_s; });
  data.excluded = std::move(excluded);
  return data;
}

PreparedData prepare_session(const std::filesystem::path& session_path,
                             const PreprocessingOptions& options) {
  const SessionReader session(session_path);
  return prepare(session_to_recording(session), options);
}

}  // namespace doorbench
