// Fault marking and anchoring, the first stages of prepare() (docs/preprocessing.md): the
// recording read and checked, the method chosen, impossible values excluded, faults marked
// and non-finite values bridged; the stillness test; the anchors; the rate integrated and
// anchored.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>

#include "acquisition/session/interpolation.h"
#include "analysis/preprocessing/internal/prepare_stages.h"
#include "core/units.h"

namespace doorbench {

using namespace preprocessing_detail;

namespace {

constexpr std::size_t kMinimumSamples = 10;

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

double mean_over(const std::vector<double>& values, const Range& r) {
  double sum = 0;
  for (std::size_t i = r.first; i <= r.last; ++i) sum += values[i];
  return sum / static_cast<double>(r.last - r.first + 1);
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
    // Enough digits that the two rates differ (never "at 20 Hz, below the 20 Hz").
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
// is still removed and the strokes beside it keep their accuracy (and the stroke holding it
// keeps its angle across it). A longer loss, like any other fault, makes the rate unknown.
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
// bridged at either end, or a gap longer than a bridged loss).
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
  // A jump of the clock no longer than a bridged loss is bridged the same way: the rate
  // integrated across it is the line between the samples around it.
  auto unbridged_gap = [&](std::size_t i) {
    return (in.fault[i] & kGapBefore) &&
           in.t[i] - in.t[i - 1] > options.max_bridged_loss_s + 0.5 * in.median_interval_s;
  };
  for (std::size_t i = 1; i < n; ++i) {
    const bool u = rate_fault(i) || unbridged_gap(i) || rate_fault(i - 1);
    unknown[i] = unknown[i - 1] + (u ? 1 : 0);
  }
  return unknown;
}

}  // namespace

namespace preprocessing_detail {

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
      throw PreprocessingError(in.source + ": no still period with the inclinometer (" +
                               in.inclinometer_name + ") inside +-" + text(limit / kRadPerDeg) +
                               " deg to anchor the integrated gyroscope to (" +
                               std::to_string(still.periods.size()) + " still periods found; " +
                               still.rule + ")");
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

}  // namespace preprocessing_detail

}  // namespace doorbench
