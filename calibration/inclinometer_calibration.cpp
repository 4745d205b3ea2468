#include "calibration/inclinometer_calibration.h"

#include <cmath>
#include <numbers>
#include <set>

#include "calibration/least_squares.h"
#include "calibration/session_signals.h"
#include "calibration/static_source.h"
#include "calibration/timing_calibration.h"
#include "core/units.h"
#include "sensors/channel_limits.h"

namespace doorbench::calibration {

namespace {}

std::string InclinometerCalibrationOptions::validate() const {
  if (!(range_deg > 0))
    return "inclinometer calibration range_deg = " + shortest(range_deg) + " must be > 0";
  if (!(output_V_per_deg > 0)) {
    return "inclinometer calibration output_V_per_deg = " + shortest(output_V_per_deg) +
           " must be > 0";
  }
  if (!(max_reference_fraction > 0 && max_reference_fraction <= 1)) {
    return "inclinometer calibration max_reference_fraction = " + shortest(max_reference_fraction) +
           " must be in (0, 1]";
  }
  if (min_references < 3) {
    return "inclinometer calibration min_references = " + std::to_string(min_references) +
           " must be >= 3";
  }
  if (!(min_span_fraction >= 0 && min_span_fraction <= 1)) {
    return "inclinometer calibration min_span_fraction = " + shortest(min_span_fraction) +
           " must be in [0, 1]";
  }
  if (!(reference_standard_uncertainty_deg >= 0)) {
    return "inclinometer calibration reference_standard_uncertainty_deg = " +
           shortest(reference_standard_uncertainty_deg) + " must be >= 0";
  }
  return "";
}

InclinometerCalibration calibrate_inclinometer(std::span<const CalibrationPoint> points,
                                               const InclinometerCalibrationOptions& options,
                                               const RecordHeader& header) {
  if (std::string problem = options.validate(); !problem.empty()) throw CalibrationError(problem);
  const double limit_deg = options.max_reference_fraction * options.range_deg;
  std::set<double> references;
  for (const CalibrationPoint& p : points) {
    const double deg = p.reference * kDegPerRad;
    if (!std::isfinite(deg) || !std::isfinite(p.signal)) {
      throw CalibrationError(
          "inclinometer calibration: a point's reference or reading is not finite");
    }
    if (std::abs(deg) > limit_deg + 1e-9) {
      throw CalibrationError("inclinometer calibration: reference angle " + fixed(deg, 3) +
                             "° is outside ±" + shortest(limit_deg) + "° (" +
                             shortest(100 * options.max_reference_fraction) +
                             " % of the inclinometer's range ±" + shortest(options.range_deg) +
                             "°); a saturated reading says nothing about the gain");
    }
    if (std::abs(p.signal) >= 0.999 * options.range_deg * options.output_V_per_deg) {
      throw CalibrationError("inclinometer calibration: at reference " + fixed(deg, 3) +
                             "° the reading " + fixed(p.signal, 4) +
                             " V is at the end of the range (saturated); use smaller angles");
    }
    references.insert(std::round(deg * 1e6) / 1e6);
  }
  if (static_cast<int>(references.size()) < options.min_references) {
    throw CalibrationError("inclinometer calibration: " + std::to_string(references.size()) +
                           " different reference angles (" + std::to_string(points.size()) +
                           " points); at least " + std::to_string(options.min_references) +
                           " are needed across the range ±" + shortest(options.range_deg) + "°");
  }
  const double span = *references.rbegin() - *references.begin();
  if (span < options.min_span_fraction * 2 * options.range_deg) {
    throw CalibrationError("inclinometer calibration: the reference angles span " + shortest(span) +
                           "°, less than " + shortest(100 * options.min_span_fraction) +
                           " % of the range (" + shortest(2 * options.range_deg) + "°)");
  }
  std::vector<double> signal, reference;
  for (const CalibrationPoint& p : points) {
    signal.push_back(p.signal);
    reference.push_back(p.reference);
  }
  const PolynomialFit fit = fit_polynomial(signal, reference, 1);
  const double factor = small_sample_factor(fit.degrees_of_freedom);
  const double u_ref = options.reference_standard_uncertainty_deg / kDegPerRad;

  InclinometerCalibration r;
  r.points = static_cast<int>(points.size());
  r.offset_deg = -fit.coefficients[0] * kDegPerRad;
  r.offset_std_deg = std::hypot(fit.coefficient_std(0) * factor, u_ref) * kDegPerRad;
  r.gain_rad_per_V = fit.coefficients[1];
  r.gain_std_rad_per_V = fit.coefficient_std(1) * factor;
  r.residual_std_deg = fit.residual_std * kDegPerRad;
  double curve = 0.0;
  for (double v : signal) curve = std::max(curve, fit.value_std(v) * factor);
  r.standard_uncertainty_deg =
      std::sqrt(std::pow(fit.residual_std * factor, 2) + curve * curve + u_ref * u_ref) *
      kDegPerRad;

  CalibrationRecord& record = r.record;
  record.sensor_kind = "inclinometer";
  record.unit = "rad";
  record.input_unit = "V";
  record.coefficients = fit.coefficients;
  record.standard_uncertainty = r.standard_uncertainty_deg / kDegPerRad;
  record.method = "multi-point least squares, straight line, against reference angles";
  record.references = options.references;
  record.valid_min = -options.range_deg / kDegPerRad;
  record.valid_max = options.range_deg / kDegPerRad;
  for (std::size_t i = 0; i < points.size(); ++i) {
    CalibrationPoint p = points[i];
    p.residual = fit.residuals[i];
    record.points.push_back(p);
  }
  record.quantities = {
      {.name = "offset_deg",
       .value = r.offset_deg,
       .standard_uncertainty = r.offset_std_deg,
       .unit = "deg"},
      {.name = "gain_rad_per_V",
       .value = r.gain_rad_per_V,
       .standard_uncertainty = r.gain_std_rad_per_V,
       .unit = "rad/V"},
      {.name = "residual_std_deg",
       .value = r.residual_std_deg,
       .standard_uncertainty = 0.0,
       .unit = "deg"},
      {.name = "range_deg", .value = options.range_deg, .standard_uncertainty = 0.0, .unit = "deg"},
  };
  apply_header(record, header);
  return r;
}

std::string InclinometerCalibration::brief_report() const {
  return "inclinometer: " + std::to_string(points) + " points\n  offset " + fixed(offset_deg, 4) +
         "° ± " + fixed(offset_std_deg, 4) + "° (the reading when level)\n  gain " +
         fixed(gain_rad_per_V * kDegPerRad, 5) + " °/V ± " +
         fixed(gain_std_rad_per_V * kDegPerRad, 5) + " °/V\n  residual sd " +
         fixed(residual_std_deg, 4) + "°; standard uncertainty of a reading " +
         fixed(standard_uncertainty_deg, 4) + "°\n";
}

std::vector<GuidedPoint> inclinometer_angle_points(std::span<const double> angles_deg) {
  std::vector<GuidedPoint> result;
  for (double deg : angles_deg) {
    GuidedPoint p;
    p.reference = deg / kDegPerRad;
    // Built with append: GCC 12 warns falsely (-Wrestrict) on "+" + std::string.
    p.label = deg > 0 ? "+" : "";
    p.label.append(shortest(deg)).append("°");
    p.instruction =
        deg == 0 ? "level the inclinometer (0°)" : "tilt the inclinometer to " + p.label;
    result.push_back(p);
  }
  return result;
}

std::vector<RangeExcursion> inclinometer_range_excursions(const SessionReader& session,
                                                          const std::string& channel,
                                                          double range_deg) {
  // The range the limit is a fraction of: the one given, else the rig's (without either,
  // inclinometer_in_range says the range is unknown).
  double full_range_deg = range_deg;
  if (!(full_range_deg > 0)) {
    const std::optional<RigDefinition> rig = session_rig(session);
    const RigChannel* rc = rig ? rig->find_channel(channel) : nullptr;
    if (rc) full_range_deg = inclinometer_parameters(*rc).range_deg;
  }
  const double margin_deg = (1.0 - sensors::kAtLimitFraction) * full_range_deg;
  const ChannelSignal s = read_channel_signal(session, channel);
  const std::vector<bool> in_range =
      inclinometer_in_range(session, channel, s.signal, range_deg, margin_deg);
  std::vector<RangeExcursion> result;
  for (std::size_t j = 0; j < in_range.size(); ++j) {
    if (in_range[j]) continue;
    if (j > 0 && !in_range[j - 1]) {
      result.back().end_s = s.time_s[j];
    } else {
      result.push_back({s.time_s[j], s.time_s[j]});
    }
  }
  return result;
}

std::string inclinometer_range_warning(const SessionReader& session, const std::string& channel,
                                       double range_deg) {
  const std::vector<RangeExcursion> out =
      inclinometer_range_excursions(session, channel, range_deg);
  if (out.empty()) return "";
  double total = 0.0;
  for (const RangeExcursion& e : out) total += e.end_s - e.start_s;
  std::string range = range_deg > 0 ? shortest(range_deg) : "";
  if (range.empty()) {
    const std::optional<RigDefinition> rig = session_rig(session);
    const RigChannel* rc = rig ? rig->find_channel(channel) : nullptr;
    range = rc ? shortest(inclinometer_parameters(*rc).range_deg) : "?";
  }
  return "inclinometer " + channel + " left its ±" + range + "° range " +
         std::to_string(out.size()) + (out.size() == 1 ? " time" : " times") + " for " +
         fixed(total, 3) + " s in all (first at " + fixed(out.front().start_s, 3) +
         " s); those samples are not angles";
}

}  // namespace doorbench::calibration

namespace doorbench::calibration {

std::string InclinometerRecordingOptions::validate() const {
  if (std::string problem = stillness.validate(); !problem.empty()) return problem;
  if (!(max_drift_deg > 0)) {
    return "inclinometer recording max_drift_deg = " + shortest(max_drift_deg) + " must be > 0";
  }
  if (!(merge_deg >= 0)) {
    return "inclinometer recording merge_deg = " + shortest(merge_deg) + " must be >= 0";
  }
  return "";
}

std::vector<CalibrationPoint> InclinometerRecordingPoints::points() const {
  std::vector<CalibrationPoint> result;
  for (const InclinometerHold& h : holds) result.push_back(h.point);
  return result;
}

std::string InclinometerRecordingPoints::brief_report() const {
  std::string text = "inclinometer holds found in the recording (noise " + fixed(noise_deg, 4) +
                     "° per sample):\n";
  for (const InclinometerHold& h : holds) {
    text += "  " + fixed(h.point.reference * kDegPerRad, 3) + "°: " + fixed(h.start_s, 3) + "–" +
            fixed(h.end_s, 3) + " s, " + std::to_string(h.samples) + " samples, reads " +
            fixed(h.mean_deg, 4) + "°, sd " + fixed(h.point.signal_std, 5) + " V, drift " +
            fixed(h.drift_deg, 4) + "°\n";
  }
  return text;
}

namespace {

// The inclinometer's channel read and checked: a uniform clock, 100 samples, a record to
// read angles through.
ChannelSignal read_inclinometer(const SessionReader& session, const std::string& name,
                                const std::string& where) {
  ChannelSignal s = read_channel_signal(session, name);
  if (s.info.sample_rate_hz <= 0 || s.signal.size() < 100) {
    throw CalibrationError(where + "inclinometer " + name +
                           " needs a uniform clock and at least 100 samples");
  }
  if (!s.record) {
    throw CalibrationError(where + "inclinometer " + name +
                           " has no calibration record to read angles for the stillness test; "
                           "apply its nominal record first");
  }
  return s;
}

// The holds: the still periods' samples, consecutive periods at the same angle (within
// merge_deg) making one hold; each with its signal's mean and spread, its angle and drift.
std::vector<InclinometerHold> holds_from_periods(const ChannelSignal& s,
                                                 const std::vector<double>& angle_deg,
                                                 const std::vector<StillPeriod>& periods,
                                                 double merge_deg) {
  // Sample ranges of the periods; consecutive ones at the same angle are one hold.
  const double t0 = s.time_s.front(), rate_hz = s.info.sample_rate_hz;
  auto index_of = [&](double t) {
    return static_cast<std::size_t>(std::llround((t - t0) * rate_hz));
  };
  std::vector<std::vector<std::pair<std::size_t, std::size_t>>> ranges;  // [a, b) per hold
  std::vector<double> means;
  for (const StillPeriod& p : periods) {
    const std::pair<std::size_t, std::size_t> range{index_of(p.start_s), index_of(p.end_s) + 1};
    if (!means.empty() && std::abs(p.mean_rate_dps - means.back()) < merge_deg) {
      ranges.back().push_back(range);
      continue;
    }
    ranges.push_back({range});
    means.push_back(p.mean_rate_dps);
  }
  std::vector<InclinometerHold> holds;
  for (const auto& hold_ranges : ranges) {
    InclinometerHold h;
    h.start_s = s.time_s[hold_ranges.front().first];
    h.end_s = s.time_s[hold_ranges.back().second - 1];
    std::vector<double> volts, degrees;
    for (const auto& [a, b] : hold_ranges) {
      volts.insert(volts.end(), s.signal.begin() + a, s.signal.begin() + b);
      degrees.insert(degrees.end(), angle_deg.begin() + a, angle_deg.begin() + b);
    }
    h.samples = volts.size();
    h.mean_deg = mean_of(degrees);
    const std::span<const double> all(degrees);
    h.drift_deg =
        std::abs(mean_of(all.subspan(all.size() / 2)) - mean_of(all.first(all.size() / 2)));
    h.point.signal = mean_of(volts);
    h.point.signal_std = std_of(volts);
    h.point.samples = static_cast<int>(volts.size());
    holds.push_back(h);
  }
  return holds;
}

// "a–b s reads x°; …" for the errors ("none" without holds).
std::string list_holds(const std::vector<InclinometerHold>& holds) {
  std::string text;
  for (std::size_t k = 0; k < holds.size(); ++k) {
    const InclinometerHold& h = holds[k];
    text += (k ? "; " : "") + fixed(h.start_s, 2) + "–" + fixed(h.end_s, 2) + " s reads " +
            fixed(h.mean_deg, 2) + "°";
  }
  return text.empty() ? std::string("none") : text;
}

// Throws CalibrationError unless there is one hold per reference angle.
void check_one_hold_per_reference(const std::vector<InclinometerHold>& holds,
                                  std::span<const double> angles_deg, const std::string& references,
                                  const std::string& where, const std::string& name,
                                  const StillnessOptions& stillness) {
  if (holds.size() != angles_deg.size()) {
    throw CalibrationError(
        where + "found " + std::to_string(holds.size()) + " still " +
        (holds.size() == 1 ? "window" : "windows") + " in inclinometer " + name + " where " +
        std::to_string(angles_deg.size()) + " reference angles were given (" + references +
        "°): " + list_holds(holds) + ". Each still stretch of at least " +
        shortest(stillness.min_duration_s + 2 * stillness.guard_s + stillness.window_s) +
        " s counts as one hold: hold each reference once, in the order given, without resting "
        "between them (or give --angles-deg for the holds recorded)");
  }
}

// The holds must follow the references: a step between references moves the reading the
// same way as the overall gain (its sign from the correlation of readings and references).
// Throws CalibrationError naming the first step that does not.
void check_holds_follow_references(const std::vector<InclinometerHold>& holds,
                                   std::span<const double> angles_deg,
                                   const std::string& references, const std::string& where) {
  const std::size_t n = angles_deg.size();
  double mean_ref = 0.0, mean_read = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    mean_ref += angles_deg[k] / n;
    mean_read += holds[k].mean_deg / n;
  }
  double covariance = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    covariance += (angles_deg[k] - mean_ref) * (holds[k].mean_deg - mean_read);
  }
  const double sign = covariance < 0 ? -1.0 : 1.0;
  for (std::size_t k = 1; k < n; ++k) {
    const double step_ref = angles_deg[k] - angles_deg[k - 1];
    const double step_read = holds[k].mean_deg - holds[k - 1].mean_deg;
    if (step_ref != 0 && !(sign * step_read * step_ref > 0)) {
      throw CalibrationError(where + "the holds do not follow the reference angles (" + references +
                             "°) in order: from " + shortest(angles_deg[k - 1]) + "° to " +
                             shortest(angles_deg[k]) + "° the reading went from " +
                             fixed(holds[k - 1].mean_deg, 2) + "° to " +
                             fixed(holds[k].mean_deg, 2) + "° (holds at " + list_holds(holds) +
                             "); give --angles-deg in the order they were held");
    }
  }
}

// Each hold's reference (rad); throws CalibrationError at the first hold that drifted more
// than max_drift_deg.
void assign_references(std::vector<InclinometerHold>& holds, std::span<const double> angles_deg,
                       double max_drift_deg, const std::string& where) {
  const std::size_t n = angles_deg.size();
  for (std::size_t k = 0; k < n; ++k) {
    InclinometerHold& h = holds[k];
    if (h.drift_deg > max_drift_deg) {
      throw CalibrationError(where + "the reading did not settle at hold " + std::to_string(k + 1) +
                             " of " + std::to_string(n) + " (" + shortest(angles_deg[k]) + "°, " +
                             fixed(h.start_s, 2) + "–" + fixed(h.end_s, 2) +
                             " s): the means of its halves differ by " + fixed(h.drift_deg, 4) +
                             "°, limit " + fixed(max_drift_deg, 4) +
                             "°; steady the reference (no touching) and record again");
    }
    h.point.reference = angles_deg[k] / kDegPerRad;
  }
}

}  // namespace

// The stages: read the channel, find its still periods, make them holds, check one hold
// per reference in the references' order, each settled, and give each its reference.
InclinometerRecordingPoints inclinometer_points_from_recording(
    const SessionReader& session, const std::string& channel, std::span<const double> angles_deg,
    const InclinometerRecordingOptions& options) {
  if (std::string problem = options.validate(); !problem.empty()) throw CalibrationError(problem);
  const std::string where = session.path().string() + ": ";
  const std::string name = find_session_channel(session, "inclinometer", channel);
  const ChannelSignal s = read_inclinometer(session, name, where);
  if (angles_deg.empty()) throw CalibrationError("no reference angles (--angles-deg)");

  std::vector<double> angle_deg(s.physical.size());
  for (std::size_t i = 0; i < angle_deg.size(); ++i) angle_deg[i] = s.physical[i] * kDegPerRad;
  InclinometerRecordingPoints result;
  const std::vector<StillPeriod> periods =
      find_still_periods(s.time_s, angle_deg, angle_deg, options.stillness, &result.noise_deg);
  result.holds = holds_from_periods(s, angle_deg, periods, options.merge_deg);

  std::string references;
  for (double a : angles_deg) references.append(references.empty() ? "" : ",").append(shortest(a));
  check_one_hold_per_reference(result.holds, angles_deg, references, where, name,
                               options.stillness);
  check_holds_follow_references(result.holds, angles_deg, references, where);
  assign_references(result.holds, angles_deg, options.max_drift_deg, where);
  return result;
}

}  // namespace doorbench::calibration
