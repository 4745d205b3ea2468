#pragma once
// What `doorbench fit` and `doorbench loop` write: result.json pieces and the plots.
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "analysis/fit/fitting.h"
#include "analysis/preprocessing/strokes.h"

namespace doorbench::app {

nlohmann::ordered_json error_stats_json(const ErrorStats& stats);
nlohmann::ordered_json metrics_json(const FitMetrics& metrics);
// Parameters with standard uncertainty, correlations, undetermined parameters, metrics on
// fitted and held-out strokes, the solver's figures and the excluded segments.
nlohmann::ordered_json fit_result_json(const FitResult& result, const PreparedData& data);
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
