#pragma once
// What the data allow for breakaway friction, whatever the residual examination does
// (docs/residual-loop.md, "What the data allow"): the refit the loop would make if
// its examination pointed at breakaway friction with the true values, judged by the loop's
// acceptance rule. Used by studies/breakaway_oracle.cpp over many draws and by
// tests/analysis/test_residual_loop_family.cpp on the draws the loop misses.
//
//   BreakawayRefit r = refit_from_true_breakaway(data, LoopOptions{});
//   r.qualifies   // the loop's rule would add it
//
// The base fit is the loop's start fit (the sensory reference door, options.fit). The refit
// starts twice, from the base fit with Stribeck friction at d1 + excess, width, and from the
// true door (the reference with that friction); the one with the lower fitted sum of squares
// is kept. The rule: held-out window RMSE down by more than min_held_out_improvement, BIC
// down by more than min_bic_decrease, the amplitude d_s − d1 at least min_amplitude_z
// standard uncertainties from zero, neither of the effect's parameters at a bound or
// undetermined (the loop's refit_parameter_problems looks at the effect's only). Throws what
// fit_model throws; thread-safe as fit_model is.
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "analysis/fit/fitting.h"
#include "analysis/loop/residual_loop.h"
#include "core/numbers.h"
#include "tests/support/reference_doors.h"

namespace doorbench::testing {

struct BreakawayRefit {
  FitSummary base, refit;  // the base fit's and the kept refit's
  ModelFigures base_figures, refit_figures;
  double amplitude_N_m = kNaN, amplitude_u_N_m = kNaN, width_rad_s = kNaN;
  bool bound_or_undetermined = false;
  bool qualifies = false;

  double held_out_fall() const {
    return (base_figures.held_out_rmse_rad_s - refit_figures.held_out_rmse_rad_s) /
           base_figures.held_out_rmse_rad_s;
  }
  double amplitude_z() const { return std::abs(amplitude_N_m) / amplitude_u_N_m; }
};

namespace breakaway_detail {

inline const FittedParameter& parameter(const FitSummary& summary, const std::string& name) {
  for (const FittedParameter& p : summary.parameters) {
    if (p.name == name) return p;
  }
  throw std::logic_error("breakaway refit: no parameter " + name);
}

}  // namespace breakaway_detail

inline BreakawayRefit refit_from_true_breakaway(const PreparedData& data, const LoopOptions& loop,
                                                double excess_N_m = 1.5,
                                                double width_rad_s = 0.05) {
  using breakaway_detail::parameter;
  BreakawayRefit r;
  const FitResult base = fit_model(sensory_reference(), data, loop.fit);
  FitOptions refit = loop.fit;
  refit.latch_start_from_data = false;  // the start is already a fit, as in the loop's refits
  const double d1 = parameter(base.summary, "d1").value;
  FitResult informed =
      fit_model(with_breakaway(base.model, d1 + excess_N_m, width_rad_s), data, refit);
  FitResult from_truth =
      fit_model(sensory_reference_with_breakaway(excess_N_m, width_rad_s), data, refit);
  r.base = base.summary;
  r.refit = model_figures(informed.summary).sum_of_squares <=
                    model_figures(from_truth.summary).sum_of_squares
                ? std::move(informed.summary)
                : std::move(from_truth.summary);
  r.base_figures = model_figures(r.base);
  r.refit_figures = model_figures(r.refit);
  const FittedParameter& d_s = parameter(r.refit, "stribeck.d_s");
  r.amplitude_N_m = d_s.value - parameter(r.refit, "d1").value;
  r.amplitude_u_N_m = d_s.uncertainty;
  r.width_rad_s = parameter(r.refit, "stribeck.w_s").value;
  for (const char* name : {"stribeck.d_s", "stribeck.w_s"}) {  // the effect's, as the loop checks
    const FittedParameter& p = parameter(r.refit, name);
    if (p.free && (p.at_bound || !p.determined)) r.bound_or_undetermined = true;
  }
  r.qualifies = r.held_out_fall() > loop.min_held_out_improvement &&
                r.refit_figures.bic - r.base_figures.bic < -loop.min_bic_decrease &&
                r.amplitude_z() >= loop.min_amplitude_z && !r.bound_or_undetermined;
  return r;
}

// What the data can say of the breakaway amplitude at the true door: d_s's standard
// uncertainty (the fit's kind, window-robust by default) from a fit started at the true door
// (the sensory reference with the breakaway friction), without cross-validation or the
// equation-error start, with
//   kDoorFree:  the loop's free set (options.fit's, else the default) and the effect's two
//               parameters, one iteration (the uncertainty at the truth, not where a
//               refit may wander);
//   kDoorKnown: d_s and w_s only, every other parameter held at its true value;
//   kAllKnown:  d_s alone.
// A one-sided test at level α has power 1 − β only if excess / u ≥ z_{1−α} + z_{1−β} (2.93
// for 5 % and 90 %); an estimator that knows less than the fit does knows d_s less well.
enum class Known { kDoorFree, kDoorKnown, kAllKnown };

inline double breakaway_amplitude_uncertainty(const PreparedData& data, const LoopOptions& loop,
                                              Known known, double excess_N_m = 1.5,
                                              double width_rad_s = 0.05) {
  FitOptions options = loop.fit;
  if (known == Known::kDoorFree) {
    options.max_iterations = 1;
  } else {
    options.free_parameters = {"stribeck.d_s"};
    if (known == Known::kDoorKnown) options.free_parameters.push_back("stribeck.w_s");
  }
  options.cross_validation_folds = 0;
  options.equation_error_start = false;
  options.latch_start_from_data = false;
  const FitResult fit =
      fit_model(sensory_reference_with_breakaway(excess_N_m, width_rad_s), data, options);
  return breakaway_detail::parameter(fit.summary, "stribeck.d_s").uncertainty;
}

}  // namespace doorbench::testing
