// The residual loop's refits (internal/loop_steps.h; docs/residual-loop.md, "Refits and
// acceptance"): which candidates are refitted, each refit from its starts (the parent's
// optimum with the effect at its neutral value among them, so that no refit ends above its
// parent), the verdicts (held-out RMSE, BIC, no effect parameter at a bound or undetermined)
// and the choice among the qualifiers.
#include <algorithm>
#include <cmath>
#include <exception>
#include <mutex>
#include <stdexcept>

#include "analysis/loop/internal/linearization.h"
#include "analysis/loop/internal/loop_common.h"
#include "analysis/loop/internal/loop_steps.h"
#include "core/clock.h"
#include "core/number_format.h"
#include "core/numbers.h"
#include "core/parallel.h"

namespace doorbench::loop_detail {

namespace {

std::vector<std::string> refit_effect_parameter_names(effects::Kind kind) {
  const effects::EffectInfo& info = effects::info(kind);
  std::vector<std::string> names;
  for (const effects::EffectParameter& parameter : info.parameters) {
    names.push_back(std::string(info.name) + "." + std::string(parameter.info.name));
  }
  return names;
}

bool held_fixed(const LoopOptions& options, const std::string& name) {
  return std::find(options.fixed_effect_parameters.begin(), options.fixed_effect_parameters.end(),
                   name) != options.fixed_effect_parameters.end();
}

EffectSetting refit_setting(effects::Kind kind, std::vector<double> values) {
  EffectSetting setting{kind, std::move(values), {}};
  for (const effects::EffectParameter& parameter : effects::info(kind).parameters) {
    setting.bounds.push_back(parameter.default_bounds);
  }
  return setting;
}

// The candidate's start values with its amplitude at the neutral value, zero torque: 0, or
// for Stribeck d_s = the base model's dry-friction level.
std::vector<double> neutral_values(const CandidateEvidence& candidate, const DoorModel& parent) {
  std::vector<double> values = candidate.start_values;
  values[0] = candidate.kind == effects::Kind::kStribeck ? base_friction(parent).level_Nm : 0.0;
  return values;
}

double fitted_sum_of_squares(const FitResult& fit) {
  return model_figures(fit.summary).sum_of_squares;
}

struct RefitOutcome {
  std::optional<FitResult> result;  // empty: the parent's fit stands (or the refit failed)
  std::string origin;
  double best_sum_of_squares = kNaN;  // the lowest fitted sum of squares a fit reached
};

// Refits `current` with the candidate effect added (LoopOptions::RefitStart). With kBest, the
// better of the two starts is fitted again with cross-validation (the parent's optimum with
// the effect at its neutral value when both failed). A cross-validated fit that ends above
// the parent's fitted sum of squares is fitted again from that neutral start; one still above
// is not kept: the parent stands. `fits` counts the calls of fit_model.
RefitOutcome refit(const DoorModel& family_start, const FitResult& current,
                   const FitOptions& current_options, const PreparedData& data,
                   const LoopOptions& options, const CandidateEvidence& candidate, int& fits) {
  const double parent = fitted_sum_of_squares(current);
  const EffectSetting setting = refit_setting(candidate.kind, candidate.start_values);
  const FitOptions from_fit = refit_options(current_options, options, candidate.kind);
  FitOptions from_start = from_fit;
  from_start.latch_start_from_data = options.fit.latch_start_from_data;
  auto fresh_start = [&] {
    std::vector<double> values(current.model.parameter_values().begin(),
                               current.model.parameter_values().end());
    for (int i = 0; i < current.model.base_parameter_count(); ++i) {
      values[i] = family_start.parameter_values()[i];
    }
    return current.model.with_parameter_values(std::move(values)).with_effect(setting);
  };
  const DoorModel neutral = current.model.with_effect(
      refit_setting(candidate.kind, neutral_values(candidate, current.model)));
  // The final fit starts at an optimum of the fine problem, window states included (from the
  // measured states it would begin above that optimum and could end above it): no
  // equation-error stage and no coarse pass (which would leave that optimum for the coarse
  // one's and come back).
  // Its global stage is the subset refits alone (the loop chooses its starts): they are on
  // the cross-validation's partition (run_residual_loop), so they are its folds when they find
  // nothing better.
  FitOptions final_fit = from_fit;
  final_fit.equation_error_start = false;
  final_fit.coarse_first = false;
  final_fit.global_samples = 0;
  RefitOutcome out;
  // A refit that ends above the parent is fitted again from the parent's optimum with the
  // effect at neutral and the parent's window states (a point of the refit's problem at the
  // parent's sum of squares); if that too ends above, the parent stands.
  auto finish = [&](FitResult fitted, const std::string& origin, bool from_neutral) {
    out.origin = origin;
    out.best_sum_of_squares = fitted_sum_of_squares(fitted);
    if (out.best_sum_of_squares <= parent) {
      out.result = std::move(fitted);
      return;
    }
    if (from_neutral) {
      out.origin += " (the parent's fit stands)";
      return;
    }
    ++fits;
    FitOptions from_parent = final_fit;
    from_parent.window_state_start = current.window_states;
    FitResult again = fit_model(neutral, data, from_parent);
    out.origin = origin + ", then the parent's optimum (the effect at neutral)";
    out.best_sum_of_squares = std::min(out.best_sum_of_squares, fitted_sum_of_squares(again));
    if (fitted_sum_of_squares(again) <= parent) {
      out.result = std::move(again);
    } else {
      out.origin += " (the parent's fit stands)";
    }
  };
  switch (options.refit_start) {
    case LoopOptions::RefitStart::kCurrentFit:
      ++fits;
      finish(fit_model(current.model.with_effect(setting), data, from_fit), "the current fit",
             false);
      return out;
    case LoopOptions::RefitStart::kStartModel:
      ++fits;
      finish(fit_model(fresh_start(), data, from_start), "the start model", false);
      return out;
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
    // Each attempt is one start polished; of the global stage only the start as given is
    // screened (the loop's two attempts are its own search).
    fit.global_subsets = 0;
    fit.global_samples = 0;
    // A start is the loop's search, not its measurement: its coarse pass goes on to the fine
    // pass's own precision instead of stopping at once where σ is inflated (a model lacking
    // an effect), so the iterations run at the coarse problem's half cost.
    fit.coarse_tolerance_factor = 1.0;
    fit.what_would_determine = false;  // nobody reads a start's report
    try {
      const DoorModel model = which == 0 ? current.model.with_effect(setting) : fresh_start();
      attempts[which].result = fit_model(model, data, fit);
    } catch (const std::exception& error) {
      attempts[which].error = error.what();
    }
  };
  parallel_for(2, refit_threads(options.parallel_refits, 2), attempt);
  std::optional<FitResult> best;
  std::string origin = "the parent's optimum (the effect at neutral)";
  for (std::size_t which = 0; which < 2; ++which) {
    ++fits;
    Attempt& tried = attempts[which];
    if (!tried.result) continue;
    if (!best || fitted_sum_of_squares(*tried.result) < fitted_sum_of_squares(*best)) {
      best = std::move(tried.result);
      origin = names[which];
    }
  }
  // The better start's optimum, or the parent's with the effect at neutral when both failed.
  ++fits;
  final_fit.window_state_start = best ? best->window_states : current.window_states;
  finish(fit_model(best ? best->model : neutral, data, final_fit), origin, !best);
  return out;
}

// The effect's parameters of a refit, in the catalogue's order.
std::vector<FittedParameter> effect_parameters(const FitSummary& summary, const std::string& name) {
  std::vector<FittedParameter> parameters;
  const std::string prefix = name + ".";
  for (const FittedParameter& parameter : summary.parameters) {
    if (parameter.name.rfind(prefix, 0) == 0) parameters.push_back(parameter);
  }
  return parameters;
}

// A refitted candidate's figures and verdict against `before`. An effect with a free
// parameter at a bound or undetermined is not added, whatever the figures say.
// An effect whose amplitude the refit cannot tell apart from its neutral value
// (`amplitude_neutral`; LoopOptions::min_amplitude_z) is not added either.
void judge(CandidateEvidence& candidate, const ModelFigures& before, const ModelFigures& after,
           double amplitude_neutral, const LoopOptions& options) {
  candidate.after = after;
  candidate.held_out_improvement =
      (before.held_out_rmse_rad_s - after.held_out_rmse_rad_s) / before.held_out_rmse_rad_s;
  candidate.bic_change = after.bic - before.bic;
  const bool held_out_ok = candidate.held_out_improvement > options.min_held_out_improvement;
  const bool bic_ok = candidate.bic_change < -options.min_bic_decrease;
  std::string problems = refit_parameter_problems(candidate.kind, candidate.parameters);
  if (problems.empty()) {
    problems =
        weak_amplitude_problem(candidate.parameters, amplitude_neutral, options.min_amplitude_z);
  }
  candidate.qualifies = held_out_ok && bic_ok && problems.empty();
  const std::string held_out_text = "held-out RMSE " + number(before.held_out_rmse_rad_s) + " -> " +
                                    number(after.held_out_rmse_rad_s) + " rad/s (" +
                                    format_signed_percent(-candidate.held_out_improvement, 1) + ")";
  const std::string bic_text = "BIC " + printf_text("%+.4g", candidate.bic_change);
  if (candidate.qualifies) {
    candidate.verdict = "qualifies: " + held_out_text + ", " + bic_text;
  } else if (!problems.empty()) {
    candidate.verdict = "rejected: " + problems + "; " + held_out_text + ", " + bic_text;
  } else if (!held_out_ok) {
    candidate.verdict = "rejected: " + held_out_text + ", needs a fall of more than " +
                        format_percent(options.min_held_out_improvement, 1);
  } else {
    candidate.verdict = "rejected: " + bic_text + " (must fall by more than " +
                        number(options.min_bic_decrease) + "), " + held_out_text;
  }
}

// The verdict when no refit ended at or below the parent's fitted sum of squares: the refit
// is the parent's optimum with the effect at neutral. Its figures are the parent's with the
// effect's free parameters added to p (BIC + Δp ln n), its held-out RMSE the parent's.
void judge_parent_stands(CandidateEvidence& candidate, const DoorModel& parent,
                         const ModelFigures& before, const LoopOptions& options,
                         double best_sum_of_squares) {
  const effects::EffectInfo& info = effects::info(candidate.kind);
  const std::vector<std::string> names = refit_effect_parameter_names(candidate.kind);
  const std::vector<double> neutral = neutral_values(candidate, parent);
  candidate.parameters.clear();
  int added = 0;
  for (std::size_t k = 0; k < names.size(); ++k) {
    FittedParameter p;
    p.name = names[k];
    p.unit = std::string(info.parameters[k].info.unit);
    p.free = !held_fixed(options, names[k]);
    p.start = p.equation_error = p.value = neutral[k];
    p.uncertainty = p.classical_uncertainty = p.robust_uncertainty = kNaN;
    p.bounds = info.parameters[k].default_bounds;
    p.start_origin = "neutral";
    added += p.free ? 1 : 0;
    candidate.parameters.push_back(std::move(p));
  }
  ModelFigures after = before;
  after.free_parameters += added;
  after.parameters += added;
  after.bic = before.bic + added * std::log(static_cast<double>(before.residuals));
  candidate.parent_stands = true;
  candidate.after = after;
  candidate.held_out_improvement = 0.0;
  candidate.bic_change = after.bic - before.bic;
  candidate.qualifies = false;
  candidate.verdict =
      "rejected: no refit ended at or below the parent's fitted sum of squares "
      "(the lowest " +
      number(best_sum_of_squares) + " against " + number(before.sum_of_squares) +
      "): the parent's fit stands with " + candidate.name +
      " at its neutral value, held-out RMSE unchanged, BIC " +
      printf_text("%+.4g", candidate.bic_change);
}

}  // namespace

std::string ranking_line(int step_number, const ResidualExamination& examination) {
  std::string ranking = "step " + std::to_string(step_number) + ": the residual ranks ";
  for (std::size_t k = 0; k < examination.candidates.size() && k < 4; ++k) {
    if (k > 0) ranking += ", ";
    ranking += examination.candidates[k].name + " (" +
               format_percent(examination.candidates[k].explained_fraction, 1) +
               printf_text(", z %.3g)", examination.candidates[k].score_z);
  }
  return ranking;
}

FitOptions refit_options(const FitOptions& current, const LoopOptions& options,
                         effects::Kind kind) {
  FitOptions fit = current;
  fit.latch_start_from_data = false;  // the start is already a fit
  for (const std::string& name : refit_effect_parameter_names(kind)) {
    if (held_fixed(options, name)) {
      fit.fixed_parameters.push_back(name);
    } else if (!fit.free_parameters.empty()) {
      fit.free_parameters.push_back(name);
    }
  }
  return fit;
}

std::vector<std::size_t> select_refits(ResidualExamination& examination, const LoopOptions& options,
                                       int step_number, const std::vector<effects::Kind>& reexamine,
                                       const Say& say) {
  std::vector<std::size_t> order, promoted, forced;
  for (std::size_t k = 0; k < examination.candidates.size(); ++k) {
    CandidateEvidence& candidate = examination.candidates[k];
    const bool share_ok = candidate.explained_fraction >= options.min_explained_fraction;
    const bool screen_ok = candidate.screened &&
                           candidate.screen_explained_fraction >= options.min_explained_fraction &&
                           candidate.screen_score_z >= options.min_score_z;
    if (std::find(reexamine.begin(), reexamine.end(), candidate.kind) != reexamine.end()) {
      candidate.reexamined = true;
      forced.push_back(k);
    } else if (share_ok && candidate.score_z >= options.min_score_z) {
      order.push_back(k);
    } else if (screen_ok) {
      promoted.push_back(k);
    } else if (!share_ok) {
      candidate.verdict =
          "not refitted: explains " + format_percent(candidate.explained_fraction, 1) +
          " of the residual (needs " + format_percent(options.min_explained_fraction, 1) + ")";
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
  }
  to_refit.insert(to_refit.end(), forced.begin(), forced.end());
  for (std::size_t k : to_refit) {
    CandidateEvidence& candidate = examination.candidates[k];
    candidate.refitted = true;
    say("step " + std::to_string(step_number) + ": refitting with " + candidate.name +
        (candidate.scan.empty() ? "" : " (" + candidate.scan + ")") +
        (candidate.reexamined ? " (added before the family switch: re-examined)" : ""));
  }
  return to_refit;
}

std::vector<std::optional<FitResult>> run_refits(
    const DoorModel& family_start, const FitResult& current, const FitOptions& current_options,
    const PreparedData& data, const LoopOptions& options, const std::vector<std::size_t>& to_refit,
    ResidualExamination& examination, int& fits, const Say& say, int step_number) {
  std::vector<std::optional<FitResult>> refits(examination.candidates.size());
  const ModelFigures before = model_figures(current.summary);
  std::vector<RefitOutcome> outcomes(to_refit.size());
  std::vector<std::string> refit_errors(to_refit.size());
  std::vector<int> refit_fits(to_refit.size(), 0);
  std::vector<double> refit_seconds(to_refit.size(), 0.0);
  LoopProgress progress{step_number, options.max_steps, 0, static_cast<int>(to_refit.size())};
  std::mutex progress_mutex;
  std::exception_ptr progress_error;
  if (options.step_progress && !to_refit.empty()) options.step_progress(progress);
  auto run_refit = [&](std::size_t j) {
    const CandidateEvidence& candidate = examination.candidates[to_refit[j]];
    const StageClock::time_point refit_began = StageClock::now();
    try {
      outcomes[j] =
          refit(family_start, current, current_options, data, options, candidate, refit_fits[j]);
    } catch (const StopRequested&) {
      throw;  // every refit asks the same hook: parallel_for rethrows once all have ended
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
    candidate.before = before;
    candidate.refit_start = outcomes[j].origin;
    if (!refit_errors[j].empty()) {
      candidate.verdict = "refit failed: " + refit_errors[j];
      say("  " + candidate.name + ": " + candidate.verdict);
      continue;
    }
    if (outcomes[j].result) {
      candidate.parameters = effect_parameters(outcomes[j].result->summary, candidate.name);
      // The amplitude's neutral value at the refit (Stribeck: its own d1).
      const double neutral = neutral_values(candidate, outcomes[j].result->model).front();
      judge(candidate, before, model_figures(outcomes[j].result->summary), neutral, options);
      refits[k] = std::move(outcomes[j].result);
    } else {
      judge_parent_stands(candidate, current.model, before, options,
                          outcomes[j].best_sum_of_squares);
    }
    say("  " + candidate.name + ": " + candidate.verdict +
        printf_text(" [refit from %s, %.1f s]", candidate.refit_start.c_str(), refit_seconds[j]));
  }
  return refits;
}

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

}  // namespace doorbench::loop_detail

namespace doorbench {

std::string refit_parameter_problems(effects::Kind kind,
                                     const std::vector<FittedParameter>& parameters) {
  const effects::EffectInfo& info = effects::info(kind);
  std::string problems;
  for (std::size_t k = 0; k < parameters.size() && k < info.parameters.size(); ++k) {
    const FittedParameter& p = parameters[k];
    if (!p.free || (!p.at_bound && p.determined)) continue;
    std::string text = p.name + " = " + loop_detail::number(p.value);
    if (!p.unit.empty()) text.append(" ").append(p.unit);
    if (p.at_bound) {
      const bool lower = std::abs(p.value - p.bounds.lower) <= std::abs(p.bounds.upper - p.value);
      const double bound = lower ? p.bounds.lower : p.bounds.upper;
      const bool physical = lower && bound == info.parameters[k].minimum;
      text.append(" at its ").append(lower ? "lower" : "upper").append(" bound ");
      text += loop_detail::number(bound);
      if (!physical) {
        text += " (the end of the search range, not a physical limit)";
      } else if (k == 0 && kind != effects::Kind::kStribeck) {
        text += " (a physical limit, where the effect vanishes)";
      } else {
        text += " (a physical limit)";
      }
    }
    if (!p.determined) text += p.at_bound ? ", undetermined" : " undetermined";
    if (!problems.empty()) problems += "; ";
    problems += text;
  }
  return problems;
}

std::string weak_amplitude_problem(const std::vector<FittedParameter>& parameters, double neutral,
                                   double min_z) {
  if (parameters.empty() || min_z <= 0) return "";
  const FittedParameter& amplitude = parameters.front();
  if (!amplitude.free || !amplitude.determined || !(amplitude.uncertainty > 0)) return "";
  const double z = std::abs(amplitude.value - neutral) / amplitude.uncertainty;
  if (z >= min_z) return "";
  std::string text = amplitude.name + " = " + loop_detail::number(amplitude.value) + " +- " +
                     loop_detail::number(amplitude.uncertainty);
  if (!amplitude.unit.empty()) text.append(" ").append(amplitude.unit);
  text.append(printf_text(" is %.3g standard uncertainties from its neutral value ", z));
  text.append(loop_detail::number(neutral)).append(printf_text(" (needs %.3g)", min_z));
  return text;
}

}  // namespace doorbench
