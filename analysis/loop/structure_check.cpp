// The residual loop's structure check (internal/loop_steps.h; docs/residual-loop.md, "The
// structure check" and "Family before stacking"): when it is due, the other model family
// fitted to the same data and compared with the loop's current model.
#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>

#include "analysis/loop/internal/examination.h"
#include "analysis/loop/internal/loop_common.h"
#include "analysis/loop/internal/loop_steps.h"
#include "analysis/model/parameter_file.h"
#include "core/number_format.h"

namespace doorbench::loop_detail {

FitOptions structure_fit_options(const LoopOptions& options, ModelKind other) {
  FitOptions fit = options.fit;
  fit.fixed_parameters.clear();
  fit.free_parameters = options.structure_free_parameters;
  if (fit.free_parameters.empty() && other == ModelKind::kPhysical) {
    fit.free_parameters = {"J_d", "k_s", "F0", "T_h", "mu_g"};
  }
  return fit;
}

bool structure_check_due(const LoopOptions& options, const ModelFigures& figures,
                         const ResidualExamination& last, StructureCheck& check) {
  // What the best candidate explains: its linear share or its second look's, and the best
  // refit's fall of the held-out RMSE.
  double best_refit = 0.0;
  for (const CandidateEvidence& candidate : last.candidates) {
    check.best_explained_fraction =
        std::max(check.best_explained_fraction, candidate.explained_fraction);
    if (candidate.screened) {
      check.best_explained_fraction =
          std::max(check.best_explained_fraction, candidate.screen_explained_fraction);
    }
    if (candidate.after && std::isfinite(candidate.held_out_improvement)) {
      best_refit = std::max(best_refit, candidate.held_out_improvement);
    }
  }
  check.noise_floor_rad_s = last.noise_floor_rad_s;
  const double ratio = last.noise_floor_rad_s > 0
                           ? figures.held_out_rmse_rad_s / last.noise_floor_rad_s
                           : std::numeric_limits<double>::infinity();
  const double enough = options.structure_max_explained_fraction;
  if (!options.structure_check) {
    check.reason = "off (structure_check)";
  } else if (check.best_explained_fraction >= enough) {
    check.reason = "not run: the best candidate explains " +
                   format_percent(check.best_explained_fraction, 1) +
                   " of the residual (at least " + format_percent(enough, 1) + ")";
  } else if (best_refit >= enough) {
    check.reason = "not run: the best refit lowers the held-out RMSE by " +
                   format_percent(best_refit, 1) + " (at least " + format_percent(enough, 1) + ")";
  } else if (ratio <= options.structure_noise_ratio) {
    check.reason = "not run: the held-out RMSE " + number(figures.held_out_rmse_rad_s) +
                   " rad/s is " + printf_text("%.2g", ratio) + " times the noise floor " +
                   number(last.noise_floor_rad_s) + " rad/s (needs more than " +
                   printf_text("%.3g", options.structure_noise_ratio) + ")";
  } else {
    check.reason = "no effect closes the gap: the best candidate explains " +
                   format_percent(check.best_explained_fraction, 1) +
                   " of the residual, the best refit " + "lowers the held-out RMSE by " +
                   format_percent(best_refit, 1) + ", and the held-out RMSE " +
                   number(figures.held_out_rmse_rad_s) + " rad/s is " + printf_text("%.3g", ratio) +
                   " times the noise floor " + number(last.noise_floor_rad_s) + " rad/s";
    return true;
  }
  return false;
}

StructureCheck check_structure(StructureCheck check, const FitResult& current,
                               const PreparedData& data, const LoopOptions& options, int& fits,
                               const Say& say, ResidualExamination& other_examination) {
  check.current_kind = current.model.kind();
  check.other_kind =
      check.current_kind == ModelKind::kSensory ? ModelKind::kPhysical : ModelKind::kSensory;
  check.current = model_figures(current.summary);
  check.ran = true;
  const std::string other_name(to_string(check.other_kind));
  say("structure check: " + check.reason + "; fitting the " + other_name + " model");
  FitOptions fit = structure_fit_options(options, check.other_kind);
  // The physical fit from the reference door takes monotonic steps: with non-monotonic ones
  // its passes wandered above their best to max_iterations on sensory doors, for no better
  // decision (docs/residual-loop.md, "4. The structure check").
  if (check.other_kind == ModelKind::kPhysical) fit.nonmonotonic_steps = false;
  try {
    ++fits;
    check.other_fit = fit_model(reference_model(check.other_kind), data, fit);
  } catch (const std::exception& error) {
    check.verdict = "the " + other_name + " model's fit failed: " + error.what();
    say("structure check: " + check.verdict);
    return check;
  }
  const FitSummary& other = check.other_fit->summary;
  check.other = model_figures(other);
  for (const FittedParameter& parameter : other.parameters) {
    if (parameter.free) check.other_free.push_back(parameter.name);
  }
  check.other_undetermined = other.undetermined;
  check.held_out_improvement =
      (check.current.held_out_rmse_rad_s - check.other.held_out_rmse_rad_s) /
      check.current.held_out_rmse_rad_s;
  check.bic_change = check.other.bic - check.current.bic;
  check.other_better = check.held_out_improvement > options.min_held_out_improvement &&
                       check.bic_change < -options.min_bic_decrease;
  fit.progress = nullptr;
  other_examination = examine(check.other_fit->model, data, options, fit);
  for (const CandidateEvidence& candidate : other_examination.candidates) {
    if (candidate.explained_fraction >= options.min_explained_fraction &&
        candidate.score_z >= options.min_score_z) {
      check.remaining.push_back(candidate);
    }
  }
  const std::string current_name(to_string(check.current_kind));
  check.verdict = std::string(check.other_better ? "the " + other_name : "the " + current_name) +
                  " model is the better structure: held-out RMSE " +
                  number(check.current.held_out_rmse_rad_s) + " rad/s (" + current_name +
                  ") against " + number(check.other.held_out_rmse_rad_s) + " (" + other_name +
                  ", " + format_signed_percent(-check.held_out_improvement, 1) + "), BIC " +
                  printf_text("%+.4g", check.bic_change);
  say("structure check: " + check.verdict);
  return check;
}

}  // namespace doorbench::loop_detail
