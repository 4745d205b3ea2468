#pragma once
// What `doorbench fit` and `doorbench loop` write: result.json pieces and the plots.
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "analysis/fitting.h"
#include "analysis/strokes.h"

namespace doorbench::app {

nlohmann::ordered_json error_stats_json(const ErrorStats& stats);
nlohmann::ordered_json metrics_json(const FitMetrics& metrics);
// Parameters with standard uncertainty, correlations, undetermined parameters, metrics on
// fitted and held-out strokes, the solver's figures and the excluded segments.
nlohmann::ordered_json fit_result_json(const FitResult& result, const PreparedData& data);
// rate.svg, force-angle.svg, residual-angle.svg, residual-speed.svg and, when there are enough
// samples for its lags, residual-whiteness.svg (analysis/residual_whiteness.h); returns their
// names.
std::vector<std::string> write_fit_plots(const std::filesystem::path& dir, const DoorModel& model,
                                         const PreparedData& data, const FitOptions& options);

}  // namespace doorbench::app
