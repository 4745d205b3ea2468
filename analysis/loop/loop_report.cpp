// The residual loop's reports: LoopResult::brief_report() and full_report() with their
// tables (figures before and after, candidates, speed bands, the structure check).
#include <cmath>
#include <string>

#include "analysis/loop/internal/loop_common.h"
#include "analysis/loop/residual_loop.h"
#include "core/number_format.h"

namespace doorbench {

using namespace loop_detail;

namespace {

void figures_table(std::string& out, const ModelFigures& before, const ModelFigures& after) {
  out += printf_text("    %-30s %-12s %-12s\n", "", "before", "after");
  auto row = [&](const char* name, double a, double b) {
    out += printf_text("    %-30s %-12s %-12s\n", name, number(a).c_str(), number(b).c_str());
  };
  row("window RMSE fitted (rad/s)", before.fitted_rmse_rad_s, after.fitted_rmse_rad_s);
  row("window RMSE held out (rad/s)", before.held_out_rmse_rad_s, after.held_out_rmse_rad_s);
  row("window FIT% fitted", before.fitted_fit_percent, after.fitted_fit_percent);
  row("window FIT% held out", before.held_out_fit_percent, after.held_out_fit_percent);
  row("BIC", before.bic, after.bic);
  row("free parameters", before.free_parameters, after.free_parameters);
  row("p in BIC (with window states)", before.parameters, after.parameters);
}

void candidate_table(std::string& out, const std::vector<CandidateEvidence>& candidates) {
  out += printf_text("    %-4s %-19s %-9s %-6s %-13s %-10s %s\n", "rank", "effect", "explains", "z",
                     "held-out RMSE", "BIC change", "verdict");
  for (const CandidateEvidence& candidate : candidates) {
    out += printf_text(
        "    %-4d %-19s %-9s %-6.3g %-13s %-10s %s\n", candidate.rank, candidate.name.c_str(),
        format_percent(candidate.explained_fraction, 1).c_str(), candidate.score_z,
        candidate.after ? format_signed_percent(-candidate.held_out_improvement, 1).c_str() : "-",
        candidate.after ? printf_text("%+.4g", candidate.bic_change).c_str() : "-",
        candidate.verdict.c_str());
    if (!candidate.scan.empty()) out += printf_text("         scan: %s\n", candidate.scan.c_str());
    if (!candidate.refit_start.empty()) {
      out += printf_text("         refit from %s\n", candidate.refit_start.c_str());
    }
    if (!candidate.parameters.empty()) {
      out += "         parameters:";
      for (const FittedParameter& parameter : candidate.parameters) {
        out += ' ';
        out += parameter_text(parameter);
        out += ';';
      }
      out += "\n";
    }
  }
}

void speed_band_line(std::string& out, const std::vector<SpeedBand>& bands) {
  if (bands.empty()) return;
  out += "    residual by measured speed |omega| (RMS of omega - omega_hat, rad/s, samples):";
  for (const SpeedBand& band : bands) {
    out += std::isfinite(band.high_rad_s)
               ? printf_text(" [%g, %g) %s (%zu);", band.low_rad_s, band.high_rad_s,
                             number(band.rms_rad_s).c_str(), band.samples)
               : printf_text(" >= %g %s (%zu)", band.low_rad_s, number(band.rms_rad_s).c_str(),
                             band.samples);
  }
  out += "\n";
}

void structure_section(std::string& out, const StructureCheck& check) {
  out += "\nStructure check: " + check.reason + "\n";
  if (!check.ran) return;
  out += "  " + check.verdict + "\n";
  out += printf_text("  checked after %d step%s", check.after_steps,
                     check.after_steps == 1 ? "" : "s");
  if (check.switched) {
    out += "; the loop went on with the " + std::string(to_string(check.other_kind)) +
           " model (the step under way abandoned)\n";
    for (const std::string& line : check.reexamined) out += "  re-examined " + line + "\n";
    if (!check.candidates.empty()) {
      out += "  the abandoned step's candidates:\n";
      candidate_table(out, check.candidates);
    }
  } else {
    out += "\n";
  }
  if (!check.other_fit) return;
  out += "  " + std::string(to_string(check.other_kind)) + " model, free:";
  for (const std::string& name : check.other_free) out += " " + name;
  out += check.other_undetermined.empty() ? "; every one determined\n" : "; undetermined:";
  for (const std::string& name : check.other_undetermined) out += " " + name;
  if (!check.other_undetermined.empty()) out += "\n";
  figures_table(out, check.current, check.other);
  out += "  (before: the loop's " + std::string(to_string(check.current_kind)) +
         " model; after: the " + std::string(to_string(check.other_kind)) + " model)\n";
  if (check.remaining.empty()) {
    out += "  the examination of the " + std::string(to_string(check.other_kind)) +
           " fit ranks no catalogue effect above the refit thresholds\n";
    return;
  }
  out += "  effects the " + std::string(to_string(check.other_kind)) +
         " fit still lacks, by the examination (not refitted):\n";
  candidate_table(out, check.remaining);
}

std::string effect_list(const std::vector<LoopStep>& steps) {
  std::string list;
  for (const LoopStep& step : steps) list += (list.empty() ? "" : ", ") + step.effect_name;
  return list;
}

}  // namespace

std::string LoopResult::brief_report() const {
  const ModelFigures first = model_figures(start_fit.summary);
  const ModelFigures last = model_figures(final_fit.summary);
  std::string out;
  out += printf_text("Residual loop%s: %zu effect%s added%s; %d fits, %.2f s.\n",
                     interrupted ? " (interrupted: the steps finished before it)" : "",
                     steps.size(), steps.size() == 1 ? "" : "s",
                     steps.empty() ? "" : (" (" + effect_list(steps) + ")").c_str(), fits,
                     total_time_s);
  out += "Window RMSE of omega, held out: " + number(first.held_out_rmse_rad_s) + " -> " +
         number(last.held_out_rmse_rad_s) + " rad/s; fitted: " + number(first.fitted_rmse_rad_s) +
         " -> " + number(last.fitted_rmse_rad_s) + " rad/s.\n";
  for (const LoopStep& step : steps) {
    if (structure.switched) out.append("[").append(to_string(step.model_kind)).append("] ");
    out += printf_text(
        "Step %d: %s (explains %s of the residual, z %.3g%s, rank %d of %zu):", step.number,
        step.effect_name.c_str(), format_percent(step.explained_fraction, 1).c_str(), step.score_z,
        step.second_look ? " on the second look" : "", step.rank, step.candidates.size());
    for (const FittedParameter& parameter : step.parameters) {
      if (!parameter.free) continue;
      out += ' ';
      out += parameter_text(parameter);
      out += ';';
    }
    out += " held-out RMSE " + format_signed_percent(-step.held_out_improvement, 1) + ", BIC " +
           printf_text("%+.4g", step.bic_change) + ".\n";
  }
  out += "Stopped: " + stop_reason + ".\n";
  if (structure.ran) {
    out += "Structure check: " + structure.verdict +
           (structure.switched ? "; the loop went on with the " +
                                     std::string(to_string(structure.other_kind)) + " model"
                               : "") +
           ".\n";
  }
  return out;
}

std::string LoopResult::full_report() const {
  std::string out = brief_report();
  const FitOptions& fit = start_fit.summary.options;
  out +=
      "\nMethod (docs/residual-loop.md): each step ranks the candidate effects by the share of "
      "the rate residual's\nsum of squares their best amplitude explains (linearized window "
      "sensitivity, free parameters\nprojected out), refits the best that are significant, and "
      "accepts the one with the lowest\nheld-out RMSE among those that lower it by more than "
      "the threshold and lower BIC.\n";
  out += printf_text("  cross-validation folds %d, window %.3g s\n", fit.cross_validation_folds,
                     fit.window_s);
  out += printf_text(
      "  refit at most %d per step if it explains >= %s and z >= %.3g; accept if the "
      "held-out RMSE falls > %s, BIC falls > %.3g and the amplitude is >= %.3g u from "
      "neutral\n",
      options.refit_candidates, format_percent(options.min_explained_fraction, 1).c_str(),
      options.min_score_z, format_percent(options.min_held_out_improvement, 1).c_str(),
      options.min_bic_decrease, options.min_amplitude_z);
  out += "\nStart model: " + std::string(to_string(start_fit.model.kind())) + ", " +
         describe_figures(model_figures(start_fit.summary)) + ", BIC " +
         number(model_figures(start_fit.summary).bic) + "\n";
  for (const LoopStep& step : steps) {
    out += printf_text("\nStep %d: added %s\n", step.number, step.effect_name.c_str());
    out += "  parameters (standard uncertainty):\n";
    for (const FittedParameter& parameter : step.parameters) {
      out += "    " + parameter_text(parameter) + "\n";
    }
    out += "  figures:\n";
    figures_table(out, step.before, step.after);
    out += "  candidates:\n";
    speed_band_line(out, step.speed_bands);
    candidate_table(out, step.candidates);
  }
  if (!last_candidates.empty()) {
    out += "\nLast examination (no step taken):\n";
    speed_band_line(out, last_speed_bands);
    candidate_table(out, last_candidates);
  }
  out += "\nStopped: " + stop_reason + ".\n";
  structure_section(out, structure);
  out += "\nFinal fit:\n" + final_fit.summary.brief_report();
  return out;
}

}  // namespace doorbench
