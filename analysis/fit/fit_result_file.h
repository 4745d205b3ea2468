#pragma once
// A `doorbench fit` output folder: its result.json, written by fit_result_json from the
// FitResult and the data it was fitted to, and read back with the fitted parameter files
// beside it by read_fit_result (the viewer's fit layout, `view --fit`). The writer and the
// reader of the format are here together, beside the FitSummary they serialise.
//
// Errors: read_fit_result throws std::runtime_error naming the file and the missing or wrong
// field, and std::invalid_argument (from the parameter file reader) for a parameter file it
// refuses.
// Thread safety: pure functions of their arguments and the files read.
#include <filesystem>
#include <string>

#include "analysis/fit/fitting.h"
#include "analysis/model/door_model.h"
#include "analysis/preprocessing/strokes.h"

namespace doorbench {

// result.json's text (two-space indent, a final newline): the data's sampling and handle
// radius, the model kind, the parameters with standard uncertainty, the correlations above
// the threshold, the undetermined parameters, the metrics on fitted and held-out strokes,
// the solver's figures and the excluded segments. A number that is not finite is null.
std::string fit_result_json(const FitResult& result, const PreparedData& data);

// A fit folder read back: what result.json says of the fit and the fitted model.
struct FitResultFolder {
  std::filesystem::path dir;
  std::filesystem::path params_path;   // DIR/fitted-params.json
  std::filesystem::path effects_path;  // DIR/fitted-effects.json, or empty when absent
  ModelKind model_kind = ModelKind::kSensory;
  std::string source;  // the data the fit ran on, as result.json names it
  bool converged = false;
  std::string termination;
  int strokes = 0;
  double fitted_window_rmse_rad_s = 0.0;    // NaN when result.json gives null
  double held_out_window_rmse_rad_s = 0.0;  // NaN without cross-validation
  DoorModel model;

  // One line: kind, folder, convergence and the fit's own RMSE.
  std::string description() const;
};

// Reads DIR/result.json and DIR/fitted-params.json (and DIR/fitted-effects.json when it is
// there): "DIR: not a folder (expected a `doorbench fit` --out)", "FILE: cannot open",
// "FILE: not JSON (...)", "FILE: a `doorbench loop` result; open it with --loop", "FILE: no
// field 'NAME'", "FILE: 'model' is not sensory or physical", "PARAMS: missing", ...
FitResultFolder read_fit_result(const std::filesystem::path& dir);

}  // namespace doorbench
