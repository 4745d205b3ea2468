#include "calibration/gyro_calibration.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "acquisition/session/interpolation.h"
#include "calibration/least_squares.h"
#include "calibration/session_signals.h"
#include "calibration/static_source.h"
#include "calibration/timing_calibration.h"
#include "core/units.h"

namespace doorbench::calibration {

namespace {}

std::string StillnessOptions::validate() const {
  auto positive = [](double v) { return v > 0 && std::isfinite(v); };
  if (!positive(window_s)) return "stillness window_s = " + shortest(window_s) + " must be > 0";
  if (!positive(noise_factor))
    return "stillness noise_factor = " + shortest(noise_factor) + " must be > 0";
  if (!(rate_std_floor_dps >= 0)) {
    return "stillness rate_std_floor_dps = " + shortest(rate_std_floor_dps) + " must be >= 0";
  }
  if (!positive(max_inclinometer_rate_dps)) {
    return "stillness max_inclinometer_rate_dps = " + shortest(max_inclinometer_rate_dps) +
           " must be > 0";
  }
  if (!(guard_s >= 0)) return "stillness guard_s = " + shortest(guard_s) + " must be >= 0";
  if (!positive(min_duration_s)) {
    return "stillness min_duration_s = " + shortest(min_duration_s) + " must be > 0";
  }
  if (!positive(consistency_dps)) {
    return "stillness consistency_dps = " + shortest(consistency_dps) + " must be > 0";
  }
  return "";
}

std::string GyroCalibrationOptions::validate() const {
  if (std::string problem = stillness.validate(); !problem.empty()) return problem;
  if (!(range_dps >= 0))
    return "gyroscope calibration range_dps = " + shortest(range_dps) + " must be >= 0";
  if (!(saturation_margin_dps >= 0)) {
    return "gyroscope calibration saturation_margin_dps = " + shortest(saturation_margin_dps) +
           " must be >= 0";
  }
  if (!(inclinometer_range_deg >= 0)) {
    return "gyroscope calibration inclinometer_range_deg = " + shortest(inclinometer_range_deg) +
           " must be >= 0";
  }
  if (!(inclinometer_margin_deg >= 0)) {
    return "gyroscope calibration inclinometer_margin_deg = " + shortest(inclinometer_margin_deg) +
           " must be >= 0";
  }
  return "";
}

std::vector<StillPeriod> find_still_periods(const std::vector<double>& time_s,
                                            const std::vector<double>& rate_dps,
                                            const std::vector<double>& inclinometer_deg,
                                            const StillnessOptions& options, double* noise_dps) {
  if (std::string problem = options.validate(); !problem.empty()) throw CalibrationError(problem);
  const std::size_t n = rate_dps.size();
  std::vector<StillPeriod> periods;
  if (n < 16) return periods;
  const double rate_hz = (n - 1) / (time_s.back() - time_s.front());

  // σ̂ from second differences: white noise gives them a standard deviation of σ√6, while
  // the door's motion, nearly straight over 2 ms, hardly shows (first differences would
  // carry its acceleration); the median ignores the strokes' sharp parts.
  std::vector<double> diff(n - 2);
  for (std::size_t i = 1; i + 1 < n; ++i) {
    diff[i - 1] = rate_dps[i + 1] - 2 * rate_dps[i] + rate_dps[i - 1];
  }
  auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  const double diff_median = median(diff);
  for (double& d : diff) d = std::abs(d - diff_median);
  const double sigma = 1.4826 * median(diff) / std::sqrt(6.0);
  if (noise_dps) *noise_dps = sigma;
  const double std_limit = std::max(options.noise_factor * sigma, options.rate_std_floor_dps);

  // Rolling sums over the centred window (values taken about the first sample, for
  // precision).
  const auto half =
      static_cast<std::size_t>(std::max(1.0, std::round(options.window_s * rate_hz / 2)));
  const bool has_inclinometer = inclinometer_deg.size() == n;
  std::vector<double> s1(n + 1, 0.0), s2(n + 1, 0.0), st(n + 1, 0.0), stt(n + 1, 0.0),
      sy(n + 1, 0.0), sty(n + 1, 0.0), unknown(n + 1, 0.0);
  const double r0 = rate_dps[0], t0 = time_s[0];
  for (std::size_t i = 0; i < n; ++i) {
    const double r = rate_dps[i] - r0;
    s1[i + 1] = s1[i] + r;
    s2[i + 1] = s2[i] + r * r;
    const double t = time_s[i] - t0;
    const double y = has_inclinometer ? inclinometer_deg[i] : NAN;
    const bool known = std::isfinite(y);
    st[i + 1] = st[i] + t;
    stt[i + 1] = stt[i] + t * t;
    sy[i + 1] = sy[i] + (known ? y : 0.0);
    sty[i + 1] = sty[i] + (known ? t * y : 0.0);
    unknown[i + 1] = unknown[i] + (known ? 0.0 : 1.0);
  }
  std::vector<char> quiet(n, 0), confirmed(n, 0);
  for (std::size_t i = half; i + half < n; ++i) {
    const std::size_t a = i - half, b = i + half + 1;
    const double m = static_cast<double>(b - a);
    const double mean = (s1[b] - s1[a]) / m;
    const double var = std::max(0.0, (s2[b] - s2[a]) / m - mean * mean) * m / (m - 1);
    bool ok = std::sqrt(var) <= std_limit;
    bool inclinometer_still = false;
    if (has_inclinometer && unknown[b] - unknown[a] == 0.0) {
      const double mt = (st[b] - st[a]) / m, my = (sy[b] - sy[a]) / m;
      const double ctt = (stt[b] - stt[a]) / m - mt * mt;
      const double cty = (sty[b] - sty[a]) / m - mt * my;
      const double slope = ctt > 0 ? cty / ctt : 0.0;
      inclinometer_still = std::abs(slope) <= options.max_inclinometer_rate_dps;
      ok = ok && inclinometer_still;
    }
    quiet[i] = ok;
    confirmed[i] = ok && inclinometer_still;
  }
  const auto guard = static_cast<std::size_t>(std::round(options.guard_s * rate_hz));
  const auto min_samples = static_cast<std::size_t>(std::round(options.min_duration_s * rate_hz));
  for (std::size_t i = 0; i < n;) {
    if (!quiet[i]) {
      ++i;
      continue;
    }
    std::size_t j = i;
    while (j < n && quiet[j]) ++j;
    if (j - i > 2 * guard + min_samples - 1) {
      const std::size_t a = i + guard, b = j - guard;  // [a, b)
      StillPeriod p;
      p.start_s = time_s[a];
      p.end_s = time_s[b - 1];
      p.samples = b - a;
      double sum = 0.0, sum2 = 0.0;
      std::size_t confirmed_count = 0;
      for (std::size_t k = a; k < b; ++k) {
        sum += rate_dps[k];
        sum2 += rate_dps[k] * rate_dps[k];
        confirmed_count += confirmed[k] ? 1 : 0;
      }
      p.mean_rate_dps = sum / p.samples;
      p.std_rate_dps =
          std::sqrt(std::max(0.0, sum2 / p.samples - p.mean_rate_dps * p.mean_rate_dps));
      p.confirmed = confirmed_count == p.samples;
      periods.push_back(p);
    }
    i = j;
  }
  return periods;
}

namespace {

// The gyroscope's channel read, checked (a uniform clock, 100 samples, a straight-line
// record), with its record's coefficients and its rate in °/s.
struct GyroInput {
  ChannelSignal signal;
  double c0 = 0.0, c1 = 1.0;  // the current record: physical = c0 + c1 · signal
  std::vector<double> rate_dps;
};

GyroInput read_gyroscope(const SessionReader& session, const std::string& gyro_name,
                         const std::string& where) {
  GyroInput in;
  in.signal = read_channel_signal(session, gyro_name);
  const ChannelSignal& gyro = in.signal;
  if (gyro.info.sample_rate_hz <= 0 || gyro.signal.size() < 100) {
    throw CalibrationError(where + "channel " + gyro_name +
                           " needs a uniform clock and at least 100 samples");
  }
  if (gyro.record && gyro.record->coefficients.size() > 2) {
    throw CalibrationError(where + "channel " + gyro_name + "'s record " + gyro.record->id +
                           " is not a straight line; calibrate from the nominal record");
  }
  in.c0 = gyro.record ? gyro.record->coefficients[0] : 0.0;
  in.c1 = gyro.record ? gyro.record->coefficients[1] : 1.0;
  in.rate_dps.resize(gyro.physical.size());
  for (std::size_t i = 0; i < in.rate_dps.size(); ++i) {
    in.rate_dps[i] = gyro.physical[i] * kDegPerRad;
  }
  return in;
}

// The gyroscope's range (°/s): the option, else the rig's channel parameter, else 100.
double gyroscope_range_dps(const SessionReader& session, const std::string& gyro_name,
                           const GyroCalibrationOptions& options) {
  double range_dps = options.range_dps;
  const std::optional<RigDefinition> rig = session_rig(session);
  if (range_dps == 0) {
    range_dps = 100.0;
    if (rig) {
      if (const RigChannel* rc = rig->find_channel(gyro_name)) {
        range_dps = gyroscope_parameters(*rc).range_dps;
      }
    }
  }
  return range_dps;
}

// Saturation: the sensor clamps its reading at ± its range. Which samples are rates
// (false: saturated); counts them and their intervals into `r`, with a warning.
std::vector<bool> mark_saturated(const GyroInput& in, const std::string& gyro_name,
                                 double range_dps, double margin_dps, GyroCalibration& r) {
  const std::vector<double>& rate_dps = in.rate_dps;
  const std::vector<double>& time_s = in.signal.time_s;
  std::vector<bool> valid(rate_dps.size(), true);
  for (std::size_t i = 0; i < rate_dps.size(); ++i) {
    if (std::abs(rate_dps[i]) >= range_dps - margin_dps) {
      valid[i] = false;
      ++r.saturated_samples;
      if (i > 0 && !valid[i - 1]) {
        r.saturated_intervals.back().second = time_s[i];
      } else {
        r.saturated_intervals.emplace_back(time_s[i], time_s[i]);
      }
    }
  }
  if (r.saturated_samples > 0) {
    r.warnings.push_back("gyroscope " + gyro_name + " saturated (±" + shortest(range_dps) +
                         " °/s) on " + std::to_string(r.saturated_samples) + " samples in " +
                         std::to_string(r.saturated_intervals.size()) +
                         " intervals; those samples are not rates and were not used");
  }
  return valid;
}

// The inclinometer's channel, which of its samples are in range, and its angle (°) on the
// gyroscope's samples (NaN where out of range). All empty when there is no inclinometer.
struct InclinometerOnGyro {
  ChannelSignal signal;
  std::vector<bool> in_range;
  std::vector<double> angle_deg;
};

InclinometerOnGyro read_inclinometer_on_gyro(const SessionReader& session,
                                             const std::string& inclinometer_name,
                                             const ChannelSignal& gyro,
                                             const GyroCalibrationOptions& options) {
  InclinometerOnGyro in;
  if (inclinometer_name.empty()) return in;
  in.signal = read_channel_signal(session, inclinometer_name);
  in.in_range =
      inclinometer_in_range(session, inclinometer_name, in.signal.signal,
                            options.inclinometer_range_deg, options.inclinometer_margin_deg);
  std::vector<double> masked(in.signal.physical.size());
  for (std::size_t j = 0; j < masked.size(); ++j) {
    masked[j] = in.in_range[j] ? in.signal.physical[j] * kDegPerRad : NAN;
  }
  in.angle_deg.resize(gyro.physical.size());
  const bool same_clock = in.signal.time_s.size() == gyro.time_s.size();
  for (std::size_t i = 0; i < in.angle_deg.size(); ++i) {
    in.angle_deg[i] =
        same_clock ? masked[i] : interpolate_held(in.signal.time_s, masked, gyro.time_s[i]);
  }
  return in;
}

// Each still period's mean signal, and whether it goes into the bias: not saturated, and
// confirmed by the inclinometer (with one) or consistent with the others (without).
void choose_bias_periods(const ChannelSignal& gyro, const std::vector<bool>& valid,
                         bool has_inclinometer, const StillnessOptions& stillness,
                         std::vector<StillPeriod>& periods) {
  for (StillPeriod& p : periods) {
    const auto a = static_cast<std::size_t>(
        std::lower_bound(gyro.time_s.begin(), gyro.time_s.end(), p.start_s) - gyro.time_s.begin());
    double sum = 0.0;
    bool saturated = false;
    for (std::size_t k = a; k < a + p.samples; ++k) {
      sum += gyro.signal[k];
      saturated = saturated || !valid[k];
    }
    p.mean_signal_V = sum / p.samples;
    p.used = !saturated;
  }
  if (has_inclinometer) {
    for (StillPeriod& p : periods) p.used = p.used && p.confirmed;
  } else if (!periods.empty()) {
    std::vector<double> means;
    for (const StillPeriod& p : periods) means.push_back(p.mean_rate_dps);
    std::nth_element(means.begin(), means.begin() + means.size() / 2, means.end());
    const double median = means[means.size() / 2];
    for (StillPeriod& p : periods) {
      p.used = p.used && std::abs(p.mean_rate_dps - median) <= stillness.consistency_dps;
    }
  }
}

// The bias from the periods used, its uncertainty and (from three periods) its drift.
// Throws CalibrationError when no period is used.
void estimate_bias(const std::string& where, bool has_inclinometer,
                   const StillnessOptions& stillness, GyroCalibration& r) {
  std::vector<double> bias_means, bias_times;
  std::size_t bias_samples = 0;
  for (const StillPeriod& p : r.still_periods) {
    if (!p.used) continue;
    bias_means.push_back(p.mean_rate_dps);
    bias_times.push_back(0.5 * (p.start_s + p.end_s));
    bias_samples += p.samples;
  }
  r.bias_periods = static_cast<int>(bias_means.size());
  if (r.bias_periods == 0) {
    throw CalibrationError(
        where + "no still period for the gyroscope's bias (" +
        std::to_string(r.still_periods.size()) + " quiet periods found, none " +
        (has_inclinometer ? "confirmed by the inclinometer in its range" : "consistent") +
        "); record at least " + shortest(stillness.min_duration_s + 2 * stillness.guard_s) +
        " s with the door at rest near closed");
  }
  // The bias: the mean of the periods' means (each period counts once: the bias wanders
  // between them). Its uncertainty: the larger of the noise's and the periods' scatter,
  // with the small-sample factor.
  r.bias_dps = mean_of(bias_means);
  const double noise_part = r.noise_dps / std::sqrt(static_cast<double>(bias_samples));
  if (r.bias_periods >= 2) {
    const double scatter_part = std_of(bias_means) / std::sqrt(static_cast<double>(r.bias_periods));
    r.bias_std_dps = std::max(noise_part, scatter_part) * small_sample_factor(r.bias_periods - 1);
  } else {
    r.bias_std_dps = noise_part;
    r.warnings.push_back(
        "only one still period: the bias's uncertainty is its noise alone, "
        "without how much the bias wanders");
  }
  if (r.bias_periods >= 3) {
    const PolynomialFit drift = fit_polynomial(bias_times, bias_means, 1);
    r.drift_dps_per_s = drift.coefficients[1];
    r.drift_std_dps_per_s =
        drift.coefficient_std(1) * small_sample_factor(drift.degrees_of_freedom);
  }
}

// The scale's gain against the inclinometer (1 when not estimated, with a warning saying
// why), the rate taken through the current record with the bias removed (rad/s).
double estimate_scale(const ChannelSignal& gyro, const std::vector<bool>& valid,
                      const InclinometerOnGyro& inclinometer, bool has_inclinometer, bool wanted,
                      GyroCalibration& r) {
  const double bias_rad_s = r.bias_dps / kDegPerRad;
  double gain = 1.0;
  if (wanted && has_inclinometer) {
    std::vector<double> rate(gyro.physical.size());
    for (std::size_t i = 0; i < rate.size(); ++i) rate[i] = gyro.physical[i] - bias_rad_s;
    try {
      const Alignment alignment = align_inclinometer_with_gyro(
          inclinometer.signal.time_s, inclinometer.signal.physical, inclinometer.in_range,
          gyro.time_s, rate, valid, AlignmentOptions{});
      gain = alignment.gain;
      r.scale_estimated = true;
      r.scale_segments = static_cast<int>(alignment.segments.size());
      r.scale_factor_error = 1.0 / alignment.gain - 1.0;
      r.scale_factor_error_std = alignment.gain_std / (alignment.gain * alignment.gain);
    } catch (const CalibrationError& error) {
      r.warnings.push_back(std::string("scale factor not estimated: ") + error.what());
    }
  } else if (wanted) {
    r.warnings.push_back("scale factor not estimated: the session has no inclinometer");
  }
  return gain;
}

// The new record: gain · (previous − bias), with its uncertainty, method, references,
// validity, quantities, notes and header.
void write_gyro_record(const SessionReader& session, const GyroInput& in,
                       const std::string& inclinometer_name, const InclinometerOnGyro& inclinometer,
                       double range_dps, double gain, const RecordHeader& header,
                       GyroCalibration& r) {
  const ChannelSignal& gyro = in.signal;
  const double bias_rad_s = r.bias_dps / kDegPerRad;
  CalibrationRecord& record = r.record;
  record.sensor_kind = "gyroscope";
  record.unit = "rad/s";
  record.input_unit = gyro.info.raw_type == RawType::kCounts ? "V" : gyro.info.raw_unit;
  // New = gain · (previous − bias), previous = c0 + c1 · signal.
  record.coefficients = {gain * (in.c0 - bias_rad_s), gain * in.c1};
  const double bias_u = r.bias_std_dps / kDegPerRad;
  record.standard_uncertainty = std::hypot(bias_u, r.noise_dps / kDegPerRad);
  record.method = std::string("bias from ") + std::to_string(r.bias_periods) +
                  " still periods (stillness test of docs/calibration.md)" +
                  (r.scale_estimated ? "; scale factor against the inclinometer on " +
                                           std::to_string(r.scale_segments) + " stroke segments"
                                     : "; scale factor not estimated");
  record.references =
      "recording " + session.path().filename().string() +
      (inclinometer_name.empty() ? ""
                                 : "; inclinometer " + inclinometer_name + " (its record " +
                                       inclinometer.signal.info.calibration_id + ")");
  record.valid_min = -range_dps / kDegPerRad;
  record.valid_max = range_dps / kDegPerRad;
  record.quantities = {
      {.name = "bias_dps",
       .value = r.bias_dps,
       .standard_uncertainty = r.bias_std_dps,
       .unit = "deg/s"},
      {.name = "bias_drift_dps_per_s",
       .value = r.drift_dps_per_s,
       .standard_uncertainty = r.drift_std_dps_per_s,
       .unit = "deg/s/s"},
      {.name = "noise_dps", .value = r.noise_dps, .standard_uncertainty = 0.0, .unit = "deg/s"},
      {.name = "still_periods",
       .value = static_cast<double>(r.bias_periods),
       .standard_uncertainty = 0.0,
       .unit = "1"},
      {.name = "saturated_samples",
       .value = static_cast<double>(r.saturated_samples),
       .standard_uncertainty = 0.0,
       .unit = "1"},
  };
  if (r.scale_estimated) {
    record.quantities.push_back({.name = "scale_factor_error",
                                 .value = r.scale_factor_error,
                                 .standard_uncertainty = r.scale_factor_error_std,
                                 .unit = "1"});
  }
  if (gyro.record) record.supersedes = gyro.record->id;
  for (const std::string& w : r.warnings)
    record.notes += (record.notes.empty() ? "" : " ") + w + ".";
  RecordHeader h = header;
  if (h.sensor_serial.empty()) h.sensor_serial = gyro.info.sensor_serial;
  if (h.supersedes.empty() && gyro.record) h.supersedes = gyro.record->id;
  apply_header(record, h);
}

}  // namespace

// The stages: read and check the gyroscope, mark its saturated samples, read the
// inclinometer on its clock, find the still periods, choose those for the bias, estimate
// the bias and the scale, and write the record.
GyroCalibration calibrate_gyroscope(const SessionReader& session, const std::string& gyro_channel,
                                    const std::string& inclinometer_channel,
                                    const GyroCalibrationOptions& options,
                                    const RecordHeader& header) {
  if (std::string problem = options.validate(); !problem.empty()) throw CalibrationError(problem);
  const std::string where = session.path().string() + ": ";
  const std::string gyro_name = find_session_channel(session, "gyroscope", gyro_channel);
  const std::string inclinometer_name =
      find_session_channel(session, "inclinometer", inclinometer_channel, true);
  const bool has_inclinometer = !inclinometer_name.empty();
  const GyroInput in = read_gyroscope(session, gyro_name, where);

  GyroCalibration r;
  const double range_dps = gyroscope_range_dps(session, gyro_name, options);
  const std::vector<bool> valid =
      mark_saturated(in, gyro_name, range_dps, options.saturation_margin_dps, r);
  const InclinometerOnGyro inclinometer =
      read_inclinometer_on_gyro(session, inclinometer_name, in.signal, options);

  r.still_periods = find_still_periods(in.signal.time_s, in.rate_dps, inclinometer.angle_deg,
                                       options.stillness, &r.noise_dps);
  choose_bias_periods(in.signal, valid, has_inclinometer, options.stillness, r.still_periods);
  estimate_bias(where, has_inclinometer, options.stillness, r);
  const double gain =
      estimate_scale(in.signal, valid, inclinometer, has_inclinometer, options.estimate_scale, r);
  write_gyro_record(session, in, inclinometer_name, inclinometer, range_dps, gain, header, r);
  return r;
}

std::string GyroCalibration::brief_report() const {
  std::string text = "gyroscope: " + std::to_string(still_periods.size()) + " still periods, " +
                     std::to_string(bias_periods) + " used for the bias; noise " +
                     fixed(noise_dps, 4) + " °/s per sample\n";
  text += "  bias " + fixed(bias_dps, 4) + " °/s ± " + fixed(bias_std_dps, 4) + " °/s";
  if (bias_periods >= 3) {
    text += "; drift " + shortest(drift_dps_per_s) + " ± " + shortest(drift_std_dps_per_s) +
            " °/s per s";
  }
  text += "\n";
  if (scale_estimated) {
    text += "  scale factor error " + fixed(100 * scale_factor_error, 3) + " % ± " +
            fixed(100 * scale_factor_error_std, 3) + " % (on " + std::to_string(scale_segments) +
            " segments against the inclinometer)\n";
  }
  text += "  saturated samples " + std::to_string(saturated_samples) + "\n";
  for (const std::string& w : warnings) text += "  warning: " + w + "\n";
  return text;
}

}  // namespace doorbench::calibration
