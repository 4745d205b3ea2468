#pragma once
// A `doorbench fit` output folder (app/fit_command.cpp) as "a fit result" for the viewer:
// its result.json (the model kind, the data it was fitted to, convergence and the window
// RMSE) and the fitted parameter file (with fitted-effects.json when the fit had effects),
// loaded as the model the fit and tuning layouts show. No GL, no ImGui.
#include <filesystem>
#include <string>

#include "analysis/model/door_model.h"

namespace doorbench::viewer {

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

  // One line for the fit layout: kind, folder, convergence and the fit's own RMSE.
  std::string description() const;
};

// Reads DIR/result.json and DIR/fitted-params.json (and DIR/fitted-effects.json when it is
// there). Throws std::runtime_error naming the file and the missing or wrong field, and
// std::invalid_argument (from the parameter file reader) for a parameter file it refuses.
FitResultFolder read_fit_result(const std::filesystem::path& dir);

}  // namespace doorbench::viewer
