#include "calibration/timing_calibration.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "acquisition/session/interpolation.h"
#include "calibration/least_squares.h"
#include "calibration/session_signals.h"
#include "calibration/static_source.h"
#include "core/units.h"

namespace doorbench::calibration {

namespace {}

std::string AlignmentOptions::validate() const {
  if (!(max_delay_s > 0))
    return "alignment max_delay_s = " + shortest(max_delay_s) + " must be > 0";
  if (!(min_travel_deg > 0))
    return "alignment min_travel_deg = " + shortest(min_travel_deg) + " must be > 0";
  if (!(motion_rate_dps > 0))
    return "alignment motion_rate_dps = " + shortest(motion_rate_dps) + " must be > 0";
  if (!(motion_pad_s >= 0))
    return "alignment motion_pad_s = " + shortest(motion_pad_s) + " must be >= 0";
  if (min_segments < 2) {
    return "alignment min_segments = " + std::to_string(min_segments) +
           " must be >= 2 (the delay's uncertainty comes from leaving each out)";
  }
  return "";
}

std::string TimingCalibrationOptions::validate() const {
  if (std::string problem = alignment.validate(); !problem.empty()) return problem;
  return gyro.validate();
}

namespace {

// The integrated rate on the gyroscope's uniform clock, read at any time.
struct Integral {
  double t0 = 0.0, rate_hz = 1.0;
  std::vector<double> theta;
  double at(double t) const {
    const double x = (t - t0) * rate_hz;
    if (x <= 0) return theta.front();
    const auto i = static_cast<std::size_t>(x);
    if (i + 1 >= theta.size()) return theta.back();
    const double w = x - static_cast<double>(i);
    return theta[i] + w * (theta[i + 1] - theta[i]);
  }
};

struct Segment {
  std::size_t begin = 0, end = 0;  // inclinometer samples [begin, end)
};

struct Regression {
  double sse = 0.0, gain = 0.0, sxx = 0.0, syy = 0.0;
  std::size_t count = 0;
};

// y_j = a_k + g · Θ(t_j − d) over the segments except `skip`, the offsets profiled out.
Regression regress(const Integral& integral, const std::vector<double>& t,
                   const std::vector<double>& y, const std::vector<Segment>& segments, double delay,
                   std::size_t skip) {
  double sxy = 0.0, sxx = 0.0, syy = 0.0;
  std::size_t count = 0;
  std::vector<double> x;
  for (std::size_t k = 0; k < segments.size(); ++k) {
    if (k == skip) continue;
    const Segment& s = segments[k];
    x.resize(s.end - s.begin);
    double mx = 0.0, my = 0.0;
    for (std::size_t j = s.begin; j < s.end; ++j) {
      x[j - s.begin] = integral.at(t[j] - delay);
      mx += x[j - s.begin];
      my += y[j];
    }
    const double m = static_cast<double>(s.end - s.begin);
    mx /= m;
    my /= m;
    for (std::size_t j = s.begin; j < s.end; ++j) {
      const double dx = x[j - s.begin] - mx, dy = y[j] - my;
      sxy += dx * dy;
      sxx += dx * dx;
      syy += dy * dy;
    }
    count += s.end - s.begin;
  }
  Regression r;
  r.gain = sxx > 0 ? sxy / sxx : 0.0;
  r.sse = syy - r.gain * sxy;
  r.sxx = sxx;
  r.syy = syy;
  r.count = count;
  return r;
}

// The delay with the least squared error: the best lag on the gyroscope's sample grid,
// then a golden-section search within one sample of it.
double best_delay(const Integral& integral, const std::vector<double>& t,
                  const std::vector<double>& y, const std::vector<Segment>& segments,
                  double max_delay_s, std::size_t skip) {
  // A coarse grid of 5 samples first (the error is smooth in the delay: the door's motion
  // is slow next to the sample rate), then every sample around its best.
  const double step = 1.0 / integral.rate_hz;
  const auto lags = static_cast<long>(std::ceil(max_delay_s / step));
  double best = 0.0, best_sse = INFINITY;
  auto consider = [&](long lag) {
    const double d = static_cast<double>(lag) * step;
    const double sse = regress(integral, t, y, segments, d, skip).sse;
    if (sse < best_sse) {
      best_sse = sse;
      best = d;
    }
  };
  constexpr long kCoarse = 5;
  for (long lag = -lags; lag <= lags; lag += kCoarse) consider(lag);
  const auto centre = static_cast<long>(std::lround(best / step));
  for (long lag = std::max(-lags, centre - kCoarse); lag <= std::min(lags, centre + kCoarse);
       ++lag) {
    consider(lag);
  }
  double a = best - step, b = best + step;
  const double ratio = (std::sqrt(5.0) - 1) / 2;
  double c = b - ratio * (b - a), d = a + ratio * (b - a);
  double fc = regress(integral, t, y, segments, c, skip).sse;
  double fd = regress(integral, t, y, segments, d, skip).sse;
  for (int iteration = 0; iteration < 30; ++iteration) {
    if (fc < fd) {
      b = d;
      d = c;
      fd = fc;
      c = b - ratio * (b - a);
      fc = regress(integral, t, y, segments, c, skip).sse;
    } else {
      a = c;
      c = d;
      fc = fd;
      d = a + ratio * (b - a);
      fd = regress(integral, t, y, segments, d, skip).sse;
    }
  }
  return 0.5 * (a + b);
}

// The rate integrated (trapezoids) on the gyroscope's uniform clock.
Integral integrate_rate(const std::vector<double>& gyro_time_s,
                        const std::vector<double>& gyro_rad_s) {
  const std::size_t ng = gyro_rad_s.size();
  Integral integral;
  integral.t0 = gyro_time_s.front();
  integral.rate_hz = static_cast<double>(ng - 1) / (gyro_time_s.back() - gyro_time_s.front());
  integral.theta.assign(ng, 0.0);
  for (std::size_t i = 1; i < ng; ++i) {
    integral.theta[i] =
        integral.theta[i - 1] + 0.5 * (gyro_rad_s[i - 1] + gyro_rad_s[i]) / integral.rate_hz;
  }
  return integral;
}

// The stroke segments: runs of inclinometer samples in range near the door's motion (on
// the gyroscope's clock, padded) that travel at least min_travel_deg, have 8 samples and
// no saturated gyroscope sample within max_delay_s. Throws CalibrationError with fewer
// than min_segments.
std::vector<Segment> stroke_segments(const Integral& integral,
                                     const std::vector<double>& inclinometer_time_s,
                                     const std::vector<double>& inclinometer_rad,
                                     const std::vector<bool>& inclinometer_in_range,
                                     const std::vector<double>& gyro_rad_s,
                                     const std::vector<bool>& gyro_valid,
                                     const AlignmentOptions& options) {
  const std::size_t ng = gyro_rad_s.size(), ni = inclinometer_rad.size();
  // Where the door moves (on the gyroscope's clock), padded; and saturated samples.
  const double motion = options.motion_rate_dps / kDegPerRad;
  const auto pad = static_cast<std::size_t>(std::round(options.motion_pad_s * integral.rate_hz));
  std::vector<char> near_motion(ng, 0);
  std::vector<double> invalid_prefix(ng + 1, 0.0);
  for (std::size_t i = 0; i < ng; ++i) {
    invalid_prefix[i + 1] = invalid_prefix[i] + (gyro_valid[i] ? 0.0 : 1.0);
    if (std::abs(gyro_rad_s[i]) > motion) {
      const std::size_t a = i > pad ? i - pad : 0, b = std::min(ng, i + pad + 1);
      for (std::size_t k = a; k < b; ++k) near_motion[k] = 1;
    }
  }
  auto gyro_index = [&](double t) {
    const double x = std::round((t - integral.t0) * integral.rate_hz);
    return static_cast<std::size_t>(std::clamp(x, 0.0, static_cast<double>(ng - 1)));
  };
  std::vector<Segment> segments;
  for (std::size_t j = 0; j < ni;) {
    auto usable = [&](std::size_t k) {
      return inclinometer_in_range[k] && near_motion[gyro_index(inclinometer_time_s[k])];
    };
    if (!usable(j)) {
      ++j;
      continue;
    }
    std::size_t e = j;
    while (e < ni && usable(e)) ++e;
    const auto [lo, hi] = std::minmax_element(inclinometer_rad.begin() + static_cast<long>(j),
                                              inclinometer_rad.begin() + static_cast<long>(e));
    const double travel_deg = (*hi - *lo) * kDegPerRad;
    // Left out near saturation: the integral is wrong from there on.
    const std::size_t ga = gyro_index(inclinometer_time_s[j] - options.max_delay_s);
    const std::size_t gb = gyro_index(inclinometer_time_s[e - 1] + options.max_delay_s);
    const bool saturated = invalid_prefix[gb + 1] - invalid_prefix[ga] > 0;
    if (travel_deg >= options.min_travel_deg && !saturated && e - j >= 8)
      segments.push_back({j, e});
    j = e;
  }
  if (static_cast<int>(segments.size()) < options.min_segments) {
    throw CalibrationError(
        "alignment of the inclinometer with the gyroscope: " + std::to_string(segments.size()) +
        " stroke segments within the inclinometer's range (moving at least " +
        shortest(options.min_travel_deg) + "°, no saturation nearby); at least " +
        std::to_string(options.min_segments) +
        " are needed: record openings and closings through the closed position");
  }
  return segments;
}

// The sum of squares of the gyroscope's rate about its mean within each segment, read at
// the inclinometer's samples less the delay (for the delay's least-squares deviation).
double rate_sum_of_squares(const std::vector<Segment>& segments,
                           const std::vector<double>& inclinometer_time_s,
                           const std::vector<double>& gyro_time_s,
                           const std::vector<double>& gyro_rad_s, double delay_s) {
  double rate_ss = 0.0;
  for (const Segment& s : segments) {
    double mean = 0.0;
    std::vector<double> w;
    for (std::size_t j = s.begin; j < s.end; ++j) {
      const double t = inclinometer_time_s[j] - delay_s;
      w.push_back(interpolate_held(gyro_time_s, gyro_rad_s, t));
      mean += w.back();
    }
    mean /= static_cast<double>(w.size());
    for (double v : w) rate_ss += (v - mean) * (v - mean);
  }
  return rate_ss;
}

// The jackknife's standard deviation of leave-one-out estimates.
double jackknife_std(const std::vector<double>& v) {
  const double k = static_cast<double>(v.size());
  const double mean = mean_of(v);
  double sum = 0.0;
  for (double x : v) sum += (x - mean) * (x - mean);
  return std::sqrt((k - 1) / k * sum);
}

// Each segment described: its times, samples, travel and the delay found without it.
std::vector<AlignmentSegment> describe_segments(const std::vector<Segment>& segments,
                                                const std::vector<double>& inclinometer_time_s,
                                                const std::vector<double>& inclinometer_rad,
                                                const std::vector<double>& delays) {
  std::vector<AlignmentSegment> described;
  for (std::size_t i = 0; i < segments.size(); ++i) {
    AlignmentSegment s;
    s.start_s = inclinometer_time_s[segments[i].begin];
    s.end_s = inclinometer_time_s[segments[i].end - 1];
    s.samples = segments[i].end - segments[i].begin;
    const auto [lo, hi] =
        std::minmax_element(inclinometer_rad.begin() + static_cast<long>(segments[i].begin),
                            inclinometer_rad.begin() + static_cast<long>(segments[i].end));
    s.travel_deg = (*hi - *lo) * kDegPerRad;
    s.delay_without_s = delays[i];
    described.push_back(s);
  }
  return described;
}

}  // namespace

// The stages: integrate the rate, find the stroke segments, the delay and gain over all of
// them, their least-squares and jackknife deviations, and the segments described.
Alignment align_inclinometer_with_gyro(const std::vector<double>& inclinometer_time_s,
                                       const std::vector<double>& inclinometer_rad,
                                       const std::vector<bool>& inclinometer_in_range,
                                       const std::vector<double>& gyro_time_s,
                                       const std::vector<double>& gyro_rad_s,
                                       const std::vector<bool>& gyro_valid,
                                       const AlignmentOptions& options) {
  if (std::string problem = options.validate(); !problem.empty()) throw CalibrationError(problem);
  const std::size_t ng = gyro_rad_s.size(), ni = inclinometer_rad.size();
  if (ng < 16 || ni < 16) throw CalibrationError("alignment: too few samples");
  const Integral integral = integrate_rate(gyro_time_s, gyro_rad_s);
  const std::vector<Segment> segments =
      stroke_segments(integral, inclinometer_time_s, inclinometer_rad, inclinometer_in_range,
                      gyro_rad_s, gyro_valid, options);

  Alignment result;
  const std::size_t none = segments.size();
  result.delay_s = best_delay(integral, inclinometer_time_s, inclinometer_rad, segments,
                              options.max_delay_s, none);
  const Regression fit =
      regress(integral, inclinometer_time_s, inclinometer_rad, segments, result.delay_s, none);
  result.gain = fit.gain;
  const auto parameters = segments.size() + 2;  // offsets, gain, delay
  const double dof = static_cast<double>(fit.count) - static_cast<double>(parameters);
  result.residual_std_rad = std::sqrt(std::max(fit.sse, 0.0) / dof);
  // Least-squares standard deviations (white residuals)…
  const double rate_ss =
      rate_sum_of_squares(segments, inclinometer_time_s, gyro_time_s, gyro_rad_s, result.delay_s);
  const double delay_ls = result.residual_std_rad / (std::abs(fit.gain) * std::sqrt(rate_ss));
  const double gain_ls = result.residual_std_rad / std::sqrt(fit.sxx);
  // …and the jackknife over segments, which also sees how the lag differs between
  // openings and closings (a low-pass is not exactly a delay).
  std::vector<double> delays, gains;
  for (std::size_t skip = 0; skip < segments.size(); ++skip) {
    const double d = best_delay(integral, inclinometer_time_s, inclinometer_rad, segments,
                                options.max_delay_s, skip);
    delays.push_back(d);
    gains.push_back(
        regress(integral, inclinometer_time_s, inclinometer_rad, segments, d, skip).gain);
  }
  const double factor = small_sample_factor(static_cast<int>(segments.size()) - 1);
  result.delay_std_s = std::max(delay_ls, jackknife_std(delays)) * factor;
  result.gain_std = std::max(gain_ls, jackknife_std(gains)) * factor;
  result.segments = describe_segments(segments, inclinometer_time_s, inclinometer_rad, delays);
  return result;
}

std::vector<bool> inclinometer_in_range(const SessionReader& session, const std::string& channel,
                                        const std::vector<double>& signal_V, double range_deg,
                                        double margin_deg) {
  double volts_per_deg = 0.4;
  if (range_deg <= 0) {
    const std::optional<RigDefinition> rig = session_rig(session);
    const RigChannel* rc = rig ? rig->find_channel(channel) : nullptr;
    if (!rc) {
      throw CalibrationError(session.path().string() + ": the range of inclinometer " + channel +
                             " is unknown (the session has no rig with that channel); give it "
                             "with --inclinometer-range-deg");
    }
    const InclinometerParameters p = inclinometer_parameters(*rc);
    range_deg = p.range_deg;
    volts_per_deg = p.output_V_per_deg;
  }
  const double limit_V = std::max(0.0, range_deg - margin_deg) * volts_per_deg;
  std::vector<bool> in_range(signal_V.size());
  for (std::size_t j = 0; j < signal_V.size(); ++j) in_range[j] = std::abs(signal_V[j]) <= limit_V;
  return in_range;
}

TimingCalibration calibrate_timing(const SessionReader& session,
                                   const std::string& inclinometer_channel,
                                   const std::string& gyro_channel,
                                   const TimingCalibrationOptions& options,
                                   const RecordHeader& header) {
  if (std::string problem = options.validate(); !problem.empty()) throw CalibrationError(problem);
  const std::string inclinometer_name =
      find_session_channel(session, "inclinometer", inclinometer_channel);
  const std::string gyro_name = find_session_channel(session, "gyroscope", gyro_channel);
  // The gyroscope's bias and saturation first (its scale does not change the delay).
  GyroCalibrationOptions gyro_options = options.gyro;
  gyro_options.estimate_scale = false;
  const GyroCalibration gyro_calibration =
      calibrate_gyroscope(session, gyro_name, inclinometer_name, gyro_options, RecordHeader{});
  const ChannelSignal gyro = read_channel_signal(session, gyro_name);
  const ChannelSignal inclinometer = read_channel_signal(session, inclinometer_name);
  if (!inclinometer.record) {
    throw CalibrationError(session.path().string() + ": inclinometer " + inclinometer_name +
                           " has no calibration record to add the delay to");
  }
  std::vector<double> rate(gyro.physical.size());
  std::vector<bool> valid(rate.size(), true);
  const double bias = gyro_calibration.bias_dps / kDegPerRad;
  for (std::size_t i = 0; i < rate.size(); ++i) rate[i] = gyro.physical[i] - bias;
  for (const auto& [start, end] : gyro_calibration.saturated_intervals) {
    for (std::size_t i = 0; i < rate.size(); ++i) {
      if (gyro.time_s[i] >= start && gyro.time_s[i] <= end) valid[i] = false;
    }
  }
  const std::vector<bool> in_range = inclinometer_in_range(
      session, inclinometer_name, inclinometer.signal, options.gyro.inclinometer_range_deg,
      options.gyro.inclinometer_margin_deg);

  TimingCalibration r;
  r.gyro_bias_dps = gyro_calibration.bias_dps;
  r.previous_delay_s = inclinometer.record->delay_s;
  r.alignment = align_inclinometer_with_gyro(inclinometer.time_s, inclinometer.physical, in_range,
                                             gyro.time_s, rate, valid, options.alignment);
  CalibrationRecord& record = r.record;
  record = *inclinometer.record;
  record.delay_s = r.alignment.delay_s;
  record.delay_standard_uncertainty_s = r.alignment.delay_std_s;
  record.method = inclinometer.record->method +
                  "; delay by cross-correlation with the integrated gyroscope " + gyro_name +
                  " on " + std::to_string(r.alignment.segments.size()) + " segments";
  record.quantities.push_back({.name = "delay_s",
                               .value = r.alignment.delay_s,
                               .standard_uncertainty = r.alignment.delay_std_s,
                               .unit = "s"});
  record.quantities.push_back({.name = "angle_per_integrated_gyro_angle",
                               .value = r.alignment.gain,
                               .standard_uncertainty = r.alignment.gain_std,
                               .unit = "1"});
  record.references += std::string(record.references.empty() ? "" : "; ") + "timing: recording " +
                       session.path().filename().string() + ", gyroscope " + gyro_name;
  RecordHeader h = header;
  if (h.sensor_serial.empty()) h.sensor_serial = inclinometer.info.sensor_serial;
  if (h.supersedes.empty()) h.supersedes = inclinometer.record->id;
  record.notes.clear();
  apply_header(record, h);
  return r;
}

std::string TimingCalibration::brief_report() const {
  std::string text = "timing: inclinometer against the integrated gyroscope on " +
                     std::to_string(alignment.segments.size()) + " segments\n";
  text += "  delay " + fixed(1e3 * alignment.delay_s, 3) + " ms ± " +
          fixed(1e3 * alignment.delay_std_s, 3) + " ms (the record said " +
          fixed(1e3 * previous_delay_s, 3) + " ms)\n";
  text += "  inclinometer angle per integrated gyroscope angle " + fixed(alignment.gain, 5) +
          " ± " + fixed(alignment.gain_std, 5) + "; residual sd " +
          fixed(alignment.residual_std_rad * kDegPerRad, 4) + "°\n";
  text += "  leaving each segment out:";
  for (const AlignmentSegment& s : alignment.segments) {
    text.append(" ").append(fixed(1e3 * s.delay_without_s, 2));
  }
  text += " ms\n";
  return text;
}

}  // namespace doorbench::calibration
