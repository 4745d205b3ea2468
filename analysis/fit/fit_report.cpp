// The text reports of a fit: FitSummary::brief_report() and full_report().
#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <string>

#include "analysis/fit/fitting.h"
#include "analysis/fit/metric_notes.h"
#include "core/number_format.h"

namespace doorbench {

namespace {

// Above this relative uncertainty (10: 1000 %) the parameters table writes "> 1000%": the figure
// says only that the data do not determine the value.
constexpr double kLargestRelativeUncertaintyShown = 10.0;

std::string number(double value) {
  return format_significant(value, 6);
}

std::string short_number(double value) {
  if (std::isnan(value)) return "-";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  return printf_text("%.3g", value);
}

std::string objective_name(const FitOptions& options) {
  if (options.objective == FitOptions::Objective::kWholeStrokeMax) {
    return "whole strokes replayed, L" + std::to_string(2 * options.max_objective_power) +
           " norm of the rate error (after the window fit)";
  }
  return "least squares on windows (multiple shooting)";
}

std::string direction_name(StrokeDirection direction) {
  return direction == StrokeDirection::kOpening ? "open" : "close";
}

void metric_rows(std::string& out, const FitMetrics& fitted, const FitMetrics* held_out) {
  auto row = [&](const char* name, double fitted_value, double held_value, const char* unit) {
    out += printf_text("  %-36s %-12s %-12s %s\n", name, short_number(fitted_value).c_str(),
                       held_out ? short_number(held_value).c_str() : "-", unit);
  };
  auto percent_row = [&](const char* name, double fitted_value, double held_value) {
    out +=
        printf_text("  %-36s %-12s %-12s\n", name, format_percent(fitted_value / 100.0, 2).c_str(),
                    held_out ? format_percent(held_value / 100.0, 2).c_str() : "-");
  };
  const double nan = std::nan("");
  row("windows: RMSE of omega", fitted.window.rmse(), held_out ? held_out->window.rmse() : nan,
      "rad/s");
  row("windows: largest |omega error|", fitted.window.max_abs_error,
      held_out ? held_out->window.max_abs_error : nan, "rad/s");
  percent_row("windows: FIT%", fitted.window.fit_percent(),
              held_out ? held_out->window.fit_percent() : nan);
  row("whole strokes replayed: RMSE of omega", fitted.replay.rmse(),
      held_out ? held_out->replay.rmse() : nan, "rad/s");
  percent_row("whole strokes replayed: FIT%", fitted.replay.fit_percent(),
              held_out ? held_out->replay.fit_percent() : nan);
  row("study objective: max |omega error|", fitted.study_objective_rad_s(),
      held_out ? held_out->study_objective_rad_s() : nan, "rad/s (whole strokes replayed)");
}

}  // namespace

std::string GlobalSearch::report(const std::vector<std::string>& names) const {
  if (!ran) return "";
  std::vector<std::string> tried{"the data-derived start"};
  if (start_as_given) tried.push_back("the start as given");
  if (subset_refits > 0) {
    tried.push_back(std::to_string(subset_refits) + " subset refits (" + std::to_string(partition) +
                    " subsets" + (rounds > 1 ? ", " + std::to_string(rounds) + " rounds" : "") +
                    ")");
  }
  if (sample_points > 0) {
    tried.push_back(std::to_string(sample_points) +
                    " points of a space-filling sample of the bounds");
  }
  if (reset_parameters > 0) {
    tried.push_back("the first optimum with " + std::to_string(reset_parameters) +
                    (reset_parameters == 1 ? " undetermined or bound parameter at its start"
                                           : " undetermined or bound parameters at their starts"));
  }
  if (repolished > 0) {
    tried.push_back(std::to_string(repolished) + (repolished == 1 ? " polish" : " polishes") +
                    " of the best optimum from its own values (" +
                    std::to_string(repolished_lower) + " lower)");
  }
  if (soft_starts > 0) {
    tried.push_back(std::to_string(soft_starts) + (soft_starts == 1 ? " fit" : " fits") +
                    " of the data-derived start with softer switches (" +
                    std::to_string(soft_polished) + " polished)");
  }
  if (hops > 0) {
    tried.push_back(std::to_string(hops) + (hops == 1 ? " basin hop" : " basin hops") +
                    " from the best optimum so far (" + std::to_string(hops_lower) + " lower)");
  }
  std::string out = "Global search: " + std::to_string(starts_tried) + " starts tried (";
  for (std::size_t i = 0; i < tried.size(); ++i) {
    out += (i == 0 ? "" : i + 1 == tried.size() ? " and " : ", ") + tried[i];
  }
  out += "), " + std::to_string(promising) + " promising, " + std::to_string(polished) +
         " polished by Levenberg-Marquardt; " + std::to_string(optima.size()) +
         (optima.size() == 1 ? " distinct optimum" : " distinct optima") + "; " +
         std::to_string(reached_best) + " of the " + std::to_string(polished) +
         " polished reached the fit's, first " + best_from + ".\n";
  for (std::size_t o = 0; o < optima.size(); ++o) {
    const GlobalOptimum& optimum = optima[o];
    out += printf_text("  optimum %zu%s: cost %s", o + 1, o == 0 ? " (the fit)" : "",
                       format_significant(optimum.cost, 4).c_str());
    if (o > 0) out += " (" + format_signed_percent(optimum.cost / optima[0].cost - 1.0, 1) + ")";
    out += ", window FIT " + format_percent(optimum.fit_percent / 100.0, 2) + ", from ";
    for (std::size_t i = 0; i < optimum.reached_from.size(); ++i) {
      out += (i == 0 ? "" : ", ") + optimum.reached_from[i];
    }
    std::string differs;
    for (std::size_t k = 0; o > 0 && k < names.size() && k < optimum.free_values.size(); ++k) {
      const double value = optimum.free_values[k];
      const double fit = optima[0].free_values[k];
      if (std::abs(value - fit) <=
          kSameOptimumParameter * std::max(std::abs(value), std::abs(fit))) {
        continue;
      }
      differs += (differs.empty() ? "" : ", ") + names[k] + " " + format_significant(value, 4) +
                 " (the fit " + format_significant(fit, 4) + ")";
    }
    if (!differs.empty()) out += "; differs in " + differs;
    out += "\n";
  }
  return out;
}

std::string FitSummary::determining_lines() const {
  if (determining.empty()) return "";
  auto relative = [](double value) {
    return std::isfinite(value) ? printf_text("%.3g%%", 100.0 * value)
                                : std::string("undetermined");
  };
  // Every row has the same kinds, in the same order (what_would_determine).
  const std::vector<DeterminingStrokes::Kind>& kinds = determining.front().kinds;
  std::string out =
      "What would determine them: u/|value| now, and with strokes of each kind added, simulated "
      "with the fitted door (their information added to the fit's, the uncertainty scaled as "
      "the fit's window-robust one is to its classical one):\n";
  std::size_t label_width = 0;
  for (const DeterminingStrokes::Kind& kind : kinds) {
    label_width = std::max(label_width, kind.label.size());
  }
  for (const DeterminingStrokes::Kind& kind : kinds) {
    out += "  " + kind.label + std::string(label_width + 2 - kind.label.size(), ' ') + kind.kind +
           "\n";
  }
  // The table: a cell per parameter and column, then each column as wide as its widest cell.
  std::vector<std::vector<std::string>> cells{{"parameter", "now"}};
  for (const DeterminingStrokes::Kind& kind : kinds) cells.front().push_back(kind.label);
  cells.front().push_back("determined by");
  for (const DeterminingStrokes& row : determining) {
    const std::string state = row.undetermined && row.at_bound ? "undetermined, at a bound"
                              : row.undetermined               ? "undetermined"
                                                               : "at a bound";
    std::vector<std::string> line{row.parameter + " (" + state + ")", relative(row.relative_now)};
    std::string determined_by;
    for (const DeterminingStrokes::Kind& kind : row.kinds) {
      line.push_back(relative(kind.relative));
      if (kind.determines) determined_by += (determined_by.empty() ? "" : ", ") + kind.label;
    }
    line.push_back(determined_by.empty() ? std::string("none of these kinds") : determined_by);
    cells.push_back(std::move(line));
  }
  std::vector<std::size_t> widths(cells.front().size(), 0);
  for (const std::vector<std::string>& line : cells) {
    for (std::size_t c = 0; c < line.size() && c < widths.size(); ++c) {
      widths[c] = std::max(widths[c], line[c].size());
    }
  }
  for (const std::vector<std::string>& line : cells) {
    out += "  " + line[0] + std::string(widths[0] - line[0].size(), ' ');
    for (std::size_t c = 1; c + 1 < line.size(); ++c) {  // figures, right-aligned
      out += "  " + std::string(widths[c] - line[c].size(), ' ') + line[c];
    }
    out += "  " + line.back() + "\n";
  }
  return out;
}

namespace {

// What was fitted, how well, and the study objective: brief_report's and headline's first lines.
std::string outcome_lines(const FitSummary& summary) {
  const FitMetrics& fitted = summary.fitted;
  const std::optional<FitMetrics>& held_out = summary.held_out;
  std::string out = printf_text(
      "Fit of the %s model (%d free parameters) to %zu strokes, %zu windows: %s after %d "
      "iterations, %.2f s.\n",
      std::string(to_string(summary.model_kind)).c_str(), summary.free_parameters, summary.strokes,
      summary.windows, summary.converged ? "converged" : "NOT converged", summary.iterations,
      summary.total_time_s);
  out += "Window RMSE of omega " + short_number(fitted.window.rmse()) + " rad/s fitted";
  if (held_out) out += ", " + short_number(held_out->window.rmse()) + " held out";
  out += "; FIT% " + format_percent(fitted.window.fit_percent() / 100.0, 2);
  if (held_out) out += " / " + format_percent(held_out->window.fit_percent() / 100.0, 2);
  out += ".\n";
  out += "Study objective (whole strokes replayed): max |omega error| " +
         short_number(fitted.study_objective_rad_s()) + " rad/s (stroke " +
         std::to_string(fitted.worst_replay_stroke_id) + ").\n";
  return out;
}

// "Undetermined: a b", the parameters the data cannot determine (no line end).
std::string undetermined_list(const FitSummary& summary) {
  std::string out = "Undetermined:";
  for (const std::string& name : summary.undetermined) out += " " + name;
  return out;
}

}  // namespace

std::string FitSummary::brief_report() const {
  std::string out = outcome_lines(*this);
  out += fit_and_max_error_note(fitted);
  out += fit_percent_warnings(fitted, held_out ? &*held_out : nullptr);
  out += global.report(free_names);
  if (!undetermined.empty()) {
    out += undetermined_list(*this) + ".\n" + identifiable_line() + "\n";
  }
  out += determining_lines();
  return out;
}

std::string FitSummary::headline() const {
  std::string out = outcome_lines(*this);
  out += fit_percent_warnings(fitted, held_out ? &*held_out : nullptr);
  if (!undetermined.empty()) {
    out += undetermined_list(*this) +
           " (the parameter table and \"What would determine them\" below).\n";
  }
  return out;
}

std::string FitSummary::identifiable_line() const {
  if (undetermined.empty()) return "";
  if (identifiable.empty()) {
    return "Identifiable free set: none (with any of the free parameters held, the others are "
           "still undetermined).";
  }
  std::string out =
      "Identifiable free set (determined with the others held, from the "
      "Jacobian's singular vectors at the optimum):";
  for (const std::string& name : identifiable) out += " " + name;
  std::string held;
  for (const std::string& name : free_names) {
    if (std::find(identifiable.begin(), identifiable.end(), name) == identifiable.end()) {
      held += " " + name;
    }
  }
  return out + "; held:" + held + " (doorbench fit --free auto fits this set).";
}

namespace {

// The data, the model, the windows, the residuals and the objective.
void data_section(std::string& out, const FitSummary& summary) {
  int openings = 0;
  for (const StrokeFitMetrics& stroke : summary.fitted.strokes) {
    if (stroke.direction == StrokeDirection::kOpening) ++openings;
  }
  out += printf_text("Data       %s: %zu strokes (%d opening, %d closing)\n",
                     summary.source.empty() ? "(unnamed)" : summary.source.c_str(), summary.strokes,
                     openings, static_cast<int>(summary.fitted.strokes.size()) - openings);
  out += printf_text("Model      %s, %d of %zu parameters free\n",
                     std::string(to_string(summary.model_kind)).c_str(), summary.free_parameters,
                     summary.parameters.size());
  out += printf_text(
      "Windows    %zu of %g s, each started from the state at its first sample (%s); "
      "RK4, %d sub-steps per sample%s\n",
      summary.windows, summary.options.window_s,
      summary.options.estimate_window_states ? "estimated, measured state as its prior"
                                             : "as measured",
      summary.options.substeps_per_sample,
      summary.options.coarse_first ? " (1 in a first pass)" : "");
  out +=
      printf_text("Residuals  %zu: omega / %s rad/s%s\n", summary.residuals,
                  short_number(summary.rate_noise_rad_s).c_str(),
                  summary.options.angle_residuals
                      ? (" and theta / " + short_number(summary.angle_noise_rad) + " rad").c_str()
                      : "");
  out += "Objective  " + objective_name(summary.options) + "\n\n";
}

// The start, the solver and where the time went.
void solver_section(std::string& out, const FitSummary& summary) {
  if (summary.options.equation_error_start) {
    out +=
        printf_text("Start      equation error: %d iterations; %s\n",
                    summary.equation_error_iterations, summary.equation_error_termination.c_str());
  }
  out +=
      printf_text("Solver     Levenberg-Marquardt (Ceres), %d iterations, %.3f s (total %.3f s)\n",
                  summary.iterations, summary.solve_time_s, summary.total_time_s);
  out += "           " + summary.termination + "\n";
  out += "           cost 1/2 sum r^2: " + short_number(summary.initial_cost) + " -> " +
         short_number(summary.final_cost) +
         "; residual variance SSR/(n-p) = " + short_number(summary.residual_variance) +
         " (1 when the weights are the noise)\n";
  if (!std::isnan(summary.ceres_covariance_difference)) {
    out += "           ceres::Covariance agrees with the fit's (J'J)^-1 to " +
           short_number(summary.ceres_covariance_difference) + " (relative)\n";
  }
  out += printf_text(
      "Time       start %.3f s, equation error %.3f s, windows %.3f s, statistics %.3f s, "
      "metrics %.3f s, global search %.3f s, held out %.3f s, what would determine %.3f s\n\n",
      summary.times.start_s, summary.times.equation_error_s, summary.times.windows_s,
      summary.times.statistics_s, summary.times.metrics_s, summary.times.search_s,
      summary.times.held_out_s, summary.times.determining_s);
}

// The parameters with their uncertainties, strong correlations, the undetermined.
void parameter_section(std::string& out, const FitSummary& summary) {
  out += printf_text(
      "Parameters (u: standard uncertainty, %s; rank %d of %d; n_eff: windows the "
      "robust u rests on)\n",
      summary.options.uncertainty == FitOptions::Uncertainty::kWindowRobust
          ? "window jackknife"
          : "classical, (J'J)^-1 x SSR/(n-p)",
      summary.covariance_rank, summary.free_parameters);
  out += printf_text("  %-16s %-13s %-11s %-8s %-11s %-11s %-6s %-13s %-13s %-21s %s\n", "name",
                     "value", "u", "u/|v|", "u robust", "u classic", "n_eff", "start", "eq. error",
                     "bounds", "status");
  for (const FittedParameter& p : summary.parameters) {
    const std::string bounds = printf_text("[%s, %s]", short_number(p.bounds.lower).c_str(),
                                           short_number(p.bounds.upper).c_str());
    std::string status = p.free ? "free" : "fixed";
    if (p.free && !p.determined) status += ", UNDETERMINED";
    if (p.at_bound) status += ", at bound";
    if (p.start_origin != "start model") status += ", start " + p.start_origin;
    const double relative = p.uncertainty / std::abs(p.value);
    out += printf_text(
        "  %-16s %-13s %-11s %-8s %-11s %-11s %-6s %-13s %-13s %-21s %s\n", p.name.c_str(),
        number(p.value).c_str(), short_number(p.uncertainty).c_str(),
        p.free ? format_percent_at_most(relative, 2, kLargestRelativeUncertaintyShown).c_str()
               : "-",
        short_number(p.robust_uncertainty).c_str(), short_number(p.classical_uncertainty).c_str(),
        p.free ? printf_text("%.1f", p.effective_windows).c_str() : "-", number(p.start).c_str(),
        p.free ? number(p.equation_error).c_str() : "-", bounds.c_str(), status.c_str());
  }
  out += printf_text("\nCorrelations above %g:", summary.options.correlation_threshold);
  if (summary.strong_correlations.empty()) out += " none";
  out += "\n";
  for (const ParameterCorrelation& c : summary.strong_correlations) {
    out += printf_text("  %-16s %-16s %+.3f\n", c.first.c_str(), c.second.c_str(), c.value);
  }
  out += "Undetermined (rank-deficient direction or u/|value| above " +
         short_number(summary.options.undetermined_relative_uncertainty) + "):";
  if (summary.undetermined.empty()) out += " none";
  for (const std::string& name : summary.undetermined) out += " " + name;
  out += "\n";
  if (!summary.undetermined.empty()) out += summary.identifiable_line() + "\n";
  out += summary.determining_lines();
}

// The latch read off the data, when it was.
void latch_section(std::string& out, const FitSummary& summary) {
  if (summary.latch_start.opening_strokes + summary.latch_start.closing_strokes > 0) {
    out += printf_text("\nLatch start read off the data (%d opening, %d closing strokes):\n",
                       summary.latch_start.opening_strokes, summary.latch_start.closing_strokes);
    auto reading = [&](const char* name, const std::optional<double>& value, const char* unit) {
      if (value) out += printf_text("  %-8s %-12s %s\n", name, number(*value).c_str(), unit);
    };
    reading("theta0", summary.latch_start.theta0_rad, "rad");
    reading("theta1", summary.latch_start.theta1_rad, "rad");
    reading("theta2", summary.latch_start.theta2_rad, "rad");
    reading("theta3", summary.latch_start.theta3_rad, "rad");
    reading("k_inf", summary.latch_start.k_inf_Nm_per_rad, "N*m/rad");
    reading("k_lock", summary.latch_start.k_lock_Nm_per_rad, "N*m/rad");
  }
}

// The metrics, fitted and held out, in total and per stroke.
void metrics_section(std::string& out, const FitSummary& summary) {
  out += printf_text("\nMetrics                                %-12s %-12s\n", "fitted",
                     summary.held_out
                         ? ("held out (" + std::to_string(summary.folds) + " folds)").c_str()
                         : "held out");
  metric_rows(out, summary.fitted, summary.held_out ? &*summary.held_out : nullptr);
  out += fit_percent_warnings(summary.fitted, summary.held_out ? &*summary.held_out : nullptr);

  out += "\nPer stroke (omega errors in rad/s; held out: by the fold that left the stroke out)\n";
  out += printf_text("  %-7s %-6s %-8s %-8s %-10s %-10s %-8s %-11s %-10s %-11s\n", "stroke", "dir",
                     "samples", "windows", "win RMSE", "win max", "win FIT%", "replay max",
                     "held RMSE", "held replay");
  for (std::size_t i = 0; i < summary.fitted.strokes.size(); ++i) {
    const StrokeFitMetrics& s = summary.fitted.strokes[i];
    const StrokeFitMetrics* h = nullptr;
    if (summary.held_out) {
      for (const StrokeFitMetrics& candidate : summary.held_out->strokes) {
        if (candidate.stroke_id == s.stroke_id && candidate.direction == s.direction)
          h = &candidate;
      }
    }
    const std::string replay =
        s.replay_ok ? short_number(s.replay.max_abs_error) : std::string("failed");
    const std::string held_replay =
        h == nullptr ? "-" : (h->replay_ok ? short_number(h->replay.max_abs_error) : "failed");
    out += printf_text("  %-7d %-6s %-8zu %-8zu %-10s %-10s %-8s %-11s %-10s %-11s\n", s.stroke_id,
                       direction_name(s.direction).c_str(), s.window.count, s.windows,
                       short_number(s.window.rmse()).c_str(),
                       short_number(s.window.max_abs_error).c_str(),
                       format_percent(s.window.fit_percent() / 100.0, 2).c_str(), replay.c_str(),
                       h ? short_number(h->window.rmse()).c_str() : "-", held_replay.c_str());
  }
}

// The cross-validation folds and the notes.
void folds_section(std::string& out, const FitSummary& summary) {
  if (!summary.fold_fits.empty()) {
    out +=
        "\nCross-validation folds (each refitted from the full fit without its "
        "strokes)\n";
    for (std::size_t f = 0; f < summary.fold_fits.size(); ++f) {
      const FoldFit& fold = summary.fold_fits[f];
      std::string left_out;
      for (int id : fold.held_out_strokes) {
        left_out.append(left_out.empty() ? "" : ",").append(std::to_string(id));
      }
      out += printf_text(
          "  fold %zu (leaves out %s): %d iterations, %s; window RMSE %s fitted, "
          "%s "
          "held out\n",
          f + 1, left_out.c_str(), fold.iterations, fold.converged ? "converged" : "NOT converged",
          short_number(fold.fitted_rmse_rad_s).c_str(),
          short_number(fold.held_out_rmse_rad_s).c_str());
    }
  }
  if (!summary.notes.empty()) {
    out += "\nNotes\n";
    for (const std::string& note : summary.notes) out += "  - " + note + "\n";
  }
}

}  // namespace

std::string FitSummary::full_report() const {
  std::string out = "doorbench fit report\n\n";
  data_section(out, *this);
  solver_section(out, *this);
  if (global.ran) out += global.report(free_names) + "\n";
  parameter_section(out, *this);
  latch_section(out, *this);
  metrics_section(out, *this);
  folds_section(out, *this);
  return out;
}

}  // namespace doorbench
