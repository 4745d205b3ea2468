#pragma once
// What a residual loop leaves in its folder: result.json (the steps with their evidence,
// parameters and errors before and after, and the start and final fits), report.md (the
// table of steps, the full report and the plots), the fitted parameter and effects files.
#include <filesystem>
#include <string>

#include "analysis/loop/residual_loop.h"

namespace doorbench::app {

// The table of steps (Markdown): the effect, its parameters with uncertainty, and the
// window RMSE of ω before → after on fitted and held-out strokes.
std::string steps_table(const LoopResult& result);

// Writes the folder's files (dir must exist) and returns steps_table(result). report.md
// starts with `report_lines` (warnings, the start values' origin), the data's rate summary
// and the handle radius's origin.
std::string write_loop_outputs(const std::filesystem::path& dir, const LoopResult& result,
                               const PreparedData& data, const std::string& model_name,
                               const FitOptions& fit_options,
                               const std::vector<std::string>& report_lines = {});

}  // namespace doorbench::app
