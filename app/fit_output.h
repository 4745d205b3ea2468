#pragma once
// What `doorbench fit` and `doorbench loop` draw: the plots (result.json is written by
// analysis/fit/fit_result_file.h and analysis/loop/loop_result_file.h).
#include <filesystem>
#include <string>
#include <vector>

#include "analysis/fit/fitting.h"
#include "analysis/preprocessing/strokes.h"

namespace doorbench::app {

struct FitPlots {
  std::vector<std::string> files;  // the plots' file names, in `dir`
  // For the text report: ResidualWhiteness::report_line(), or "residual whiteness: not
  // computed (REASON)" when the data have too few samples for its lags.
  std::string whiteness;
};
// rate.svg, force-angle.svg, residual-angle.svg, residual-speed.svg and, when there are enough
// samples for its lags, residual-whiteness.svg (analysis/fit/residual_whiteness.h).
FitPlots write_fit_plots(const std::filesystem::path& dir, const DoorModel& model,
                         const PreparedData& data, const FitOptions& options);

}  // namespace doorbench::app
