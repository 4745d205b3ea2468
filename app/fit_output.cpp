// What `doorbench fit` and `doorbench loop` write: result.json pieces and the plots.
#include "app/fit_output.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "acquisition/session/output_file.h"
#include "analysis/fit/fit_metrics.h"
#include "analysis/fit/residual_whiteness.h"
#include "analysis/fit/search_scale.h"
#include "analysis/report/svg_plot.h"
#include "core/json_number.h"
#include "core/numbers.h"
#include "core/units.h"

namespace doorbench::app {
namespace {

// Optima whose cost is within this share of the fit's: the global-search plot's inner range,
// basins the data hardly tell apart from the fit's (the truth-start bar's 1 %, docs/fitting.md).
constexpr double kNearOptimumCost = 0.01;

// The plots write_fit_plots draws, in order (the last when the data allow its lags), and
// write_global_search_plot's.
constexpr std::array<const char*, 5> kFitPlotFiles = {"rate.svg", "force-angle.svg",
                                                      "residual-angle.svg", "residual-speed.svg",
                                                      "residual-whiteness.svg"};
constexpr const char* kGlobalSearchFile = "global-search.svg";

}  // namespace

// Measured against simulated (window by window) rate and angle, the force–angle loops, and
// the rate residual against angle and speed, and the residual's whiteness (when the data
// have enough samples).
FitPlots write_fit_plots(const std::filesystem::path& dir, const DoorModel& model,
                         const PreparedData& data, const FitOptions& options) {
  WindowOptions window_options;
  window_options.window_s = options.window_s;
  window_options.substeps_per_sample = options.substeps_per_sample;
  const WindowSimulation simulated = simulate_windows(model, data, window_options);
  std::vector<std::vector<double>> time_s, measured_deg_s, simulated_deg_s, angle_deg,
      residual_deg_s, speed_deg_s, force_N;
  for (std::size_t s = 0; s < data.strokes.size(); ++s) {
    const Stroke& stroke = data.strokes[s];
    time_s.push_back(stroke.time_s);
    std::vector<double> m, sim, a, r, v;
    for (std::size_t i = 0; i < stroke.size(); ++i) {
      m.push_back(stroke.omega_rad_s[i] * kDegPerRad);
      sim.push_back(simulated.omega_rad_s[s][i] * kDegPerRad);
      a.push_back(stroke.theta_rad[i] * kDegPerRad);
      r.push_back((stroke.omega_rad_s[i] - simulated.omega_rad_s[s][i]) * kDegPerRad);
      v.push_back(stroke.omega_rad_s[i] * kDegPerRad);
    }
    measured_deg_s.push_back(std::move(m));
    simulated_deg_s.push_back(std::move(sim));
    angle_deg.push_back(std::move(a));
    residual_deg_s.push_back(std::move(r));
    speed_deg_s.push_back(std::move(v));
    force_N.push_back(stroke.force_N);
  }
  std::vector<PlotSeries> rate, loops, residual_angle, residual_speed;
  using plot_style::Meaning;
  bool opening_named = false, closing_named = false;
  for (std::size_t s = 0; s < data.strokes.size(); ++s) {
    const bool opening = data.strokes[s].direction == StrokeDirection::kOpening;
    const Meaning direction = opening ? Meaning::kOpening : Meaning::kClosing;
    // One legend entry per direction: the first stroke of each names it.
    bool& named = opening ? opening_named : closing_named;
    const std::string label = named ? "" : (opening ? "opening" : "closing");
    named = true;
    rate.push_back({.label = s == 0 ? "measured" : "",
                    .x = time_s[s],
                    .y = measured_deg_s[s],
                    .color = "",
                    .meaning = Meaning::kMeasured});
    rate.push_back({.label = s == 0 ? "simulated (windows)" : "",
                    .x = time_s[s],
                    .y = simulated_deg_s[s],
                    .color = "",
                    .meaning = Meaning::kSimulated});
    loops.push_back(
        {.label = label, .x = angle_deg[s], .y = force_N[s], .color = "", .meaning = direction});
    residual_angle.push_back({.label = label,
                              .x = angle_deg[s],
                              .y = residual_deg_s[s],
                              .color = "",
                              .meaning = direction});
    residual_speed.push_back({.label = label,
                              .x = speed_deg_s[s],
                              .y = residual_deg_s[s],
                              .color = "",
                              .meaning = direction});
  }
  FitPlots plots;
  std::vector<std::string>& files = plots.files;
  files = {kFitPlotFiles[0], kFitPlotFiles[1], kFitPlotFiles[2], kFitPlotFiles[3]};
  write_svg_plot((dir / files[0]).string(),
                 {"Door rate: measured and simulated window by window", "time [s]", "rate [deg/s]"},
                 rate);
  write_svg_plot((dir / files[1]).string(),
                 {"Force-angle loops (measured)", "angle [deg]", "hand force [N]"}, loops);
  write_svg_plot((dir / files[2]).string(),
                 {"Rate residual against angle", "angle [deg]", "measured - simulated [deg/s]"},
                 residual_angle);
  write_svg_plot((dir / files[3]).string(),
                 {"Rate residual against speed", "rate [deg/s]", "measured - simulated [deg/s]"},
                 residual_speed);
  // Is the residual noise? Its autocorrelation and cross-correlation with the force.
  try {
    const ResidualWhiteness w = residual_whiteness(residual_deg_s, force_N, data.interval_median_s,
                                                   whiteness_max_lag(data.interval_median_s));
    const int max_lag = int(w.autocorrelation.size()) - 1;
    std::vector<double> auto_lag_s, cross_lag_s;
    for (int k = 0; k <= max_lag; ++k) auto_lag_s.push_back(k * w.lag_step_s);
    for (int k = -max_lag; k <= max_lag; ++k) cross_lag_s.push_back(k * w.lag_step_s);
    const std::vector<double> band_x = {cross_lag_s.front(), cross_lag_s.back()};
    const std::vector<double> upper = {w.band, w.band}, lower = {-w.band, -w.band};
    const std::vector<PlotSeries> whiteness = {
        {.label = "autocorrelation of the residual",
         .x = auto_lag_s,
         .y = w.autocorrelation,
         .color = "",
         .meaning = plot_style::Meaning::kResidual},
        {.label = "cross-correlation with the force",
         .x = cross_lag_s,
         .y = w.cross_correlation,
         .color = "#b8860b"},
        {.label = "99 % band of white noise",
         .x = band_x,
         .y = upper,
         .color = "",
         .meaning = plot_style::Meaning::kOther},
        {.label = "", .x = band_x, .y = lower, .color = "", .meaning = plot_style::Meaning::kOther},
    };
    files.push_back(kFitPlotFiles[4]);
    write_svg_plot((dir / files.back()).string(),
                   {"Residual whiteness: " + w.summary(), "lag [s]", "correlation"}, whiteness);
    plots.whiteness = w.report_line();
  } catch (const std::invalid_argument& error) {
    // Too few samples for the lags: no whiteness plot. The reason without its own prefix.
    std::string reason = error.what();
    const std::string prefix = "residual whiteness: ";
    if (reason.starts_with(prefix)) reason.erase(0, prefix.size());
    plots.whiteness = prefix + "not computed (" + reason + ")";
    remove_output_not_written(dir / kFitPlotFiles[4]);
  }
  return plots;
}

std::vector<ForestRow> global_search_rows(const FitSummary& summary) {
  const GlobalSearch& global = summary.global;
  std::vector<ForestRow> rows;
  if (!global.ran || global.optima.size() < 2) return rows;
  const double fit_cost = global.optima.front().cost;
  const auto near = [&](const GlobalOptimum& optimum) {
    return optimum.cost <= (1.0 + kNearOptimumCost) * fit_cost;
  };
  const auto near_count = std::count_if(global.optima.begin(), global.optima.end(), near);
  for (std::size_t k = 0; k < summary.free_names.size(); ++k) {
    const auto parameter =
        std::find_if(summary.parameters.begin(), summary.parameters.end(),
                     [&](const FittedParameter& p) { return p.name == summary.free_names[k]; });
    if (parameter == summary.parameters.end()) continue;
    const Bounds& bounds = parameter->bounds;
    const auto place = [&](const GlobalOptimum& optimum) {
      return search_scale_place(bounds, optimum.free_values.at(k));
    };
    ForestRow row;
    row.label = summary.free_names[k] + (search_scale_is_logarithmic(bounds) ? " (log)" : "");
    row.estimate = row.low = row.high = place(global.optima.front());
    double inner_low = row.estimate, inner_high = row.estimate;
    for (const GlobalOptimum& optimum : global.optima) {
      const double u = place(optimum);
      row.low = std::min(row.low, u);
      row.high = std::max(row.high, u);
      if (near(optimum)) {
        inner_low = std::min(inner_low, u);
        inner_high = std::max(inner_high, u);
      }
    }
    if (near_count >= 2) {
      row.inner_low = inner_low;
      row.inner_high = inner_high;
    }
    rows.push_back(std::move(row));
  }
  return rows;
}

std::string write_global_search_plot(const std::filesystem::path& dir, const FitSummary& summary) {
  const std::string file = kGlobalSearchFile;
  const std::vector<ForestRow> rows = global_search_rows(summary);
  if (rows.empty()) {
    remove_output_not_written(dir / file);
    return "";
  }
  const std::size_t optima = summary.global.optima.size();
  ForestOptions options;
  options.title = "Global search: the fit and " + std::to_string(optima - 1) +
                  " other distinct optima, each free parameter within its bounds";
  options.x_label = "place within the bounds (0 lower, 1 upper; (log): on a log scale) [-]";
  options.interval_label = "range of the " + std::to_string(optima) + " distinct optima";
  options.inner_label = "range of those within 1 % of the fit's cost";
  options.estimate_label = "the fit";
  options.reference_line = kNaN;
  options.band_low = 0.0;
  options.band_high = 1.0;
  options.band_label = "the bounds";
  write_text_file_atomically(dir / file, render_svg_forest(options, rows));
  return file;
}

void remove_whole_fit_outputs(const std::filesystem::path& dir) {
  for (const char* file :
       {"result.json", "report.md", "fitted-params.json", "fitted-effects.json"}) {
    remove_output_not_written(dir / file);
  }
  for (const char* file : kFitPlotFiles) remove_output_not_written(dir / file);
  remove_output_not_written(dir / kGlobalSearchFile);
}

void remove_start_outputs(const std::filesystem::path& dir) {
  remove_output_not_written(dir / "start-params.json");
  remove_output_not_written(dir / "start.md");
}

}  // namespace doorbench::app
