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
#include "analysis/loop/internal/loop_steps.h"
#include "analysis/model/parameter_file.h"
#include "core/clock.h"
#include "core/number_format.h"
#include "core/numbers.h"
#include "core/parallel.h"

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
  // fit.global_subsets is checked as the loop uses it: set to the folds (run_residual_loop).
  FitOptions used = fit;
  used.global_subsets = fit.cross_validation_folds;
  if (const std::string message = used.validate(); !message.empty()) {
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
  if (!std::isfinite(min_amplitude_z) || min_amplitude_z < 0) {
    return "loop min_amplitude_z must be >= 0";
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
  figures.fitted_samples = summary.fitted.window.count;
  figures.held_out_samples = summary.held_out ? summary.held_out->window.count : 0;
  return figures;
}

namespace {

LoopStep make_step(int step_number, ResidualExamination& examination, int chosen,
                   const FitResult& refit_result, const ModelFigures& before) {
  const CandidateEvidence& accepted = examination.candidates[chosen];
  LoopStep step;
  step.number = step_number;
  step.model_kind = refit_result.model.kind();
  step.effect = accepted.kind;
  step.effect_name = accepted.name;
  step.second_look = accepted.promoted;
  step.explained_fraction =
      accepted.promoted ? accepted.screen_explained_fraction : accepted.explained_fraction;
  step.score_z = accepted.promoted ? accepted.screen_score_z : accepted.score_z;
  step.rank = accepted.rank;
  step.parameters = accepted.parameters;
  step.before = before;
  step.after = *accepted.after;
  step.held_out_improvement = accepted.held_out_improvement;
  step.bic_change = accepted.bic_change;
  step.candidates = std::move(examination.candidates);
  step.speed_bands = std::move(examination.speed_bands);
  return step;
}

// The loop's state between its stages.
struct LoopRun {
  const PreparedData& data;
  const LoopOptions& options;
  const Say& say;
  LoopResult& result;
  FitResult current;            // the current model's fit
  FitOptions current_options;   // the options its refits derive from
  DoorModel family_start;       // the start model of the current family
  int steps_in_family = 0;      // effects added in the current family
  bool family_checked = false;  // the structure check ran (it runs once)
  // Effects added before a family switch, not yet judged in the new family.
  std::vector<effects::Kind> reexamine;
  // The structure check's examination of the new family's fit, the next step's.
  std::optional<ResidualExamination> next_examination;

  // LoopOptions::stop_requested, asked at the stage boundaries; true stops the loop there.
  bool stopping(const std::string& where) {
    if (result.interrupted) return true;
    if (!options.stop_requested || !options.stop_requested()) return false;
    result.interrupted = true;
    result.stop_reason += (result.stop_reason.empty() ? "interrupted " : "; then interrupted ");
    result.stop_reason += where;
    return true;
  }
};

enum class FamilyCheck { kKept, kSwitched, kInterrupted };

// The structure check, once, when it is due on `examination` (the step's refits judged, if
// any): the other family fitted and compared. When it is the better structure the loop goes
// on in it from its fit, and the effects added before are re-examined there.
FamilyCheck family_check(LoopRun& run, const ResidualExamination& examination) {
  if (run.family_checked) return FamilyCheck::kKept;
  StructureCheck check;
  check.after_steps = static_cast<int>(run.result.steps.size());
  if (!structure_check_due(run.options, model_figures(run.current.summary), examination, check)) {
    run.result.structure = std::move(check);  // the reason it did not run, so far
    return FamilyCheck::kKept;
  }
  if (run.stopping("before the structure check")) return FamilyCheck::kInterrupted;
  ResidualExamination other_examination;
  check = check_structure(std::move(check), run.current, run.data, run.options, run.result.fits,
                          run.say, other_examination);
  run.family_checked = true;
  if (!check.other_better || !check.other_fit) {
    run.result.structure = std::move(check);
    return FamilyCheck::kKept;
  }
  check.switched = true;
  check.candidates = examination.candidates;  // the abandoned step's ranking and refits
  for (CandidateEvidence& candidate : check.candidates) {
    if (candidate.qualifies) {
      candidate.verdict += "; not added: the loop switched to the " +
                           std::string(to_string(check.other_kind)) + " model first";
    }
  }
  std::string names;
  for (const LoopStep& step : run.result.steps) {
    if (step.model_kind != run.current.model.kind()) continue;
    run.reexamine.push_back(step.effect);
    names += (names.empty() ? "" : ", ") + step.effect_name;
  }
  run.current = *check.other_fit;
  run.current_options = structure_fit_options(run.options, check.other_kind);
  run.current_options.progress = nullptr;
  run.family_start = reference_model(check.other_kind);
  run.steps_in_family = 0;
  run.next_examination = std::move(other_examination);
  run.result.stop_reason.clear();
  run.say("switching to the " + std::string(to_string(check.other_kind)) + " model" +
          (names.empty() ? "" : "; refitting there the effects added before it: " + names));
  run.result.structure = std::move(check);
  return FamilyCheck::kSwitched;
}

// What became of the effects re-examined after a family switch in this step: kept (the
// chosen one), dropped (rejected); one that qualified but was not chosen is tried again.
void settle_reexamined(LoopRun& run, const std::vector<CandidateEvidence>& candidates, int chosen,
                       int step_number) {
  for (std::size_t k = 0; k < candidates.size(); ++k) {
    const CandidateEvidence& candidate = candidates[k];
    if (!candidate.reexamined) continue;
    std::string fate;
    if (static_cast<int>(k) == chosen) {
      fate = candidate.name + ": kept (step " + std::to_string(step_number) + ")";
    } else if (!candidate.qualifies) {
      fate = candidate.name + ": dropped: " + candidate.verdict;
    } else {
      continue;
    }
    run.result.structure.reexamined.push_back(fate);
    run.say("  after the family switch, " + fate);
    std::erase(run.reexamine, candidate.kind);
  }
}

// Accepts the chosen candidate's refit as the step.
void accept_step(LoopRun& run, ResidualExamination& examination, int chosen,
                 std::optional<FitResult>& refit, int step_number) {
  const effects::Kind accepted = examination.candidates[chosen].kind;
  LoopStep step =
      make_step(step_number, examination, chosen, *refit, model_figures(run.current.summary));
  std::string added = "step " + std::to_string(step_number) + ": added " + step.effect_name + ":";
  for (const FittedParameter& parameter : step.parameters) {
    added += ' ';
    added += parameter_text(parameter);
  }
  run.say(added);
  run.current = std::move(*refit);
  run.current_options = refit_options(run.current_options, run.options, accepted);
  run.result.steps.push_back(std::move(step));
  ++run.steps_in_family;
}

// One step: examine, refit, check the family, choose. False when the loop stops.
bool loop_step(LoopRun& run) {
  const LoopOptions& options = run.options;
  LoopResult& result = run.result;
  const int step_number = static_cast<int>(result.steps.size()) + 1;
  const std::string step_text = "step " + std::to_string(step_number);
  if (run.steps_in_family >= options.max_steps) {
    result.stop_reason = "reached max_steps (" + std::to_string(options.max_steps) + ")";
    // The structure check's evidence: the final model's residual (no refits).
    if (run.family_checked || !options.structure_check) return false;
    const ResidualExamination last =
        examine(run.current.model, run.data, options, run.current_options);
    return family_check(run, last) == FamilyCheck::kSwitched;
  }
  if (run.stopping("before " + step_text)) return false;
  ResidualExamination examination =
      run.next_examination ? std::move(*run.next_examination)
                           : examine(run.current.model, run.data, options, run.current_options);
  run.next_examination.reset();
  if (examination.candidates.empty()) {
    result.stop_reason = "no candidate effect is left (every candidate is in the model)";
    return family_check(run, examination) == FamilyCheck::kSwitched;
  }
  run.say(ranking_line(step_number, examination));
  if (run.stopping("during " + step_text + ", before its refits (the step is abandoned)")) {
    return false;
  }
  const std::vector<std::size_t> to_refit =
      select_refits(examination, options, step_number, run.reexamine, run.say);
  std::vector<std::optional<FitResult>> refits =
      run_refits(run.family_start, run.current, run.current_options, run.data, options, to_refit,
                 examination, result.fits, run.say, step_number);
  if (family_check(run, examination) == FamilyCheck::kSwitched) return true;
  const int chosen = choose(examination.candidates);
  settle_reexamined(run, examination.candidates, chosen, step_number);
  if (chosen < 0) {
    result.stop_reason =
        to_refit.empty()
            ? "no candidate was worth a refit (explained share or z below the thresholds)"
            : "no refitted candidate qualified";
    result.last_candidates = examination.candidates;
    result.last_speed_bands = examination.speed_bands;
    return false;
  }
  accept_step(run, examination, chosen, refits[chosen], step_number);
  return !result.interrupted;
}

}  // namespace

LoopResult run_residual_loop(const DoorModel& start, const PreparedData& data,
                             const LoopOptions& given) {
  const StageClock::time_point began = StageClock::now();
  if (const std::string message = given.validate(); !message.empty()) {
    throw std::invalid_argument(message);
  }
  // Every fit of the loop (the start fit, the refits, the structure check's) derives its
  // options from `fit`: they all end at their next solver iteration when the loop is asked
  // to stop.
  LoopOptions options = given;
  if (!options.fit.stop_requested) options.fit.stop_requested = options.stop_requested;
  // The global stage's subset refits are the folds' partition, so each fit's
  // cross-validation reuses them instead of refitting the folds apart.
  options.fit.global_subsets = options.fit.cross_validation_folds;
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

  LoopRun run{.data = data,
              .options = options,
              .say = say,
              .result = result,
              .current = result.start_fit,
              .current_options = options.fit,
              .family_start = start,
              .steps_in_family = 0,
              .family_checked = false,
              .reexamine = {},
              .next_examination = std::nullopt};
  run.current_options.progress = nullptr;  // the refits run several at once
  try {
    while (loop_step(run)) {
    }
  } catch (const StopRequested& stop) {
    // A fit of the step under way ended early: the step is abandoned, the steps before kept.
    result.interrupted = true;
    result.stop_reason += (result.stop_reason.empty() ? "" : "; then ");
    result.stop_reason += "interrupted during step " + std::to_string(result.steps.size() + 1) +
                          ", in " + stop.where() + " (the step is abandoned)";
  }
  for (effects::Kind kind : run.reexamine) {
    result.structure.reexamined.push_back(std::string(effects::info(kind).name) +
                                          ": not judged in the new family before the loop "
                                          "stopped (" +
                                          result.stop_reason + ")");
  }
  say("stopped: " + result.stop_reason);
  if (result.interrupted && !run.family_checked) {
    result.structure = StructureCheck{};
    result.structure.reason = "not run: the loop was interrupted";
  }
  result.final_fit = std::move(run.current);
  result.total_time_s = seconds_since(began);
  return result;
}

}  // namespace doorbench
