// The residual loop (run_residual_loop; docs/residual-loop.md): its options' validation,
// the figures of a fit, the refits of a step's candidates, the verdicts and the choice, the
// structure check, and the loop itself. The examination is residual_examination.cpp, the
// reports loop_report.cpp.
#include "analysis/loop/residual_loop.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <mutex>
#include <stdexcept>

#include "analysis/fit/fit_metrics.h"
#include "analysis/loop/internal/examination.h"
#include "analysis/loop/internal/loop_common.h"
#include "analysis/model/parameter_file.h"
#include "core/clock.h"
#include "core/number_format.h"
#include "core/parallel.h"
#include "core/numbers.h"

namespace doorbench {

using namespace loop_detail;

namespace {


bool finite_in(double value, double lower, double upper) {
  return std::isfinite(value) && value >= lower && value <= upper;
}

// Why a grid is unusable for an effect parameter (empty when usable).
std::string check_grid(const std::vector<double>& grid, const char* option, effects::Kind kind,
                       int parameter) {
  const effects::EffectParameter& info = effects::info(kind).parameters[parameter];
  if (grid.empty()) return std::string("loop ") + option + " must not be empty";
  for (double value : grid) {
    if (!finite_in(value, info.default_bounds.lower, info.default_bounds.upper) ||
        (info.minimum_is_strict && value <= info.minimum)) {
      return std::string("loop ") + option + " must lie within " + std::string(info.info.name) +
             "'s bounds [" + number(info.default_bounds.lower) + ", " +
             number(info.default_bounds.upper) + "] (got " + number(value) + ")";
    }
  }
  return "";
}

}  // namespace

std::string LoopOptions::validate() const {
  if (const std::string message = fit.validate(); !message.empty()) {
    return "loop fit options: " + message;
  }
  if (fit.cross_validation_folds < 2) {
    return "loop fit.cross_validation_folds must be >= 2: the loop compares held-out errors";
  }
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    const int index = static_cast<int>(candidates[i]);
    if (index < 0 || index >= effects::kKindCount) return "loop candidates holds an unknown effect";
    for (std::size_t j = 0; j < i; ++j) {
      if (candidates[j] == candidates[i]) {
        return "loop candidates names " + std::string(effects::info(candidates[i]).name) + " twice";
      }
    }
  }
  if (max_steps < 1) return "loop max_steps must be >= 1";
  if (refit_candidates < 1) return "loop refit_candidates must be >= 1";
  if (!finite_in(min_explained_fraction, 0.0, 1.0) || min_explained_fraction >= 1.0) {
    return "loop min_explained_fraction must lie in [0, 1)";
  }
  if (!std::isfinite(min_score_z) || min_score_z < 0) return "loop min_score_z must be >= 0";
  if (!finite_in(min_held_out_improvement, 0.0, 1.0) || min_held_out_improvement >= 1.0) {
    return "loop min_held_out_improvement must lie in [0, 1)";
  }
  if (!std::isfinite(min_bic_decrease) || min_bic_decrease < 0) {
    return "loop min_bic_decrease must be >= 0";
  }
  if (std::string message =
          check_grid(stribeck_speeds_rad_s, "stribeck_speeds_rad_s", effects::Kind::kStribeck, 1);
      !message.empty()) {
    return message;
  }
  if (std::string message =
          check_grid(soft_close_angles_rad, "soft_close_angles_rad", effects::Kind::kSoftClose, 1);
      !message.empty()) {
    return message;
  }
  if (std::string message = check_grid(soft_close_sharpness_per_rad, "soft_close_sharpness_per_rad",
                                       effects::Kind::kSoftClose, 2);
      !message.empty()) {
    return message;
  }
  if (end_stop_angles < 1) return "loop end_stop_angles must be >= 1";
  if (screen_steps < 0) return "loop screen_steps must be >= 0 (0: no second look)";
  for (const std::string& name : fixed_effect_parameters) {
    bool known = false;
    for (const effects::EffectInfo& effect : effects::catalogue()) {
      for (const effects::EffectParameter& parameter : effect.parameters) {
        known = known || name == std::string(effect.name) + "." + std::string(parameter.info.name);
      }
    }
    if (!known) {
      return "loop fixed_effect_parameters names '" + name +
             "', which no effect has (write <effect>.<parameter>, e.g. end_stop.beta_e)";
    }
  }
  if (!finite_in(structure_max_explained_fraction, 0.0, 1.0)) {
    return "loop structure_max_explained_fraction must lie in [0, 1]";
  }
  if (!std::isfinite(structure_noise_ratio) || structure_noise_ratio < 1) {
    return "loop structure_noise_ratio must be >= 1";
  }
  if (refit_start != RefitStart::kBest && refit_start != RefitStart::kCurrentFit &&
      refit_start != RefitStart::kStartModel) {
    return "loop refit_start is not a RefitStart";
  }
  return "";
}

ModelFigures model_figures(const FitSummary& summary) {
  ModelFigures figures;
  figures.fitted_rmse_rad_s = summary.fitted.window.rmse();
  figures.fitted_fit_percent = summary.fitted.window.fit_percent();
  figures.held_out_rmse_rad_s = summary.held_out ? summary.held_out->window.rmse() : kNaN;
  figures.held_out_fit_percent = summary.held_out ? summary.held_out->window.fit_percent() : kNaN;
  figures.residuals = summary.residuals;
  figures.free_parameters = summary.free_parameters;
  figures.parameters = summary.free_parameters + summary.window_state_parameters;
  const double n = static_cast<double>(summary.residuals);
  const double degrees_of_freedom = n - figures.parameters;
  figures.sum_of_squares = std::isfinite(summary.residual_variance) && degrees_of_freedom > 0
                               ? summary.residual_variance * degrees_of_freedom
                               : 2.0 * summary.final_cost;
  figures.bic = n > 0 && figures.sum_of_squares > 0
                    ? n * std::log(figures.sum_of_squares / n) + figures.parameters * std::log(n)
                    : kNaN;
  return figures;
}

namespace {

std::vector<std::string> effect_parameter_names(effects::Kind kind) {
  const effects::EffectInfo& info = effects::info(kind);
  std::vector<std::string> names;
  for (const effects::EffectParameter& parameter : info.parameters) {
    names.push_back(std::string(info.name) + "." + std::string(parameter.info.name));
  }
  return names;
}

// The fit options of a refit with `kind` added to a model fitted with `current`.
FitOptions refit_options(const FitOptions& current, const LoopOptions& options,
                         effects::Kind kind) {
  FitOptions fit = current;
  fit.latch_start_from_data = false;  // the start is already a fit
  for (const std::string& name : effect_parameter_names(kind)) {
    const bool fixed =
        std::find(options.fixed_effect_parameters.begin(), options.fixed_effect_parameters.end(),
                  name) != options.fixed_effect_parameters.end();
    if (fixed) {
      fit.fixed_parameters.push_back(name);
    } else if (!fit.free_parameters.empty()) {
      fit.free_parameters.push_back(name);
    }
  }
  return fit;
}

// Refits `current` with the candidate effect added (LoopOptions::RefitStart). `fits` counts
// the calls of fit_model; `origin` says which start won.
FitResult refit(const DoorModel& start, const FitResult& current, const FitOptions& current_options,
                const PreparedData& data, const LoopOptions& options,
                const CandidateEvidence& candidate, int& fits, std::string& origin) {
  const effects::EffectInfo& info = effects::info(candidate.kind);
  EffectSetting setting{candidate.kind, candidate.start_values, {}};
  for (const effects::EffectParameter& parameter : info.parameters) {
    setting.bounds.push_back(parameter.default_bounds);
  }
  const FitOptions from_fit = refit_options(current_options, options, candidate.kind);
  FitOptions from_start = from_fit;
  from_start.latch_start_from_data = options.fit.latch_start_from_data;
  auto fresh_start = [&] {
    std::vector<double> values(current.model.parameter_values().begin(),
                               current.model.parameter_values().end());
    for (int i = 0; i < current.model.base_parameter_count(); ++i) {
      values[i] = start.parameter_values()[i];
    }
    return current.model.with_parameter_values(std::move(values)).with_effect(setting);
  };
  switch (options.refit_start) {
    case LoopOptions::RefitStart::kCurrentFit:
      origin = "the current fit";
      ++fits;
      return fit_model(current.model.with_effect(setting), data, from_fit);
    case LoopOptions::RefitStart::kStartModel:
      origin = "the start model";
      ++fits;
      return fit_model(fresh_start(), data, from_start);
    case LoopOptions::RefitStart::kBest:
      break;
  }
  // Both starts without cross-validation (at once when options.parallel_refits: each fit
  // is the same on any thread); the better one again, with it, from its result.
  struct Attempt {
    std::optional<FitResult> result;
    std::string error;
  };
  Attempt attempts[2];
  const char* names[2] = {"the current fit", "the start model"};
  auto attempt = [&](std::size_t which) {
    FitOptions fit = which == 0 ? from_fit : from_start;
    fit.cross_validation_folds = 0;
    // A start is the loop's search, not its measurement: its coarse pass goes on to the fine
    // pass's own precision instead of stopping at once where σ is inflated (a model lacking
    // an effect), so the iterations run at the coarse problem's half cost.
    fit.coarse_tolerance_factor = 1.0;
    try {
      const DoorModel model = which == 0 ? current.model.with_effect(setting) : fresh_start();
      attempts[which].result = fit_model(model, data, fit);
    } catch (const std::exception& error) {
      attempts[which].error = error.what();
    }
  };
  parallel_for(2, refit_threads(options.parallel_refits, 2), attempt);
  std::optional<FitResult> best;
  std::string failures;
  for (std::size_t which = 0; which < 2; ++which) {
    ++fits;
    Attempt& tried = attempts[which];
    if (!tried.result) {
      failures += std::string(failures.empty() ? "" : "; ") + "from " + names[which] + ": " +
                  tried.error;
      continue;
    }
    if (!best || model_figures(tried.result->summary).sum_of_squares <
                     model_figures(best->summary).sum_of_squares) {
      best = std::move(tried.result);
      origin = names[which];
    }
  }
  if (!best) throw std::runtime_error(failures);
  // It starts at the better start's optimum of the fine problem: no equation-error stage and
  // no coarse pass (which would leave that optimum for the coarse one's and come back).
  FitOptions final_fit = from_fit;
  final_fit.equation_error_start = false;
  final_fit.coarse_first = false;
  ++fits;
  return fit_model(best->model, data, final_fit);
}

}  // namespace

namespace {

using Say = std::function<void(const std::string&)>;

std::string ranking_line(int step_number, const ResidualExamination& examination) {
  std::string ranking = "step " + std::to_string(step_number) + ": the residual ranks ";
  for (std::size_t k = 0; k < examination.candidates.size() && k < 4; ++k) {
    if (k > 0) ranking += ", ";
    ranking += examination.candidates[k].name + " (" +
               percent(examination.candidates[k].explained_fraction) +
               printf_text(", z %.3g)", examination.candidates[k].score_z);
  }
  return ranking;
}

// Who is refitted: the candidates whose linear share and z pass, in rank order, then those
// the second look promotes, while refit slots are left. Gives the others their verdicts.
std::vector<std::size_t> select_refits(ResidualExamination& examination, const LoopOptions& options,
                                       int step_number, const Say& say) {
  std::vector<std::size_t> order, promoted;
  for (std::size_t k = 0; k < examination.candidates.size(); ++k) {
    CandidateEvidence& candidate = examination.candidates[k];
    const bool share_ok = candidate.explained_fraction >= options.min_explained_fraction;
    if (share_ok && candidate.score_z >= options.min_score_z) {
      order.push_back(k);
    } else if (candidate.screened &&
               candidate.screen_explained_fraction >= options.min_explained_fraction &&
               candidate.screen_score_z >= options.min_score_z) {
      promoted.push_back(k);
    } else if (!share_ok) {
      candidate.verdict = "not refitted: explains " + percent(candidate.explained_fraction) +
                          " of the residual (needs " + percent(options.min_explained_fraction) +
                          ")";
      if (candidate.screened) {
        candidate.verdict +=
            printf_text(", second look %.1f%%, z %.2g", 100.0 * candidate.screen_explained_fraction,
                        candidate.screen_score_z);
      }
    } else {
      candidate.verdict = "not refitted: score z = " + printf_text("%.2g", candidate.score_z) +
                          " (needs " + printf_text("%.2g", options.min_score_z) + ")";
      if (candidate.screened) {
        candidate.verdict +=
            printf_text(", second look %.1f%%, z %.2g", 100.0 * candidate.screen_explained_fraction,
                        candidate.screen_score_z);
      }
    }
  }
  for (std::size_t k : promoted) {
    CandidateEvidence& candidate = examination.candidates[k];
    candidate.promoted = true;
    candidate.start_values = candidate.screen_values;
    candidate.scan +=
        std::string(candidate.scan.empty() ? "" : "; ") +
        printf_text("second look: %.1f%%, z %.3g", 100.0 * candidate.screen_explained_fraction,
                    candidate.screen_score_z);
  }
  order.insert(order.end(), promoted.begin(), promoted.end());
  std::vector<std::size_t> to_refit;
  for (std::size_t k : order) {
    CandidateEvidence& candidate = examination.candidates[k];
    if (static_cast<int>(to_refit.size()) >= options.refit_candidates) {
      candidate.verdict = "not refitted: ranked below the " +
                          std::to_string(options.refit_candidates) + " refitted";
      continue;
    }
    to_refit.push_back(k);
    candidate.refitted = true;
    say("step " + std::to_string(step_number) + ": refitting with " + candidate.name +
        (candidate.scan.empty() ? "" : " (" + candidate.scan + ")"));
  }
  return to_refit;
}

// A refitted candidate's figures and verdict against `before`.
void judge(CandidateEvidence& candidate, const ModelFigures& before, const ModelFigures& after,
           const LoopOptions& options) {
  candidate.after = after;
  candidate.held_out_improvement =
      (before.held_out_rmse_rad_s - after.held_out_rmse_rad_s) / before.held_out_rmse_rad_s;
  candidate.bic_change = after.bic - before.bic;
  const bool held_out_ok = candidate.held_out_improvement > options.min_held_out_improvement;
  const bool bic_ok = candidate.bic_change < -options.min_bic_decrease;
  candidate.qualifies = held_out_ok && bic_ok;
  const std::string held_out_text = "held-out RMSE " + number(before.held_out_rmse_rad_s) + " -> " +
                                    number(after.held_out_rmse_rad_s) + " rad/s (" +
                                    signed_percent(-candidate.held_out_improvement) + ")";
  const std::string bic_text = "BIC " + printf_text("%+.4g", candidate.bic_change);
  if (candidate.qualifies) {
    candidate.verdict = "qualifies: " + held_out_text + ", " + bic_text;
  } else if (!held_out_ok) {
    candidate.verdict = "rejected: " + held_out_text + ", needs a fall of more than " +
                        percent(options.min_held_out_improvement);
  } else {
    candidate.verdict = "rejected: " + bic_text + " (must fall by more than " +
                        number(options.min_bic_decrease) + "), " + held_out_text;
  }
}

// The refits of one step (LoopOptions::parallel_refits): fit_model gives the same result bit
// for bit on any thread and with any num_threads (docs/fitting.md), so running them at once
// changes no verdict, only the time. Returns the refits by candidate index; counts fits.
std::vector<std::optional<FitResult>> run_refits(
    const DoorModel& start, const FitResult& current, const FitOptions& current_options,
    const PreparedData& data, const LoopOptions& options, const std::vector<std::size_t>& to_refit,
    ResidualExamination& examination, int& fits, const Say& say, int step_number) {
  std::vector<std::optional<FitResult>> refits(examination.candidates.size());
  const ModelFigures before = model_figures(current.summary);
  std::vector<std::string> refit_errors(to_refit.size());
  std::vector<int> refit_fits(to_refit.size(), 0);
  std::vector<double> refit_seconds(to_refit.size(), 0.0);
  LoopProgress progress{step_number, options.max_steps, 0, static_cast<int>(to_refit.size())};
  std::mutex progress_mutex;
  std::exception_ptr progress_error;
  if (options.step_progress && !to_refit.empty()) options.step_progress(progress);
  auto run_refit = [&](std::size_t j) {
    CandidateEvidence& candidate = examination.candidates[to_refit[j]];
    const StageClock::time_point refit_began = StageClock::now();
    try {
      refits[to_refit[j]] = refit(start, current, current_options, data, options, candidate,
                                  refit_fits[j], candidate.refit_start);
    } catch (const std::exception& error) {
      refit_errors[j] = error.what();
    } catch (...) {
      refit_errors[j] = "an exception that is not a std::exception";
    }
    refit_seconds[j] = seconds_since(refit_began);
    if (options.step_progress) {
      const std::lock_guard lock(progress_mutex);
      ++progress.refits_done;
      try {  // on a refit's thread: what it throws is rethrown on the caller's, after the join
        options.step_progress(progress);
      } catch (...) {
        if (!progress_error) progress_error = std::current_exception();
      }
    }
  };
  parallel_for(static_cast<int>(to_refit.size()),
               refit_threads(options.parallel_refits, to_refit.size()), run_refit);
  if (progress_error) std::rethrow_exception(progress_error);
  for (std::size_t j = 0; j < to_refit.size(); ++j) {
    const std::size_t k = to_refit[j];
    CandidateEvidence& candidate = examination.candidates[k];
    fits += refit_fits[j];
    if (!refits[k]) {
      candidate.verdict = "refit failed: " + refit_errors[j];
      say("  " + candidate.name + ": " + candidate.verdict);
      continue;
    }
    judge(candidate, before, model_figures(refits[k]->summary), options);
    say("  " + candidate.name + ": " + candidate.verdict +
        printf_text(" [refit from %s, %.1f s]", candidate.refit_start.c_str(), refit_seconds[j]));
  }
  return refits;
}

// The qualifying candidate with the lowest held-out RMSE; -1 when none qualifies.
int choose(const std::vector<CandidateEvidence>& candidates) {
  int chosen = -1;
  for (std::size_t k = 0; k < candidates.size(); ++k) {
    const CandidateEvidence& candidate = candidates[k];
    if (!candidate.qualifies) continue;
    if (chosen < 0 ||
        candidate.after->held_out_rmse_rad_s < candidates[chosen].after->held_out_rmse_rad_s) {
      chosen = static_cast<int>(k);
    }
  }
  return chosen;
}

LoopStep make_step(int step_number, ResidualExamination& examination, int chosen,
                   const FitResult& refit_result, const ModelFigures& before) {
  const CandidateEvidence& accepted = examination.candidates[chosen];
  LoopStep step;
  step.number = step_number;
  step.effect = accepted.kind;
  step.effect_name = accepted.name;
  step.second_look = accepted.promoted;
  step.explained_fraction =
      accepted.promoted ? accepted.screen_explained_fraction : accepted.explained_fraction;
  step.score_z = accepted.promoted ? accepted.screen_score_z : accepted.score_z;
  step.rank = accepted.rank;
  const std::string prefix = accepted.name + ".";
  for (const FittedParameter& parameter : refit_result.summary.parameters) {
    if (parameter.name.rfind(prefix, 0) == 0) step.parameters.push_back(parameter);
  }
  step.before = before;
  step.after = *accepted.after;
  step.held_out_improvement = accepted.held_out_improvement;
  step.bic_change = accepted.bic_change;
  step.candidates = std::move(examination.candidates);
  step.speed_bands = std::move(examination.speed_bands);
  return step;
}

// The reference door of the other family with the structure check's free set.
FitOptions structure_fit_options(const LoopOptions& options, ModelKind other) {
  FitOptions fit = options.fit;
  fit.fixed_parameters.clear();
  fit.free_parameters = options.structure_free_parameters;
  if (fit.free_parameters.empty() && other == ModelKind::kPhysical) {
    fit.free_parameters = {"J_d", "k_s", "F0", "T_h", "mu_g"};
  }
  return fit;
}

// Whether the structure check runs, and why (or why not).
bool structure_check_due(const LoopOptions& options, const ModelFigures& figures,
                         const ResidualExamination& last, StructureCheck& check) {
  for (const CandidateEvidence& candidate : last.candidates) {
    check.best_explained_fraction =
        std::max(check.best_explained_fraction, candidate.explained_fraction);
  }
  check.noise_floor_rad_s = last.noise_floor_rad_s;
  const double ratio = last.noise_floor_rad_s > 0
                           ? figures.held_out_rmse_rad_s / last.noise_floor_rad_s
                           : std::numeric_limits<double>::infinity();
  if (!options.structure_check) {
    check.reason = "off (structure_check)";
  } else if (check.best_explained_fraction >= options.structure_max_explained_fraction) {
    check.reason = "not run: the best candidate explains " +
                   percent(check.best_explained_fraction) + " of the residual (at least " +
                   percent(options.structure_max_explained_fraction) + ")";
  } else if (ratio <= options.structure_noise_ratio) {
    check.reason = "not run: the held-out RMSE " + number(figures.held_out_rmse_rad_s) +
                   " rad/s is " + printf_text("%.2g", ratio) + " times the noise floor " +
                   number(last.noise_floor_rad_s) + " rad/s (needs more than " +
                   printf_text("%.3g", options.structure_noise_ratio) + ")";
  } else {
    check.reason = "no effect closes the gap: the best remaining candidate explains " +
                   percent(check.best_explained_fraction) +
                   " of the residual and the held-out "
                   "RMSE " +
                   number(figures.held_out_rmse_rad_s) + " rad/s is " + printf_text("%.3g", ratio) +
                   " times the noise floor " + number(last.noise_floor_rad_s) + " rad/s";
    return true;
  }
  return false;
}

// The structure check: the other family fitted and compared, then examined for what it
// leaves. Counts its fit in `fits`.
StructureCheck check_structure(const FitResult& current, const PreparedData& data,
                               const LoopOptions& options, const ResidualExamination& last,
                               int& fits, const Say& say) {
  StructureCheck check;
  check.current_kind = current.model.kind();
  check.other_kind =
      check.current_kind == ModelKind::kSensory ? ModelKind::kPhysical : ModelKind::kSensory;
  check.current = model_figures(current.summary);
  if (!structure_check_due(options, check.current, last, check)) {
    return check;
  }
  check.ran = true;
  const std::string other_name(to_string(check.other_kind));
  say("structure check: " + check.reason + "; fitting the " + other_name + " model");
  const FitOptions fit = structure_fit_options(options, check.other_kind);
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
  ResidualExamination examination = examine(check.other_fit->model, data, options, fit);
  for (const CandidateEvidence& candidate : examination.candidates) {
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
                  ", " + signed_percent(-check.held_out_improvement) + "), BIC " +
                  printf_text("%+.4g", check.bic_change);
  say("structure check: " + check.verdict);
  return check;
}

}  // namespace

LoopResult run_residual_loop(const DoorModel& start, const PreparedData& data,
                             const LoopOptions& options) {
  const StageClock::time_point began = StageClock::now();
  if (const std::string message = options.validate(); !message.empty()) {
    throw std::invalid_argument(message);
  }
  int usable_strokes = 0;
  for (const Stroke& stroke : data.strokes) usable_strokes += stroke.size() >= 2 ? 1 : 0;
  if (usable_strokes < 2) {
    throw std::invalid_argument(
        "residual loop: the data needs at least 2 strokes (held-out errors need strokes left "
        "out of a fit)");
  }
  const Say say = [&](const std::string& line) {
    if (options.progress) options.progress(line);
  };

  say("fitting the start model (" + std::string(to_string(start.kind())) + ", " +
      std::to_string(start.effects().size()) + " effects) with " +
      std::to_string(options.fit.cross_validation_folds) + "-fold cross-validation");
  FitResult start_fit = fit_model(start, data, options.fit);
  LoopResult result{.start_fit = start_fit,
                    .final_fit = std::move(start_fit),
                    .steps = {},
                    .last_candidates = {},
                    .last_speed_bands = {},
                    .stop_reason = "",
                    .interrupted = false,
                    .fits = 1,
                    .total_time_s = 0.0,
                    .options = options,
                    .structure = {}};
  say("start model: " + describe_figures(model_figures(result.start_fit.summary)) +
      printf_text(" [%.1f s]", result.start_fit.summary.total_time_s));

  FitResult current = result.start_fit;
  FitOptions current_options = options.fit;  // the options current was fitted with
  current_options.progress = nullptr;        // the refits run several at once
  ResidualExamination last;                  // the examination that ended the loop
  // LoopOptions::stop_requested, asked at the stage boundaries; true stops the loop there.
  const auto stopping = [&](const std::string& where) {
    if (!options.stop_requested || !options.stop_requested()) return false;
    result.interrupted = true;
    result.stop_reason += (result.stop_reason.empty() ? "interrupted " : "; then interrupted ");
    result.stop_reason += where;
    return true;
  };
  for (int step_number = 1;; ++step_number) {
    const std::string step_text = "step " + std::to_string(step_number);
    if (step_number <= options.max_steps && stopping("before " + step_text)) break;
    if (step_number > options.max_steps) {
      result.stop_reason = "reached max_steps (" + std::to_string(options.max_steps) + ")";
      // The structure check's evidence: the final model's residual (no refits).
      if (options.structure_check) last = examine(current.model, data, options, current_options);
      break;
    }
    ResidualExamination examination = examine(current.model, data, options, current_options);
    if (examination.candidates.empty()) {
      result.stop_reason = "no candidate effect is left (every candidate is in the model)";
      last = std::move(examination);
      break;
    }
    say(ranking_line(step_number, examination));
    if (stopping("during " + step_text + ", before its refits (the step is abandoned)")) break;
    const ModelFigures before = model_figures(current.summary);
    const std::vector<std::size_t> to_refit = select_refits(examination, options, step_number, say);
    std::vector<std::optional<FitResult>> refits =
        run_refits(start, current, current_options, data, options, to_refit, examination,
                   result.fits, say, step_number);
    const int chosen = choose(examination.candidates);
    if (chosen < 0) {
      result.stop_reason =
          to_refit.empty()
              ? "no candidate was worth a refit (explained share or z below the thresholds)"
              : "no refitted candidate qualified";
      result.last_candidates = examination.candidates;
      result.last_speed_bands = examination.speed_bands;
      last = std::move(examination);
      break;
    }
    const effects::Kind accepted = examination.candidates[chosen].kind;
    LoopStep step = make_step(step_number, examination, chosen, *refits[chosen], before);
    std::string added = "step " + std::to_string(step_number) + ": added " + step.effect_name + ":";
    for (const FittedParameter& parameter : step.parameters) {
      added += ' ';
      added += parameter_text(parameter);
    }
    say(added);
    current = std::move(*refits[chosen]);
    current_options = refit_options(current_options, options, accepted);
    result.steps.push_back(std::move(step));
  }
  if (!result.interrupted) stopping("before the structure check");
  say("stopped: " + result.stop_reason);
  if (result.interrupted) {
    result.structure.reason = "not run: the loop was interrupted";
  } else {
    result.structure = check_structure(current, data, options, last, result.fits, say);
  }
  result.final_fit = std::move(current);
  result.total_time_s = seconds_since(began);
  return result;
}

}  // namespace doorbench
