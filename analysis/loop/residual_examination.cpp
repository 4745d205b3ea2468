// The residual examination (examine_residual; docs/residual-loop.md, "The examination"):
// the candidates' regressors scored against the rate residual with the free parameters
// projected out, and the second look at the weak ones. The linearization it scores is
// linearization.cpp.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>
#include <utility>

#include "analysis/fit/fit_metrics.h"
#include "analysis/fit/fit_windows.h"
#include "analysis/loop/internal/examination.h"
#include "analysis/loop/internal/linearization.h"
#include "analysis/loop/internal/loop_common.h"
#include "analysis/loop/residual_loop.h"
#include "core/clock.h"
#include "core/number_format.h"
#include "core/parallel.h"

namespace doorbench {

using namespace loop_detail;

namespace {

// An eigenvalue of the free parameters' scaled normal matrix below this share of the largest
// is a direction the data does not determine (left out of the projection); a regressor
// with less than this share of its norm left after the projection is indistinguishable
// from the free parameters.
constexpr double kProjectionRankTolerance = 1e-10;

std::vector<effects::Kind> candidate_kinds(const DoorModel& model, const LoopOptions& options) {
  std::vector<effects::Kind> kinds;
  if (options.candidates.empty()) {
    for (const effects::EffectInfo& effect : effects::catalogue()) kinds.push_back(effect.kind);
  } else {
    kinds = options.candidates;
  }
  std::erase_if(kinds, [&](effects::Kind kind) { return model.has_effect(kind); });
  return kinds;
}

// The free parameters a fit with `fit` would estimate (as fit_model resolves them; names
// the model lacks are skipped here, the fit itself reports them).
std::vector<int> free_indices(const DoorModel& model, const FitOptions& fit) {
  const std::vector<std::string> names =
      fit.free_parameters.empty() ? default_free_parameters(model) : fit.free_parameters;
  std::vector<char> free(model.parameter_count(), 0);
  for (const std::string& name : names) {
    if (const std::optional<int> index = model.find_parameter(name)) free[*index] = 1;
  }
  for (const std::string& name : fit.fixed_parameters) {
    if (const std::optional<int> index = model.find_parameter(name)) free[*index] = 0;
  }
  std::vector<int> indices;
  for (int i = 0; i < model.parameter_count(); ++i) {
    if (free[i]) indices.push_back(i);
  }
  return indices;
}

// A few damped Gauss–Newton (Levenberg–Marquardt) steps on the measured-state windows of
// the examination, the linearization above as the Jacobian: moves `parameters` (model
// indices) of `model` to lower Σ(ω − ω̂)². A step is taken only when it lowers the sum and
// no more windows fail to simulate. `linear` holds the columns [parameters..., e] at the
// result.
struct Refined {
  DoorModel model;
  Linearization linear;
  int steps = 0;
};

Refined refine_parameters(const DoorModel& start, const PreparedData& data,
                          const WindowOptions& windows, const std::vector<int>& parameters,
                          int max_steps) {
  Refined refined{start, linearize(start, data, windows, parameters, {}), 0};
  const int p = static_cast<int>(parameters.size());
  const auto bounds = start.parameter_bounds();
  double damping = 1e-3;
  for (int attempt = 0; attempt < 4 * max_steps && refined.steps < max_steps; ++attempt) {
    const Eigen::MatrixXd& g = refined.linear.gram;
    Eigen::VectorXd scale(p);
    for (int k = 0; k < p; ++k) {
      const double d = g(k, k);
      scale[k] = d > 0 && std::isfinite(d) ? 1.0 / std::sqrt(d) : 0.0;
    }
    const Eigen::MatrixXd a = scale.asDiagonal() * g.topLeftCorner(p, p) * scale.asDiagonal();
    const Eigen::VectorXd b = scale.cwiseProduct(g.block(0, p, p, 1));
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(a);
    const Eigen::VectorXd& values = eigen.eigenvalues();
    const double largest = values.size() > 0 ? values.maxCoeff() : 0.0;
    Eigen::VectorXd inverse = Eigen::VectorXd::Zero(p);
    for (int k = 0; k < p; ++k) {
      if (values[k] > kProjectionRankTolerance * largest) {
        inverse[k] = 1.0 / (values[k] + damping * largest);
      }
    }
    const Eigen::VectorXd step = scale.cwiseProduct(eigen.eigenvectors() * inverse.asDiagonal() *
                                                    eigen.eigenvectors().transpose() * b);
    if (!step.allFinite() || largest <= 0) break;
    std::vector<double> trial_values(refined.model.parameter_values().begin(),
                                     refined.model.parameter_values().end());
    for (int k = 0; k < p; ++k) {
      const int i = parameters[k];
      trial_values[i] = std::clamp(trial_values[i] + step[k], bounds[i].lower, bounds[i].upper);
    }
    std::optional<DoorModel> trial;
    try {
      trial = refined.model.with_parameter_values(std::move(trial_values));
    } catch (const std::invalid_argument&) {
      damping *= 10.0;
      continue;
    }
    const auto [trial_sum, trial_failed] = window_sum_of_squares(*trial, data, windows);
    const double before = refined.linear.rate_sum_of_squares;
    if (trial_failed <= refined.linear.failed_windows && trial_sum < before) {
      refined.model = std::move(*trial);
      refined.linear = linearize(refined.model, data, windows, parameters, {});
      ++refined.steps;
      damping = std::max(1e-6, 0.1 * damping);
      if (before - refined.linear.rate_sum_of_squares < 1e-3 * before) break;
    } else {
      damping *= 10.0;
    }
  }
  return refined;
}

// The projection off a Gram matrix's first `count` columns (X): (XᵀX)⁺ taken on
// unit-diagonal scaling with a relative eigenvalue cut-off, the coefficients β_a = (XᵀX)⁺
// Xᵀ(column a) in scaled coordinates, and (P column a)·(P column b) over the rows of any
// Gram matrix `g` of the same columns (the whole data or one window), P = I − X (XᵀX)⁺ Xᵀ.
class GramProjector {
 public:
  GramProjector(const Eigen::MatrixXd& gram, int count)
      : count_(count), scale_(Eigen::VectorXd::Ones(count)) {
    if (count_ == 0) return;
    for (int k = 0; k < count_; ++k) {
      const double d = gram(k, k);
      scale_[k] = d > 0 && std::isfinite(d) ? 1.0 / std::sqrt(d) : 0.0;
    }
    const Eigen::MatrixXd scaled =
        scale_.asDiagonal() * gram.topLeftCorner(count_, count_) * scale_.asDiagonal();
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(scaled);
    const Eigen::VectorXd& values = eigen.eigenvalues();
    const double largest = values.size() > 0 ? values.maxCoeff() : 0.0;
    Eigen::VectorXd inverse_values = Eigen::VectorXd::Zero(values.size());
    for (int k = 0; k < values.size(); ++k) {
      if (values[k] > kProjectionRankTolerance * largest) inverse_values[k] = 1.0 / values[k];
    }
    inverse_ =
        eigen.eigenvectors() * inverse_values.asDiagonal() * eigen.eigenvectors().transpose();
  }
  Eigen::VectorXd coefficients(const Eigen::MatrixXd& gram, int a) const {
    if (count_ == 0) return Eigen::VectorXd();
    return inverse_ * scale_.cwiseProduct(gram.block(0, a, count_, 1));
  }
  double project(const Eigen::MatrixXd& g, int a, const Eigen::VectorXd& beta_a, int b,
                 const Eigen::VectorXd& beta_b) const {
    double value = g(a, b);
    if (count_ == 0) return value;
    const Eigen::VectorXd ga = scale_.cwiseProduct(g.block(0, a, count_, 1));
    const Eigen::VectorXd gb = scale_.cwiseProduct(g.block(0, b, count_, 1));
    const Eigen::MatrixXd h =
        scale_.asDiagonal() * g.topLeftCorner(count_, count_) * scale_.asDiagonal();
    return value - beta_a.dot(gb) - beta_b.dot(ga) + beta_a.dot(h * beta_b);
  }

 private:
  int count_;
  Eigen::VectorXd scale_;
  Eigen::MatrixXd inverse_;
};

// The score of the last parameter column of `linear` (columns [nuisance..., x, e]) with
// the nuisance projected out: returns (x·Pe, |Px|², Σ_w (Px·r)_w²), the pieces of the
// window-clustered Wald statistic. r = Pe − (x·Pe/|Px|²) Px is the residual the linearised
// least-squares step in x would leave, as the first look's standard error takes it: at a
// least-squares point x·Pe = 0 and r = Pe, but a refinement cut off after a few steps is
// not at one, and Pe then still holds the score of the step not taken, which is no noise
// (the soft close of docs/residual-loop.md, "Recordings with the tremor hand": z 1.6 with
// Pe, 6.4 with r, after 5 steps).
struct ColumnScore {
  double pxe = 0.0, pxx = 0.0, spread = 0.0;
};

ColumnScore last_column_score(const Linearization& linear) {
  const int columns = static_cast<int>(linear.gram.rows());
  const int x = columns - 2, e = columns - 1;
  const GramProjector projector(linear.gram, x);
  const Eigen::VectorXd beta_x = projector.coefficients(linear.gram, x);
  const Eigen::VectorXd beta_e = projector.coefficients(linear.gram, e);
  ColumnScore score;
  score.pxe = projector.project(linear.gram, x, beta_x, e, beta_e);
  score.pxx = projector.project(linear.gram, x, beta_x, x, beta_x);
  const double step = score.pxx > 0 ? score.pxe / score.pxx : 0.0;
  for (const Eigen::MatrixXd& window_gram : linear.window_grams) {
    const double w = projector.project(window_gram, x, beta_x, e, beta_e) -
                     step * projector.project(window_gram, x, beta_x, x, beta_x);
    score.spread += w * w;
  }
  return score;
}

// A candidate chosen for the second look: the model with it added at its start values, and
// the parameters to refine (the free ones, the effect's other free parameters, its
// amplitude last: the column scored).
struct SecondLook {
  CandidateEvidence* candidate = nullptr;
  DoorModel with;
  std::vector<int> parameters;
  // The same with the amplitude at the far end of its first-order 3-standard-error interval
  // (when that is another value within the bounds): a second start for the refinement.
  std::optional<DoorModel> with_far;
};

// The second look's far start for each effect: parameter 0 (offset + amplitude) at
// â + 3 SE(â) (away from 0), clamped into the amplitude's range; only for effects whose
// first look gave an amplitude.
using FarStarts = std::vector<std::pair<effects::Kind, double>>;

// `model` with `setting`, or nothing when the values break a constraint.
std::optional<DoorModel> try_with_effect(const DoorModel& model, const EffectSetting& setting) {
  try {
    return model.with_effect(setting);
  } catch (const std::invalid_argument&) {
    return std::nullopt;
  }
}

// The candidates the second look takes (those the linear score leaves refit slots for).
std::vector<SecondLook> second_look_candidates(const DoorModel& model, const LoopOptions& options,
                                               const std::vector<int>& free,
                                               const FarStarts& far_starts,
                                               ResidualExamination& examination) {
  std::vector<SecondLook> chosen;
  // Only refit slots that the linear score leaves free are worth a second look.
  int slots = options.refit_candidates;
  for (const CandidateEvidence& candidate : examination.candidates) {
    if (candidate.explained_fraction >= options.min_explained_fraction &&
        candidate.score_z >= options.min_score_z) {
      --slots;
    }
  }
  int taken = 0;  // slots used, by a candidate the second look then takes or not
  for (CandidateEvidence& candidate : examination.candidates) {
    if (taken >= slots) break;
    // Every candidate that does not pass both thresholds, whatever its share: an effect
    // acting on a few windows explains little of the whole residual even when it is what
    // those windows lack (breakaway friction under impulses, docs/residual-loop.md,
    // "Breakaway friction on the recording family").
    if ((candidate.explained_fraction >= options.min_explained_fraction &&
         candidate.score_z >= options.min_score_z) ||
        candidate.start_values.empty()) {
      continue;
    }
    ++taken;
    const effects::EffectInfo& info = effects::info(candidate.kind);
    EffectSetting setting{candidate.kind, candidate.start_values, {}};
    for (const effects::EffectParameter& parameter : info.parameters) {
      setting.bounds.push_back(parameter.default_bounds);
    }
    std::optional<DoorModel> with = try_with_effect(model, setting);
    if (!with) continue;  // the start breaks a constraint: no second look
    std::optional<DoorModel> with_far;
    for (const auto& [kind, far] : far_starts) {
      if (kind != candidate.kind || far == setting.values[0]) continue;
      EffectSetting far_setting = setting;
      far_setting.values[0] = far;
      with_far = try_with_effect(model, far_setting);
    }
    std::vector<int> parameters = free;
    int amplitude = -1;
    for (std::size_t k = 0; k < info.parameters.size(); ++k) {
      const std::string name =
          std::string(info.name) + "." + std::string(info.parameters[k].info.name);
      const bool fixed =
          std::find(options.fixed_effect_parameters.begin(), options.fixed_effect_parameters.end(),
                    name) != options.fixed_effect_parameters.end();
      const std::optional<int> index = with->find_parameter(name);
      if (!index) continue;
      if (k == 0) {
        amplitude = *index;
      } else if (!fixed) {
        parameters.push_back(*index);
      }
    }
    if (amplitude < 0) continue;
    parameters.push_back(amplitude);
    chosen.push_back({&candidate, std::move(*with), std::move(parameters), std::move(with_far)});
  }
  return chosen;
}

// The second look (LoopOptions::screen_steps): the best-ranked candidates that do not pass
// both thresholds (share and z), as many as refit slots are left by the candidates that
// pass both, are each added at their examination start, and again at the far end of its
// amplitude's 3-standard-error interval, and refined from both, with the free parameters,
// by a few Gauss–Newton steps on the examination's windows (refine_parameters; the
// better of the two is kept); the model without it is refined the same way. Its screened
// share is the fall of Σe² between the two over the examination's Σe², its screened z the
// refined amplitude over its window-clustered standard error there. A linear score is
// poor where the effect's response is not linear in its amplitude: breakaway friction
// that holds the door a few milliseconds longer before the latch snaps.
void screen_weak_candidates(const DoorModel& model, const PreparedData& data,
                            const LoopOptions& options, const WindowOptions& windows,
                            const std::vector<int>& free, const FarStarts& far_starts,
                            ResidualExamination& examination) {
  if (options.screen_steps <= 0) return;
  const std::vector<SecondLook> chosen =
      second_look_candidates(model, options, free, far_starts, examination);
  if (chosen.empty()) return;
  // The model without any candidate, and each candidate's from both its starts, refined at
  // once (each is deterministic and independent: the same results as one after another).
  // Task 0 is the model without; task 2j + 1 candidate j's start, 2j + 2 its far start.
  const std::size_t tasks = 2 * chosen.size() + 1;
  std::vector<std::optional<Refined>> refined(tasks);
  std::vector<std::exception_ptr> errors(tasks);
  parallel_for(
      static_cast<int>(tasks), refit_threads(options.parallel_refits, tasks), [&](std::size_t t) {
        try {
          if (t == 0) {
            refined[t] = refine_parameters(model, data, windows, free, options.screen_steps);
            return;
          }
          const SecondLook& look = chosen[(t - 1) / 2];
          const std::optional<DoorModel>& start =
              t % 2 == 1 ? std::optional<DoorModel>(look.with) : look.with_far;
          if (start) {
            refined[t] =
                refine_parameters(*start, data, windows, look.parameters, options.screen_steps);
          }
        } catch (...) {
          errors[t] = std::current_exception();
        }
      });
  for (const std::exception_ptr& error : errors) {
    if (error) std::rethrow_exception(error);
  }
  const Refined& without = *refined[0];
  for (std::size_t j = 0; j < chosen.size(); ++j) {
    CandidateEvidence& candidate = *chosen[j].candidate;
    // The better of the two starts' refinements (the lower sum of squares).
    const std::optional<Refined>& near = refined[2 * j + 1];
    const std::optional<Refined>& far = refined[2 * j + 2];
    const Refined& with =
        far && far->linear.rate_sum_of_squares < near->linear.rate_sum_of_squares ? *far : *near;
    const effects::EffectInfo& info = effects::info(candidate.kind);
    const ColumnScore score = last_column_score(with.linear);
    const double offset =
        candidate.kind == effects::Kind::kStribeck ? base_friction(with.model).level_Nm : 0.0;
    const double value = with.model.parameter_values()[chosen[j].parameters.back()] - offset;
    const double fall = without.linear.rate_sum_of_squares - with.linear.rate_sum_of_squares;
    candidate.screened = true;
    candidate.screen_explained_fraction =
        examination.rate_sum_of_squares > 0 ? std::max(0.0, fall) / examination.rate_sum_of_squares
                                            : 0.0;
    candidate.screen_score_z =
        score.spread > 0 && fall > 0 ? std::abs(value) * score.pxx / std::sqrt(score.spread) : 0.0;
    candidate.screen_values.clear();
    for (const effects::EffectParameter& parameter : info.parameters) {
      const std::optional<int> index = with.model.find_parameter(std::string(info.name) + "." +
                                                                 std::string(parameter.info.name));
      candidate.screen_values.push_back(with.model.parameter_values()[*index]);
    }
  }
}

}  // namespace

namespace loop_detail {

ResidualExamination examine(const DoorModel& model, const PreparedData& data,
                            const LoopOptions& options, const FitOptions& fit) {
  const StageClock::time_point began = StageClock::now();
  const std::vector<effects::Kind> kinds = candidate_kinds(model, options);
  std::vector<Regressor> regressors = make_regressors(model, data, kinds, options);
  const WindowOptions windows = metric_window_options(fit, model);
  const std::vector<int> free = free_indices(model, fit);
  const int free_count = static_cast<int>(free.size());
  const int regressor_count = static_cast<int>(regressors.size());
  const int columns = free_count + regressor_count + 1;
  Linearization linear = linearize(model, data, windows, free, regressors);
  const Eigen::MatrixXd& gram = linear.gram;
  const std::vector<Eigen::MatrixXd>& window_grams = linear.window_grams;
  ResidualExamination examination;
  examination.samples = linear.samples;
  examination.rate_sum_of_squares = linear.rate_sum_of_squares;
  estimate_noise_floor(linear, examination);
  examination.speed_bands = linear.speed_bands();

  // Project the free parameters' columns out (the fit re-estimates them with the effect):
  // with X those columns, x a regressor and P = I − X (XᵀX)⁺ Xᵀ,
  //   x·Pe = x·e − xᵀX (XᵀX)⁺ Xᵀe,  |Px|² = x·x − xᵀX (XᵀX)⁺ Xᵀx,
  // (XᵀX)⁺ taken on unit-diagonal scaling with a relative eigenvalue cut-off.
  const GramProjector projector(gram, free_count);
  // β_a = (XᵀX)⁺ Xᵀ(column a), scaled: Xβ is the part of a column the parameters mimic.
  auto coefficients = [&](int a) { return projector.coefficients(gram, a); };
  // (P column a)·(P column b) over the rows of `g` (the whole data or one window).
  auto project = [&](const Eigen::MatrixXd& g, int a, const Eigen::VectorXd& beta_a, int b,
                     const Eigen::VectorXd& beta_b) {
    return projector.project(g, a, beta_a, b, beta_b);
  };
  const int e_column = columns - 1;
  const Eigen::VectorXd beta_e = coefficients(e_column);
  FarStarts far_starts;

  // Each effect's best configuration: the amplitude minimizing |Pe − a Px|² within its
  // range, and the share of Σe² it removes.
  for (effects::Kind kind : kinds) {
    CandidateEvidence candidate;
    candidate.kind = kind;
    candidate.name = std::string(effects::info(kind).name);
    int best = -1;
    double best_amplitude = 0.0;
    double best_reduction = -1.0;
    double best_independent = 0.0;
    double best_score = 0.0;
    for (int r = 0; r < regressor_count; ++r) {
      const Regressor& regressor = regressors[r];
      if (regressor.kind != kind) continue;
      const int c = free_count + r;
      const Eigen::VectorXd beta_x = coefficients(c);
      const double xx = gram(c, c);
      const double pxx = project(gram, c, beta_x, c, beta_x);
      const double pxe = project(gram, c, beta_x, e_column, beta_e);
      double amplitude = 0.0;
      double reduction = 0.0;
      const double independent = xx > 0 ? std::max(0.0, pxx) / xx : 0.0;
      if (independent > kProjectionRankTolerance && std::isfinite(pxe)) {
        amplitude = std::clamp(pxe / pxx, regressor.lower, regressor.upper);
        reduction = 2.0 * amplitude * pxe - amplitude * amplitude * pxx;
      }
      if (reduction > best_reduction) {
        // The amplitude over its window-clustered standard error (a Wald test): windows are
        // independent, the samples within one are not (the force noise integrates along
        // it). With r = Pe − â Px the residual left, Var(â) = Σ_w (Px·r)_w² / |Px|⁴.
        const double unconstrained = pxx > 0 ? pxe / pxx : 0.0;
        double spread = 0.0;
        for (const Eigen::MatrixXd& window_gram : window_grams) {
          const double score = project(window_gram, c, beta_x, e_column, beta_e) -
                               unconstrained * project(window_gram, c, beta_x, c, beta_x);
          spread += score * score;
        }
        best = r;
        best_amplitude = amplitude;
        best_reduction = reduction;
        best_independent = independent;
        best_score = spread > 0 ? std::abs(pxe) / std::sqrt(spread) : 0.0;
      }
    }
    if (best < 0) continue;  // no configuration (the end stop without data)
    candidate.explained_fraction =
        examination.rate_sum_of_squares > 0
            ? std::max(0.0, best_reduction) / examination.rate_sum_of_squares
            : 0.0;
    candidate.independent_share = best_independent;
    candidate.score_z = best_amplitude != 0.0 ? best_score : 0.0;
    candidate.start_values = regressors[best].unit_values;
    candidate.start_values[0] = regressors[best].amplitude_offset + best_amplitude;
    if (best_amplitude != 0.0 && best_score > 0) {
      const Regressor& regressor = regressors[best];
      const double far = best_amplitude * (1.0 + 3.0 / best_score);  // â + 3 SE(â), away from 0
      far_starts.emplace_back(
          kind, regressor.amplitude_offset + std::clamp(far, regressor.lower, regressor.upper));
    }
    candidate.scan = regressors[best].scan;
    examination.candidates.push_back(std::move(candidate));
  }
  std::stable_sort(examination.candidates.begin(), examination.candidates.end(),
                   [](const CandidateEvidence& a, const CandidateEvidence& b) {
                     return a.explained_fraction > b.explained_fraction;
                   });
  for (std::size_t k = 0; k < examination.candidates.size(); ++k) {
    examination.candidates[k].rank = static_cast<int>(k) + 1;
  }
  const StageClock::time_point screen_began = StageClock::now();
  screen_weak_candidates(model, data, options, windows, free, far_starts, examination);
  examination.screen_time_s = seconds_since(screen_began);
  examination.time_s = seconds_since(began);
  return examination;
}

}  // namespace loop_detail

ResidualExamination examine_residual(const DoorModel& model, const PreparedData& data,
                                     const LoopOptions& options) {
  if (const std::string message = options.validate(); !message.empty()) {
    throw std::invalid_argument(message);
  }
  return examine(model, data, options, options.fit);
}

}  // namespace doorbench
