#pragma once
// The residual loop's steps as `doorbench loop` leaves them in its folder (result.json,
// app/loop_output.cpp): each step's effect, its parameters, and the window RMSE of ω on
// fitted and held-out strokes before and after it. No GL, no ImGui.
#include <filesystem>
#include <string>
#include <vector>

#include "viewer/plot_view.h"

namespace doorbench::viewer {

struct LoopStep {
  int number = 0;
  std::string effect;
  std::string parameters;  // "name = value ± u unit, …"
  double fitted_before_rad_s = 0.0, fitted_after_rad_s = 0.0;
  double held_out_before_rad_s = 0.0, held_out_after_rad_s = 0.0;
  double held_out_improvement = 0.0;  // as result.json gives it
  double bic_change = 0.0;
};

struct LoopSteps {
  std::filesystem::path path;  // the result.json read
  std::string source;          // the data the loop ran on
  std::vector<LoopStep> steps;
};

// Reads DIR/result.json (or the file itself). Throws std::runtime_error naming the file and
// the missing field.
LoopSteps read_loop_steps(const std::filesystem::path& dir_or_file);

// Window RMSE of ω after each step (step 0: the start model), fitted and held out.
PlotView loop_steps_plot(const LoopSteps& steps);

}  // namespace doorbench::viewer
