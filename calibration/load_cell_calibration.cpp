#include "calibration/load_cell_calibration.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "calibration/least_squares.h"

namespace doorbench::calibration {

std::string LoadCellCalibrationOptions::validate() const {
  if (!(full_scale_N > 0) || !std::isfinite(full_scale_N)) {
    return "load-cell calibration full_scale_N = " + shortest(full_scale_N) + " must be > 0";
  }
  if (min_references < 3) {
    return "load-cell calibration min_references = " + std::to_string(min_references) +
           " must be >= 3";
  }
  if (!(min_span_fraction_fs >= 0 && min_span_fraction_fs <= 1)) {
    return "load-cell calibration min_span_fraction_fs = " + shortest(min_span_fraction_fs) +
           " must be in [0, 1]";
  }
  if (!(quadratic_significance > 0)) {
    return "load-cell calibration quadratic_significance = " + shortest(quadratic_significance) +
           " must be > 0";
  }
  if (!(reference_relative_uncertainty >= 0)) {
    return "load-cell calibration reference_relative_uncertainty = " +
           shortest(reference_relative_uncertainty) + " must be >= 0";
  }
  return "";
}

namespace {

// Points grouped by reference value (equal within a part in 1e9 of full scale).
std::map<double, std::vector<std::size_t>> by_reference(std::span<const CalibrationPoint> points,
                                                        double full_scale) {
  std::map<double, std::vector<std::size_t>> groups;
  for (std::size_t i = 0; i < points.size(); ++i) {
    double key = points[i].reference;
    for (const auto& [known, members] : groups) {
      if (std::abs(known - key) <= 1e-9 * full_scale) key = known;
    }
    groups[key].push_back(i);
  }
  return groups;
}

std::string kg_text(double force_N) {
  return fixed(force_N / kStandardGravity_m_s2, 2) + " kg";
}

// Throws CalibrationError on a point that is not finite or beyond the cell's range.
void check_load_cell_points(std::span<const CalibrationPoint> points,
                            const LoadCellCalibrationOptions& options) {
  const double fs = options.full_scale_N;
  for (const CalibrationPoint& p : points) {
    if (!std::isfinite(p.reference) || !std::isfinite(p.signal)) {
      throw CalibrationError("load-cell calibration: a point's reference or reading is not finite");
    }
    if (p.reference > fs * (1 + 1e-9)) {
      throw CalibrationError("load-cell calibration: reference " + shortest(p.reference) + " N (" +
                             kg_text(p.reference) + ") is above the cell's full scale " +
                             shortest(fs) + " N; use references from 0 to full scale");
    }
    if (options.compression_only && p.reference < 0) {
      throw CalibrationError("load-cell calibration: reference " + shortest(p.reference) +
                             " N is negative, but the cell reads compression only; use "
                             "references from 0 to full scale");
    }
    if (p.reference < -fs * (1 + 1e-9)) {
      throw CalibrationError("load-cell calibration: reference " + shortest(p.reference) +
                             " N is beyond the cell's full scale -" + shortest(fs) + " N");
    }
  }
}

// Throws CalibrationError unless there are enough different references spanning enough
// of the full scale.
void check_reference_spread(const std::map<double, std::vector<std::size_t>>& groups,
                            std::size_t points, const LoadCellCalibrationOptions& options) {
  const double fs = options.full_scale_N;
  const int references = static_cast<int>(groups.size());
  if (references < options.min_references) {
    throw CalibrationError("load-cell calibration: " + std::to_string(references) +
                           " different references (" + std::to_string(points) +
                           " points); at least " + std::to_string(options.min_references) +
                           " are needed, spread from 0 to full scale (" + shortest(fs) + " N)");
  }
  const double span = groups.rbegin()->first - groups.begin()->first;
  if (span < options.min_span_fraction_fs * fs) {
    throw CalibrationError("load-cell calibration: the references span " + shortest(span) +
                           " N, less than " + shortest(options.min_span_fraction_fs * 100) +
                           " % of full scale (" + shortest(fs) +
                           " N); a gain fitted on a small part of the range does not hold over it");
  }
}

// The straight line through the points and the curve chosen: the quadratic when its
// term is significant (from four points at four references), else the line.
struct LoadCellCurves {
  PolynomialFit line, chosen;
  bool quadratic = false;
};

LoadCellCurves fit_load_cell(const std::vector<double>& signal,
                             const std::vector<double>& reference, int references,
                             double quadratic_significance) {
  const PolynomialFit line = fit_polynomial(signal, reference, 1);
  if (!(line.coefficients[1] > 0)) {
    throw CalibrationError("load-cell calibration: the readings do not rise with the load (gain " +
                           shortest(line.coefficients[1]) +
                           " N/V); check the wiring and that the references were applied");
  }
  LoadCellCurves curves{.line = line, .chosen = line, .quadratic = false};
  if (static_cast<int>(signal.size()) >= 4 && references >= 4) {
    const PolynomialFit curve = fit_polynomial(signal, reference, 2);
    const double c2 = curve.coefficients[2];
    const double u2 = curve.coefficient_std(2);
    if (u2 > 0 && std::abs(c2) > quadratic_significance * u2) {
      curves.chosen = curve;
      curves.quadratic = true;
    } else if (u2 == 0 && c2 != 0 && curve.residual_std < line.residual_std) {
      curves.chosen = curve;  // an exact fit (no noise at all)
      curves.quadratic = true;
    }
  }
  return curves;
}

// Non-linearity: the branch-averaged points against the best straight line.
// Hysteresis: unloading − loading at each reference reached both ways. Both in % of
// full scale, into `r`.
void nonlinearity_and_hysteresis(std::span<const CalibrationPoint> points,
                                 const std::map<double, std::vector<std::size_t>>& groups,
                                 const LoadCellCurves& curves, double fs, LoadCellCalibration& r) {
  double nonlinearity = 0.0, hysteresis = 0.0;
  for (const auto& [ref, members] : groups) {
    double sum = 0.0, loading = 0.0, unloading = 0.0;
    int n_loading = 0, n_unloading = 0;
    for (std::size_t i : members) {
      sum += curves.line.residuals[i];
      if (points[i].branch == "loading") {
        loading += curves.chosen.residuals[i];
        ++n_loading;
      } else if (points[i].branch == "unloading") {
        unloading += curves.chosen.residuals[i];
        ++n_unloading;
      }
    }
    nonlinearity = std::max(nonlinearity, std::abs(sum / static_cast<double>(members.size())));
    if (n_loading > 0 && n_unloading > 0) {
      hysteresis = std::max(hysteresis, std::abs(unloading / n_unloading - loading / n_loading));
    }
  }
  r.nonlinearity_percent_fs = 100.0 * nonlinearity / fs;
  r.hysteresis_percent_fs = 100.0 * hysteresis / fs;
}

// The record: the chosen curve's coefficients, its points with their residuals and the
// quantities found.
void write_load_cell_record(std::span<const CalibrationPoint> points, const PolynomialFit& chosen,
                            const LoadCellCalibrationOptions& options, const RecordHeader& header,
                            LoadCellCalibration& r) {
  const double fs = options.full_scale_N;
  CalibrationRecord& record = r.record;
  record.sensor_kind = "load_cell";
  record.unit = "N";
  record.input_unit = "V";
  record.coefficients = chosen.coefficients;
  record.standard_uncertainty = r.standard_uncertainty_N;
  record.method = std::string("multi-point least squares, ") +
                  (r.quadratic ? "quadratic (significant)" : "straight line") +
                  ", loading and unloading";
  record.references = options.references;
  record.valid_min = options.compression_only ? 0.0 : -fs;
  record.valid_max = fs;
  for (std::size_t i = 0; i < points.size(); ++i) {
    CalibrationPoint p = points[i];
    p.residual = chosen.residuals[i];
    record.points.push_back(p);
  }
  record.quantities = {
      {.name = "offset_N",
       .value = r.offset_N,
       .standard_uncertainty = r.offset_std_N,
       .unit = "N"},
      {.name = "gain_N_per_V",
       .value = r.gain_N_per_V,
       .standard_uncertainty = r.gain_std_N_per_V,
       .unit = "N/V"},
  };
  if (r.quadratic) {
    record.quantities.push_back({.name = "quadratic_N_per_V2",
                                 .value = r.quadratic_N_per_V2,
                                 .standard_uncertainty = r.quadratic_std_N_per_V2,
                                 .unit = "N/V^2"});
  }
  record.quantities.push_back({.name = "residual_std_N",
                               .value = r.residual_std_N,
                               .standard_uncertainty = 0.0,
                               .unit = "N"});
  record.quantities.push_back({.name = "nonlinearity_percent_fs",
                               .value = r.nonlinearity_percent_fs,
                               .standard_uncertainty = 0.0,
                               .unit = "%"});
  record.quantities.push_back({.name = "hysteresis_percent_fs",
                               .value = r.hysteresis_percent_fs,
                               .standard_uncertainty = 0.0,
                               .unit = "%"});
  record.quantities.push_back(
      {.name = "full_scale_N", .value = fs, .standard_uncertainty = 0.0, .unit = "N"});
  apply_header(record, header);
}

}  // namespace

// The stages: check the points and their spread, fit the line and (if significant) the
// quadratic, the coefficients with their uncertainties, non-linearity and hysteresis, a
// reading's uncertainty, and the record.
LoadCellCalibration calibrate_load_cell(std::span<const CalibrationPoint> points,
                                        const LoadCellCalibrationOptions& options,
                                        const RecordHeader& header) {
  if (std::string problem = options.validate(); !problem.empty()) throw CalibrationError(problem);
  const double fs = options.full_scale_N;
  check_load_cell_points(points, options);
  const auto groups = by_reference(points, fs);
  check_reference_spread(groups, points.size(), options);
  const int references = static_cast<int>(groups.size());

  std::vector<double> signal, reference;
  for (const CalibrationPoint& p : points) {
    signal.push_back(p.signal);
    reference.push_back(p.reference);
  }
  const LoadCellCurves curves =
      fit_load_cell(signal, reference, references, options.quadratic_significance);
  const PolynomialFit& chosen = curves.chosen;

  LoadCellCalibration r;
  r.points = static_cast<int>(points.size());
  r.references = references;
  r.degrees_of_freedom = chosen.degrees_of_freedom;
  r.quadratic = curves.quadratic;
  const double factor = small_sample_factor(chosen.degrees_of_freedom);
  const double rel = options.reference_relative_uncertainty;
  r.offset_N = chosen.coefficients[0];
  r.offset_std_N = chosen.coefficient_std(0) * factor;
  r.gain_N_per_V = chosen.coefficients[1];
  r.gain_std_N_per_V = std::hypot(chosen.coefficient_std(1) * factor, rel * r.gain_N_per_V);
  if (curves.quadratic) {
    r.quadratic_N_per_V2 = chosen.coefficients[2];
    r.quadratic_std_N_per_V2 = chosen.coefficient_std(2) * factor;
  }
  r.residual_std_N = chosen.residual_std;
  nonlinearity_and_hysteresis(points, groups, curves, fs, r);

  // A calibrated reading's uncertainty: the scatter of the points about the curve
  // (hysteresis, what is left of the non-linearity, the points' noise), the curve's own
  // uncertainty at its worst point, and the references'.
  double curve_std = 0.0;
  for (double v : signal) curve_std = std::max(curve_std, chosen.value_std(v) * factor);
  r.standard_uncertainty_N = std::sqrt(r.residual_std_N * r.residual_std_N * factor * factor +
                                       curve_std * curve_std + (rel * fs) * (rel * fs));
  write_load_cell_record(points, chosen, options, header, r);
  return r;
}

std::string LoadCellCalibration::brief_report() const {
  std::string text = "load cell: " + std::to_string(points) + " points at " +
                     std::to_string(references) + " references, " +
                     (quadratic ? "quadratic" : "straight line") + "\n";
  text += "  offset " + fixed(offset_N, 4) + " N ± " + fixed(offset_std_N, 4) + " N\n";
  text += "  gain   " + fixed(gain_N_per_V, 5) + " N/V ± " + fixed(gain_std_N_per_V, 5) + " N/V (" +
          fixed(100 * gain_std_N_per_V / gain_N_per_V, 4) + " %)\n";
  if (quadratic) {
    text += "  quadratic " + shortest(quadratic_N_per_V2) + " N/V² ± " +
            shortest(quadratic_std_N_per_V2) + " N/V²\n";
  }
  text += "  residual sd " + fixed(residual_std_N, 4) + " N; non-linearity " +
          fixed(nonlinearity_percent_fs, 4) + " % FS; hysteresis " +
          fixed(hysteresis_percent_fs, 4) + " % FS\n";
  text += "  standard uncertainty of a reading " + fixed(standard_uncertainty_N, 4) +
          " N (k = 1; ±2u covers about 95 %)\n";
  return text;
}

std::vector<GuidedPoint> load_cell_mass_points(std::span<const double> masses_kg,
                                               double gravity_m_s2) {
  std::vector<double> masses(masses_kg.begin(), masses_kg.end());
  masses.push_back(0.0);
  std::sort(masses.begin(), masses.end());
  masses.erase(std::unique(masses.begin(), masses.end()), masses.end());
  std::vector<GuidedPoint> result;
  auto add = [&](double kg, const std::string& branch) {
    GuidedPoint p;
    p.reference = kg * gravity_m_s2;
    p.label = shortest(kg) + " kg";
    p.branch = branch;
    p.instruction = kg == 0 ? "remove every load from the cell"
                            : (branch == "loading" ? "load the cell with " + p.label + " in all"
                                                   : "unload the cell to " + p.label + " in all");
    result.push_back(p);
  };
  for (double kg : masses) add(kg, "loading");
  for (std::size_t i = masses.size() - 1; i-- > 0;) add(masses[i], "unloading");
  return result;
}

std::vector<GuidedPoint> load_cell_force_points(std::span<const double> forces_N) {
  std::vector<double> forces(forces_N.begin(), forces_N.end());
  forces.push_back(0.0);
  std::sort(forces.begin(), forces.end());
  forces.erase(std::unique(forces.begin(), forces.end()), forces.end());
  std::vector<GuidedPoint> result;
  auto add = [&](double force, const std::string& branch) {
    GuidedPoint p;
    p.reference = force;
    p.label = shortest(force) + " N";
    p.branch = branch;
    p.instruction = force == 0 ? "remove every load from the cell"
                               : "apply " + p.label + " with the reference force (" + branch + ")";
    result.push_back(p);
  };
  for (double f : forces) add(f, "loading");
  for (std::size_t i = forces.size() - 1; i-- > 0;) add(forces[i], "unloading");
  return result;
}

CalibrationRecord tare_load_cell(const CalibrationRecord& calibrated, double unloaded_signal_V,
                                 double unloaded_std_V, int samples, const RecordHeader& header) {
  if (calibrated.sensor_kind != "load_cell") {
    throw CalibrationError("tare: record " + calibrated.id + " is for a " + calibrated.sensor_kind +
                           ", not a load cell");
  }
  if (!std::isfinite(unloaded_signal_V))
    throw CalibrationError("tare: the unloaded reading is not finite");
  CalibrationRecord tared = calibrated;
  const double reading_N = calibrated.apply(unloaded_signal_V);
  tared.coefficients[0] -= reading_N;
  const double gain = calibrated.coefficients[1];
  const double offset_std_N =
      samples > 1 ? std::abs(gain) * unloaded_std_V / std::sqrt(samples) : 0.0;
  tared.standard_uncertainty = std::hypot(calibrated.standard_uncertainty, offset_std_N);
  tared.method =
      calibrated.method + "; tared (offset from " + std::to_string(samples) + " unloaded samples)";
  tared.points.clear();  // the points belong to the calibration it was made from
  for (CalibrationQuantity& q : tared.quantities) {
    if (q.name == "offset_N") {
      q.value = tared.coefficients[0];
      q.standard_uncertainty = offset_std_N;
    }
  }
  tared.quantities.push_back({.name = "tare_reading_before_N",
                              .value = reading_N,
                              .standard_uncertainty = offset_std_N,
                              .unit = "N"});
  tared.notes =
      "Tare of " + calibrated.id + ": the unloaded cell read " + fixed(reading_N, 4) + " N before.";
  RecordHeader h = header;
  if (h.supersedes.empty()) h.supersedes = calibrated.id;
  apply_header(tared, h);
  return tared;
}

}  // namespace doorbench::calibration
