#pragma once
// What `doorbench fit` and `doorbench loop` draw: the plots (result.json is written by
// analysis/fit/fit_result_file.h and analysis/loop/loop_result_file.h).
#include <filesystem>
#include <string>
#include <vector>

#include "analysis/fit/fitting.h"
#include "analysis/preprocessing/strokes.h"
#include "analysis/report/svg_charts.h"

namespace doorbench::app {

struct FitPlots {
  std::vector<std::string> files;  // the plots' file names, in `dir`
  // For the text report: ResidualWhiteness::report_line(), or "residual whiteness: not
  // computed (REASON)" when the data have too few samples for its lags.
  std::string whiteness;
};
// rate.svg, force-angle.svg, residual-angle.svg, residual-speed.svg and, when there are enough
// samples for its lags, residual-whiteness.svg (analysis/fit/residual_whiteness.h); when
// there are not, an earlier run's residual-whiteness.svg in `dir` is removed (output rule 5).
FitPlots write_fit_plots(const std::filesystem::path& dir, const DoorModel& model,
                         const PreparedData& data, const FitOptions& options);

// The rows of global-search.svg, one per free parameter of `summary` (FitSummary::free_names),
// each labelled with its name ("k_lock (log)" where the global stage's scale of its bounds is
// logarithmic, analysis/fit/search_scale.h) and placed on that scale (0: lower bound, 1: upper
// bound): the estimate the fit's value, the interval the range of every distinct optimum's
// value, the inner interval the range of the optima within 1 % of the fit's cost (none when
// only the fit is). Empty when the global stage did not run or found one distinct optimum.
std::vector<ForestRow> global_search_rows(const FitSummary& summary);

// global-search.svg in `dir`, drawn from global_search_rows, when there are rows: how unique
// the optimum is, each parameter's spread over the distinct optima at a glance. Its file name,
// or empty when nothing was drawn (and an earlier run's global-search.svg in `dir` is removed,
// output rule 5). Throws OutputError when it cannot write or remove.
std::string write_global_search_plot(const std::filesystem::path& dir, const FitSummary& summary);

// Output rule 5 between `fit`'s two kinds of run, so that `dir` holds one run's outputs: a
// whole fit writes result.json, report.md, fitted-params.json, fitted-effects.json and the
// plots above; `--init-only` writes start-params.json and start.md. Each kind removes the
// other kind's files that an earlier run left in `dir` (under --overwrite); other files stay.
// Throws OutputError "PATH: cannot remove: SYSTEM ERROR".
void remove_whole_fit_outputs(const std::filesystem::path& dir);
void remove_start_outputs(const std::filesystem::path& dir);

}  // namespace doorbench::app
