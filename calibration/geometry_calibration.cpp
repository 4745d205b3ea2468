#include "calibration/geometry_calibration.h"

#include <cmath>
#include <numbers>
#include <tuple>

#include "calibration/least_squares.h"
#include "core/units.h"

namespace doorbench::calibration {

namespace {

// Mean of repeated readings and its uncertainty: their scatter (Student-scaled) combined
// with the instrument's resolution.
std::pair<double, double> repeated(const std::vector<double>& values, double resolution) {
  const double mean = mean_of(values);
  const double n = static_cast<double>(values.size());
  const double scatter =
      values.size() >= 2
          ? std_of(values) / std::sqrt(n) * small_sample_factor(static_cast<int>(values.size()) - 1)
          : 0.0;
  return {mean, std::hypot(scatter, resolution / std::sqrt(12.0))};
}
}  // namespace

std::string GeometryCalibrationOptions::validate() const {
  if (!(length_resolution_m >= 0)) {
    return "geometry length_resolution_m = " + shortest(length_resolution_m) + " must be >= 0";
  }
  if (!(angle_resolution_deg >= 0)) {
    return "geometry angle_resolution_deg = " + shortest(angle_resolution_deg) + " must be >= 0";
  }
  return "";
}

GeometryCalibration calibrate_geometry(const GeometryInputs& inputs,
                                       const GeometryCalibrationOptions& options,
                                       const RecordHeader& header) {
  if (std::string problem = options.validate(); !problem.empty()) throw CalibrationError(problem);
  if (inputs.handle_radius_m.empty()) {
    throw CalibrationError(
        "geometry: no measurement of the handle radius (load cell to hinge axis)");
  }
  for (double r : inputs.handle_radius_m) {
    if (!(r > 0) || !std::isfinite(r)) {
      throw CalibrationError("geometry: handle radius " + shortest(r) + " m must be > 0");
    }
  }
  GeometryCalibration g;
  std::tie(g.handle_radius_m, g.handle_radius_std_m) =
      repeated(inputs.handle_radius_m, options.length_resolution_m);
  std::string angle_method;
  if (!inputs.mounting_angle_deg.empty()) {
    for (double a : inputs.mounting_angle_deg) {
      if (!(std::abs(a) < 60)) {
        throw CalibrationError("geometry: mounting angle " + shortest(a) +
                               "° is not a misalignment (|α| must be below 60°)");
      }
    }
    std::tie(g.mounting_angle_deg, g.mounting_angle_std_deg) =
        repeated(inputs.mounting_angle_deg, options.angle_resolution_deg);
    g.cos_factor = std::cos(g.mounting_angle_deg / kDegPerRad);
    angle_method = "mounting angle measured (" + std::to_string(inputs.mounting_angle_deg.size()) +
                   " readings)";
  } else if (inputs.tangential_checks_N.size() >= 2) {
    // reading = cos α · reference, least squares through the origin.
    double srr = 0.0, sry = 0.0;
    for (const auto& [reference, reading] : inputs.tangential_checks_N) {
      srr += reference * reference;
      sry += reference * reading;
    }
    if (!(srr > 0)) throw CalibrationError("geometry: the reference forces are all zero");
    const double c = sry / srr;
    double sse = 0.0;
    for (const auto& [reference, reading] : inputs.tangential_checks_N) {
      sse += std::pow(reading - c * reference, 2);
    }
    const int dof = static_cast<int>(inputs.tangential_checks_N.size()) - 1;
    const double u_c = std::sqrt(sse / dof / srr) * small_sample_factor(dof);
    g.cos_factor = std::min(c, 1.0);
    const double alpha = std::acos(g.cos_factor);
    g.mounting_angle_deg = alpha * kDegPerRad;
    // dα = dc / sin α; near α = 0 the bound from c = 1 − 2u_c instead.
    const double sin_alpha = std::max(std::sin(alpha), std::sqrt(2 * u_c));
    g.mounting_angle_std_deg = u_c / sin_alpha * kDegPerRad;
    angle_method = "mounting angle estimated from " +
                   std::to_string(inputs.tangential_checks_N.size()) +
                   " tangential reference forces";
  } else {
    throw CalibrationError(
        "geometry: no mounting angle: measure it, or apply at least 2 "
        "reference forces tangentially and give the load cell's readings");
  }
  CalibrationRecord& record = g.record;
  record.sensor_kind = "geometry";
  record.input_unit = "N";
  record.unit = "N";
  record.coefficients = {0.0, 1.0 / g.cos_factor};
  const double tan_alpha = std::tan(g.mounting_angle_deg / kDegPerRad);
  // Relative uncertainty of 1/cos α is tan α · u(α).
  record.standard_uncertainty = tan_alpha * g.mounting_angle_std_deg / kDegPerRad;
  record.method = "handle radius measured (" + std::to_string(inputs.handle_radius_m.size()) +
                  " readings); " + angle_method;
  record.references = "tape/calliper resolution " + shortest(options.length_resolution_m) +
                      " m; protractor resolution " + shortest(options.angle_resolution_deg) + "°";
  record.quantities = {
      {"handle_radius_m", g.handle_radius_m, g.handle_radius_std_m, "m"},
      {"mounting_angle_deg", g.mounting_angle_deg, g.mounting_angle_std_deg, "deg"},
      {"cos_mounting_angle", g.cos_factor,
       std::sin(g.mounting_angle_deg / kDegPerRad) * g.mounting_angle_std_deg / kDegPerRad, "1"},
  };
  record.notes =
      "Tangential force = reading / cos(mounting angle); standard_uncertainty is relative.";
  apply_header(record, header);
  return g;
}

std::string GeometryCalibration::brief_report() const {
  return "geometry:\n  handle radius " + fixed(handle_radius_m, 4) + " m ± " +
         fixed(handle_radius_std_m, 4) + " m\n  mounting angle " + fixed(mounting_angle_deg, 2) +
         "° ± " + fixed(mounting_angle_std_deg, 2) + "° (the cell reads " +
         fixed(100 * cos_factor, 3) + " % of the tangential force)\n";
}

}  // namespace doorbench::calibration
