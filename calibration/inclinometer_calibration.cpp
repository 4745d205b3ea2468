#include "calibration/inclinometer_calibration.h"

#include <cmath>
#include <numbers>
#include <set>

#include "calibration/least_squares.h"
#include "calibration/session_signals.h"
#include "calibration/static_source.h"
#include "calibration/timing_calibration.h"

namespace doorbench::calibration {

namespace {
constexpr double kDegPerRad = 180.0 / std::numbers::pi;
}

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
      {"offset_deg", r.offset_deg, r.offset_std_deg, "deg"},
      {"gain_rad_per_V", r.gain_rad_per_V, r.gain_std_rad_per_V, "rad/V"},
      {"residual_std_deg", r.residual_std_deg, 0.0, "deg"},
      {"range_deg", options.range_deg, 0.0, "deg"},
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
                                                          double range_deg, double margin_deg) {
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
