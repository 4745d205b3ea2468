#pragma once
// Load-cell calibration against reference masses or a reference force: the points are
// taken loading (references rising) and unloading (falling); a least-squares line
// F = offset + gain · V, with a quadratic term only where it is significant; residuals,
// non-linearity and hysteresis in % of full scale, and the fit's standard uncertainty.
// Also the tare before a session: a new record whose offset makes the unloaded cell read 0.
#include <span>
#include <string>
#include <vector>

#include "acquisition/rig/calibration_record.h"
#include "calibration/guided_procedure.h"
#include "calibration/procedure.h"

namespace doorbench::calibration {

inline constexpr double kStandardGravity_m_s2 = 9.80665;

struct LoadCellCalibrationOptions {
  double full_scale_N = 445.0;   // references must not exceed it
  bool compression_only = true;  // references must then be >= 0
  int min_references = 5;        // distinct reference values at least
  // The references must span at least this fraction of full scale.
  double min_span_fraction_fs = 0.2;
  // The quadratic term is kept when |c₂| > this × its standard uncertainty (a t-test).
  double quadratic_significance = 3.0;
  // Relative standard uncertainty of the references (OIML class M1 masses: about 5e-5);
  // added to the gain's and the reading's uncertainty.
  double reference_relative_uncertainty = 0.0;
  std::string references = "reference masses";  // described in the record

  std::string validate() const;  // "" when usable, else one line naming the option
};

// The Summary of a load-cell calibration.
struct LoadCellCalibration {
  CalibrationRecord record;  // coefficients N per V: offset, gain (, quadratic)
  double offset_N = 0.0, offset_std_N = 0.0;
  double gain_N_per_V = 0.0, gain_std_N_per_V = 0.0;
  bool quadratic = false;
  double quadratic_N_per_V2 = 0.0, quadratic_std_N_per_V2 = 0.0;
  double residual_std_N = 0.0;           // of the points about the chosen curve
  double nonlinearity_percent_fs = 0.0;  // largest deviation of the branch-averaged points
                                         // from the best straight line, % of full scale
  double hysteresis_percent_fs = 0.0;    // largest unloading − loading difference, % FS
  double standard_uncertainty_N = 0.0;   // of a calibrated reading (excluding its noise)
  int points = 0, references = 0, degrees_of_freedom = 0;

  std::string brief_report() const;
};

// The standard uncertainties are scaled by t₉₅(ν)/1.96 (ν = points − coefficients) so that
// ±2u covers about 95 % also with few points. Throws CalibrationError for too few points or
// references, references out of range, or readings that do not rise with the load.
LoadCellCalibration calibrate_load_cell(std::span<const CalibrationPoint> points,
                                        const LoadCellCalibrationOptions& options,
                                        const RecordHeader& header);

// Guided points for masses (kg) hung or placed on the cell: 0 first, then each mass
// loading in rising order, then unloading in falling order back to 0 (the largest once).
std::vector<GuidedPoint> load_cell_mass_points(std::span<const double> masses_kg,
                                               double gravity_m_s2 = kStandardGravity_m_s2);
// The same for a reference force (N) applied by a force standard.
std::vector<GuidedPoint> load_cell_force_points(std::span<const double> forces_N);

// The tare: the same calibration with the offset changed so that the unloaded signal
// (mean over a still, unloaded window) reads 0 N. A new version superseding `calibrated`.
CalibrationRecord tare_load_cell(const CalibrationRecord& calibrated, double unloaded_signal_V,
                                 double unloaded_std_V, int samples, const RecordHeader& header);

}  // namespace doorbench::calibration
