#include "analysis/design/felt_quantities.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "analysis/preprocessing/preprocessing.h"
#include "core/number_format.h"
#include "core/numbers.h"
#include "core/percentile.h"
#include "core/units.h"

namespace doorbench {

namespace {

double finite_median(std::vector<double> values) {
  std::erase_if(values, [](double v) { return !std::isfinite(v); });
  return median(std::move(values));
}

bool positive_finite(double value) {
  return std::isfinite(value) && value > 0;
}

}  // namespace

const std::array<FeltQuantityInfo, 6> kFeltQuantities = {{
    {"peak_unlatch_force_N", "peak force to unlatch", "N", &FeltQuantities::peak_unlatch_force_N},
    {"peak_latch_force_N", "peak force to latch", "N", &FeltQuantities::peak_latch_force_N},
    {"friction_near_closed_N", "friction near closed", "N",
     &FeltQuantities::friction_near_closed_N},
    {"friction_open_N", "friction further open", "N", &FeltQuantities::friction_open_N},
    {"free_movement_friction_N", "friction in free movement", "N",
     &FeltQuantities::free_movement_friction_N},
    {"balance_force_N", "holding force at mid-angle", "N", &FeltQuantities::balance_force_N},
}};

std::string felt_label(const FeltQuantityInfo& info) {
  return std::string(info.label) + " (" + std::string(info.unit) + ")";
}

std::string felt_definition(const FeltOptions& o) {
  return printf_text(
      "hand force at the handle; peaks within %.1f deg of closed (latching: while moving "
      "faster than %.2f rad/s), median over strokes; friction = half the opening-closing gap "
      "from %.1f to %.1f deg (near closed) and beyond (further open, to %.1f deg short of the "
      "largest angle); holding force = mean of opening and closing at %.0f +- %.0f deg "
      "(> 0: falls shut)",
      o.latch_zone_rad * kDegPerRad, o.moving_rate_rad_s, o.latch_zone_rad * kDegPerRad,
      o.near_closed_end_rad * kDegPerRad, o.open_end_margin_rad * kDegPerRad,
      o.balance_angle_rad * kDegPerRad, o.balance_half_width_rad * kDegPerRad);
}

std::string standard_run_conditions(const FeltOptions& o) {
  return printf_text("virtual hand, 0 to %.0f deg and back in %.0f s (opening %.1f s)",
                     o.hand.target_angle_rad * kDegPerRad, o.hand.duration_s,
                     o.hand.opening_fraction * o.hand.duration_s);
}

std::string FeltOptions::validate() const {
  if (std::string error = hand.validate(); !error.empty()) return error;
  if (std::string error = simulation.validate(); !error.empty()) return error;
  if (!positive_finite(output_rate_hz)) return "felt output_rate_hz must be > 0";
  if (!positive_finite(latch_zone_rad)) return "felt latch_zone_rad must be > 0";
  if (!positive_finite(bin_width_rad)) return "felt bin_width_rad must be > 0";
  if (!(moving_rate_rad_s >= 0)) return "felt moving_rate_rad_s must be >= 0";
  if (!(near_closed_end_rad > latch_zone_rad)) {
    return "felt near_closed_end_rad must be > latch_zone_rad";
  }
  if (!(open_end_margin_rad >= 0)) return "felt open_end_margin_rad must be >= 0";
  if (!positive_finite(balance_angle_rad)) return "felt balance_angle_rad must be > 0";
  if (!positive_finite(balance_half_width_rad)) return "felt balance_half_width_rad must be > 0";
  if (!positive_finite(acceleration_cutoff_hz)) return "felt acceleration_cutoff_hz must be > 0";
  if (peak_median_samples < 1 || peak_median_samples % 2 == 0) {
    return "felt peak_median_samples must be odd and >= 1";
  }
  return "";
}

namespace {

void check(const FeltOptions& options, double theta_max_rad) {
  if (std::string error = options.validate(); !error.empty()) throw std::invalid_argument(error);
  if (!positive_finite(theta_max_rad)) {
    throw std::invalid_argument("felt quantities: theta_max_rad must be > 0");
  }
}

std::size_t stroke_count(std::span<const PreparedData> data) {
  std::size_t count = 0;
  for (const PreparedData& d : data) count += d.strokes.size();
  return count;
}

// The mean of (opening − sign × closing) / 2 over bins whose centre is in [from, to] and which
// hold both directions; `sign` +1 gives the friction, −1 the balance. Median for friction (robust
// to a bin crossing the latch), mean for the balance (its bins are few and adjacent).
double combine(const ForceAngleCurve& curve, double from_rad, double to_rad, double sign,
               bool use_median) {
  std::vector<double> values;
  for (std::size_t b = 0; b < curve.angle_rad.size(); ++b) {
    if (curve.angle_rad[b] < from_rad || curve.angle_rad[b] > to_rad) continue;
    if (curve.opening_count[b] == 0 || curve.closing_count[b] == 0) continue;
    values.push_back(0.5 * (curve.opening_force_N[b] - sign * curve.closing_force_N[b]));
  }
  if (values.empty()) return kNaN;
  if (use_median) return finite_median(std::move(values));
  double sum = 0.0;
  for (double v : values) sum += v;
  return sum / static_cast<double>(values.size());
}

}  // namespace

ForceAngleCurve force_angle_curve(std::span<const PreparedData> data, double theta_max_rad,
                                  const FeltOptions& options) {
  check(options, theta_max_rad);
  ForceAngleCurve curve;
  curve.bin_width_rad = options.bin_width_rad;
  const auto bins = static_cast<std::size_t>(std::ceil(theta_max_rad / options.bin_width_rad));
  curve.angle_rad.resize(bins);
  for (std::size_t b = 0; b < bins; ++b) {
    curve.angle_rad[b] = (static_cast<double>(b) + 0.5) * options.bin_width_rad;
  }
  std::vector<double> open_sum(bins, 0.0), close_sum(bins, 0.0);
  curve.opening_count.assign(bins, 0);
  curve.closing_count.assign(bins, 0);
  for (const PreparedData& d : data) {
    for (const Stroke& stroke : d.strokes) {
      for (std::size_t i = 0; i < stroke.size(); ++i) {
        const double theta = stroke.theta_rad[i];
        const double omega = stroke.omega_rad_s[i];
        if (!(theta >= 0 && theta < theta_max_rad) || !std::isfinite(stroke.force_N[i])) continue;
        if (!(std::abs(omega) > options.moving_rate_rad_s)) continue;
        const auto b = std::min(bins - 1, static_cast<std::size_t>(theta / options.bin_width_rad));
        // The direction of the moment, not of the stroke: a door bouncing back off the open
        // stop during an opening stroke is closing.
        if (omega > 0) {
          open_sum[b] += stroke.force_N[i];
          ++curve.opening_count[b];
        } else {
          close_sum[b] += stroke.force_N[i];
          ++curve.closing_count[b];
        }
      }
    }
  }
  curve.opening_force_N.resize(bins);
  curve.closing_force_N.resize(bins);
  for (std::size_t b = 0; b < bins; ++b) {
    curve.opening_force_N[b] = curve.opening_count[b] ? open_sum[b] / curve.opening_count[b] : kNaN;
    curve.closing_force_N[b] =
        curve.closing_count[b] ? close_sum[b] / curve.closing_count[b] : kNaN;
  }
  return curve;
}

FeltQuantities felt_from_strokes(std::span<const PreparedData> data, double theta_max_rad,
                                 const FeltOptions& options) {
  check(options, theta_max_rad);
  if (stroke_count(data) == 0) throw std::invalid_argument("felt quantities: no strokes");
  FeltQuantities felt{kNaN, kNaN, kNaN, kNaN, kNaN, kNaN, kNaN, options.balance_angle_rad};

  // Peaks per stroke, near closed; the median over strokes (one odd stroke does not set it).
  std::vector<double> unlatch_peaks, unlatch_angles, latch_peaks;
  for (const PreparedData& d : data) {
    for (const Stroke& stroke : d.strokes) {
      double peak = -std::numeric_limits<double>::infinity();
      double peak_angle = kNaN;
      const std::size_t n = stroke.size();
      const auto half = static_cast<std::size_t>(options.peak_median_samples / 2);
      std::vector<double> window;
      for (std::size_t i = 0; i < n; ++i) {
        const double theta = stroke.theta_rad[i];
        if (!(theta > 0 && theta < options.latch_zone_rad)) continue;
        const bool opening = stroke.direction == StrokeDirection::kOpening;
        if (!opening && !(stroke.omega_rad_s[i] < -options.moving_rate_rad_s)) continue;
        // The running median: one sample's noise (an angle on the latch's crest) sets no peak.
        window.clear();
        for (std::size_t k = i >= half ? i - half : 0; k <= std::min(n - 1, i + half); ++k) {
          window.push_back(opening ? stroke.force_N[k] : -stroke.force_N[k]);
        }
        const double value = finite_median(window);
        if (value > peak) {
          peak = value;
          peak_angle = theta;
        }
      }
      if (!std::isfinite(peak)) continue;
      if (stroke.direction == StrokeDirection::kOpening) {
        unlatch_peaks.push_back(peak);
        unlatch_angles.push_back(peak_angle);
      } else {
        latch_peaks.push_back(peak);
      }
    }
  }
  felt.peak_unlatch_force_N = finite_median(unlatch_peaks);
  felt.unlatch_angle_rad = finite_median(unlatch_angles);
  felt.peak_latch_force_N = finite_median(latch_peaks);

  const ForceAngleCurve curve = force_angle_curve(data, theta_max_rad, options);
  const double open_end = theta_max_rad - options.open_end_margin_rad;
  felt.friction_near_closed_N =
      combine(curve, options.latch_zone_rad, options.near_closed_end_rad, 1.0, true);
  felt.friction_open_N = combine(curve, options.near_closed_end_rad, open_end, 1.0, true);
  felt.free_movement_friction_N = combine(curve, options.latch_zone_rad, open_end, 1.0, true);
  felt.balance_force_N =
      combine(curve, options.balance_angle_rad - options.balance_half_width_rad,
              options.balance_angle_rad + options.balance_half_width_rad, -1.0, false);
  return felt;
}

PreparedData virtual_hand_strokes(const DoorModel& model, const FeltOptions& options) {
  check(options, model.geometry().theta_max_rad);
  const VirtualHand hand(options.hand, model.geometry().handle_radius_m);
  // The run ends at the last sample of a stroke: what follows (the door let go at rest) is
  // read by no quantity, and the samples before it do not depend on it.
  auto samples =
      static_cast<std::size_t>(std::floor(hand.duration_s() * options.output_rate_hz)) + 1;
  while (samples > 1 &&
         hand.stroke_at(static_cast<double>(samples - 1) / options.output_rate_hz) == 0) {
    --samples;
  }
  std::vector<double> times(samples);
  for (std::size_t i = 0; i < samples; ++i) {
    times[i] = static_cast<double>(i) / options.output_rate_hz;
  }
  const Trajectory run = simulate(model, hand, DoorState{}, times, options.simulation);
  PreparedData data;
  data.source = "virtual hand";
  data.handle_radius_m = model.geometry().handle_radius_m;
  data.sample_rate_hz = options.output_rate_hz;
  for (const int marker : {1, 2}) {
    Stroke stroke;
    stroke.id = marker;
    stroke.direction = marker == 1 ? StrokeDirection::kOpening : StrokeDirection::kClosing;
    for (std::size_t i = 0; i < samples; ++i) {
      if (hand.stroke_at(times[i]) != marker) continue;
      stroke.time_s.push_back(times[i]);
      stroke.force_N.push_back(run.force_N[i]);
      stroke.theta_rad.push_back(run.theta_rad[i]);
      stroke.omega_rad_s.push_back(run.omega_rad_s[i]);
    }
    data.strokes.push_back(std::move(stroke));
  }
  return data;
}

FeltQuantities felt_quantities(const DoorModel& model, const FeltOptions& options) {
  const PreparedData strokes = virtual_hand_strokes(model, options);
  return felt_from_strokes(std::span<const PreparedData>(&strokes, 1),
                           model.geometry().theta_max_rad, options);
}

std::vector<PreparedData> model_force_along(const DoorModel& model,
                                            std::span<const PreparedData> recordings,
                                            const FeltOptions& options) {
  check(options, model.geometry().theta_max_rad);
  const double r_h = model.geometry().handle_radius_m;
  const double inertia = model.inertia_kg_m2();
  std::vector<PreparedData> out(recordings.begin(), recordings.end());
  for (PreparedData& d : out) {
    for (Stroke& stroke : d.strokes) {
      const std::size_t n = stroke.size();
      std::vector<double> alpha(n, 0.0);
      if (n >= 3) {
        // The stroke's own rate (a recording's sample_rate_hz may be 0 when unknown).
        const double rate_hz =
            static_cast<double>(n - 1) / (stroke.time_s.back() - stroke.time_s[0]);
        const double cutoff = std::min(options.acceleration_cutoff_hz, 0.4 * rate_hz);
        alpha = smoothing_derivative(stroke.time_s, stroke.omega_rad_s, cutoff, rate_hz);
      }
      for (std::size_t i = 0; i < n; ++i) {
        const double tau_m = model.torque_Nm(stroke.theta_rad[i], stroke.omega_rad_s[i]);
        stroke.force_N[i] = (inertia * alpha[i] - tau_m) / r_h;
      }
    }
    d.source = std::string("model along ").append(d.source);
  }
  return out;
}

FeelCheck compare_feel(const DoorModel& model, std::span<const PreparedData> recordings,
                       const FeltOptions& options) {
  if (recordings.empty()) throw std::invalid_argument("compare_feel: no recordings");
  if (stroke_count(recordings) == 0) {
    throw std::invalid_argument(std::string("compare_feel: no strokes in ")
                                    .append(recordings[0].source)
                                    .append(recordings.size() > 1 ? " and the others" : ""));
  }
  const double theta_max = model.geometry().theta_max_rad;
  const std::vector<PreparedData> along = model_force_along(model, recordings, options);
  FeelCheck result;
  result.model_curve = force_angle_curve(along, theta_max, options);
  result.recorded_curve = force_angle_curve(recordings, theta_max, options);
  result.model = felt_from_strokes(along, theta_max, options);
  result.recorded = felt_from_strokes(recordings, theta_max, options);
  for (const FeltQuantityInfo& info : kFeltQuantities) {
    FeltQuantityError e;
    e.name = std::string(info.name);
    e.model = result.model.*info.member;
    e.recorded = result.recorded.*info.member;
    e.error = e.model - e.recorded;
    e.error_percent = std::isfinite(e.recorded) && e.recorded != 0
                          ? 100.0 * e.error / std::abs(e.recorded)
                          : kNaN;
    result.errors.push_back(e);
  }
  // Curves from the same samples: a bin holds model samples exactly when it holds recorded ones.
  double open_sum = 0, close_sum = 0;
  int open_n = 0, close_n = 0;
  const ForceAngleCurve& m = result.model_curve;
  const ForceAngleCurve& r = result.recorded_curve;
  for (std::size_t b = 0; b < r.angle_rad.size(); ++b) {
    if (r.opening_count[b] > 0) {
      open_sum += std::pow(m.opening_force_N[b] - r.opening_force_N[b], 2);
      ++open_n;
    }
    if (r.closing_count[b] > 0) {
      close_sum += std::pow(m.closing_force_N[b] - r.closing_force_N[b], 2);
      ++close_n;
    }
  }
  result.opening_rms_error_N = open_n ? std::sqrt(open_sum / open_n) : kNaN;
  result.closing_rms_error_N = close_n ? std::sqrt(close_sum / close_n) : kNaN;
  result.bins_compared = open_n + close_n;
  result.curve_rms_error_N =
      result.bins_compared ? std::sqrt((open_sum + close_sum) / result.bins_compared) : kNaN;
  return result;
}

std::string FeltQuantities::brief_report() const {
  std::string text;
  text += printf_text("  peak force to unlatch       %7.2f N (at %.2f deg)\n", peak_unlatch_force_N,
                      unlatch_angle_rad * kDegPerRad);
  text += printf_text("  peak force to latch         %7.2f N\n", peak_latch_force_N);
  text += printf_text("  friction near closed        %7.2f N\n", friction_near_closed_N);
  text += printf_text("  friction further open       %7.2f N\n", friction_open_N);
  text += printf_text("  friction in free movement   %7.2f N\n", free_movement_friction_N);
  text += printf_text("  holding force at %4.1f deg   %7.2f N (%s)\n",
                      balance_angle_rad * kDegPerRad, balance_force_N,
                      !std::isfinite(balance_force_N) ? "unknown"
                      : balance_force_N > 0           ? "falls shut when let go"
                                                      : "falls open when let go");
  return text;
}

std::string FeelCheck::brief_report() const {
  std::string text = "  quantity                     model   recorded    error\n";
  for (const FeltQuantityError& e : errors) {
    std::string label = e.name;
    for (const FeltQuantityInfo& info : kFeltQuantities) {
      if (info.name == e.name) label = std::string(info.label);
    }
    text += printf_text("  %-26s %8.2f   %8.2f %8.2f N (%+.1f %%)\n", label.c_str(), e.model,
                        e.recorded, e.error, e.error_percent);
  }
  text += printf_text(
      "  force-angle curve RMS error %.2f N (opening %.2f N, closing %.2f N, %d bins)\n",
      curve_rms_error_N, opening_rms_error_N, closing_rms_error_N, bins_compared);
  return text;
}

}  // namespace doorbench
