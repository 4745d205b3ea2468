#include "analysis/fit/fit_problem.h"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <functional>
#include <limits>
#include <mutex>
#include <stdexcept>
#include <system_error>
#include <thread>

#include "analysis/fit/internal/fit_equation_error.h"
#include "core/numbers.h"
#include "core/parallel.h"

namespace doorbench {

namespace {

// DOORBENCH_FIT_TRACE=1 prints Ceres' progress and summaries to stderr.
bool tracing() {
  return std::getenv("DOORBENCH_FIT_TRACE") != nullptr;
}

}  // namespace

// Keeps the results of the last evaluations at one point: residuals and every Jacobian
// (`full_`), and residuals alone (`values_`, a trial point). prepare() fills them on our
// own threads before Ceres asks (EvaluationPreparer); Evaluate() then only copies. The
// trust-region solver evaluates the Jacobian at each accepted point, so `full_` holds it at
// the current iterate: the stopping rule and the statistics need no new evaluation.
class CachingCost final : public ceres::CostFunction {
 public:
  explicit CachingCost(ceres::CostFunction* inner) : inner_(inner) {
    set_num_residuals(inner->num_residuals());
    *mutable_parameter_block_sizes() = inner->parameter_block_sizes();
  }

  // Evaluates at `parameters` into the cache unless it holds the result there already.
  // Touches this cost only: costs may be prepared on different threads at once.
  void prepare(double const* const* parameters, bool with_jacobians) const {
    if (holds(full_, parameters)) return;
    if (with_jacobians) {
      fill(full_, parameters, true);
    } else if (!holds(values_, parameters)) {
      fill(values_, parameters, false);
    }
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const std::vector<int32_t>& sizes = parameter_block_sizes();
    bool any_jacobian = false;
    for (std::size_t b = 0; jacobians != nullptr && b < sizes.size(); ++b) {
      any_jacobian = any_jacobian || jacobians[b] != nullptr;
    }
    const Slot* slot = nullptr;
    if (holds(full_, parameters)) {
      slot = &full_;
    } else if (any_jacobian) {
      fill(full_, parameters, true);
      slot = &full_;
    } else {
      if (!holds(values_, parameters)) fill(values_, parameters, false);
      slot = &values_;
    }
    if (!slot->ok) return false;
    std::copy(slot->residuals.begin(), slot->residuals.end(), residuals);
    for (std::size_t b = 0; any_jacobian && b < sizes.size(); ++b) {
      if (jacobians[b] != nullptr) {
        std::copy(slot->jacobians[b].begin(), slot->jacobians[b].end(), jacobians[b]);
      }
    }
    return true;
  }

  bool cached_at(double const* const* parameters) const { return holds(full_, parameters); }

  // Residuals and row-major Jacobians (one per parameter block) at `parameters`: the cached
  // ones when taken there, else evaluated now.
  bool evaluate_at(double const* const* parameters, const std::vector<double>** residuals,
                   const std::vector<std::vector<double>>** jacobians) const {
    if (!holds(full_, parameters)) fill(full_, parameters, true);
    *residuals = &full_.residuals;
    *jacobians = &full_.jacobians;
    return full_.ok;
  }

 private:
  struct Slot {
    bool valid = false;
    bool ok = false;
    std::vector<double> at;  // the parameter blocks' values, concatenated
    std::vector<double> residuals;
    std::vector<std::vector<double>> jacobians;
  };

  bool holds(const Slot& slot, double const* const* parameters) const {
    if (!slot.valid) return false;
    const std::vector<int32_t>& sizes = parameter_block_sizes();
    for (std::size_t b = 0, at = 0; b < sizes.size(); ++b) {
      for (int i = 0; i < sizes[b]; ++i, ++at) {
        if (slot.at[at] != parameters[b][i]) return false;
      }
    }
    return true;
  }

  void fill(Slot& slot, double const* const* parameters, bool with_jacobians) const {
    const std::vector<int32_t>& sizes = parameter_block_sizes();
    slot.at.clear();
    for (std::size_t b = 0; b < sizes.size(); ++b) {
      slot.at.insert(slot.at.end(), parameters[b], parameters[b] + sizes[b]);
    }
    slot.residuals.resize(static_cast<std::size_t>(num_residuals()));
    std::vector<double*> pointers;
    if (with_jacobians) {
      slot.jacobians.resize(sizes.size());
      for (std::size_t b = 0; b < sizes.size(); ++b) {
        slot.jacobians[b].resize(static_cast<std::size_t>(num_residuals()) * sizes[b]);
        pointers.push_back(slot.jacobians[b].data());
      }
    }
    slot.ok = inner_->Evaluate(parameters, slot.residuals.data(),
                               with_jacobians ? pointers.data() : nullptr);
    slot.valid = true;
  }

  std::unique_ptr<ceres::CostFunction> inner_;
  mutable Slot full_;
  mutable Slot values_;
};

// Before every evaluation: checks the model's constraints at the new point (a trial step
// that breaks one fails to evaluate everywhere, and Levenberg–Marquardt shrinks its step),
// then evaluates every residual block on our own threads into its CachingCost. Ceres itself
// runs on one thread and only sums what was prepared, in the blocks' fixed order: the
// result does not depend on which thread evaluated which block. (Ceres' own threads sum
// cost, gradient and Schur complement in the order the threads happen to finish.)
class EvaluationPreparer final : public ceres::EvaluationCallback {
 public:
  EvaluationPreparer(const DoorModel& model, const ParameterMap& map, const double* x)
      : model_(model), map_(map), x_(x) {}

  void add(const CachingCost* cost, std::vector<const double*> blocks) {
    costs_.push_back(cost);
    blocks_.push_back(std::move(blocks));
  }
  void set_threads(int threads) { threads_ = std::max(1, threads); }

  void PrepareForEvaluation(bool evaluate_jacobians, bool new_evaluation_point) override {
    if (new_evaluation_point) check();
    if (feasible_) prepare(evaluate_jacobians);
  }

  // At the parameter blocks' current values, outside the solver.
  void prepare_here(bool jacobians) {
    check();
    if (feasible_) prepare(jacobians);
  }

  const bool* flag() const { return &feasible_; }

 private:
  void check() {
    try {
      (void)model_.with_parameter_values(map_.values(x_));
      feasible_ = true;
    } catch (const std::invalid_argument&) {
      feasible_ = false;
    }
  }
  void prepare(bool jacobians) const {
    parallel_for(static_cast<int>(costs_.size()), threads_,
                 [&](int i) { costs_[i]->prepare(blocks_[i].data(), jacobians); });
  }

  const DoorModel& model_;
  const ParameterMap& map_;
  const double* x_;
  bool feasible_ = true;
  int threads_ = 1;
  std::vector<const CachingCost*> costs_;
  std::vector<std::vector<const double*>> blocks_;
};

namespace {

// The free parameters' block with the parameter file's bounds, in solver units.
void add_free_block(ceres::Problem& problem, double* x, const DoorModel& model,
                    const ParameterMap& map) {
  problem.AddParameterBlock(x, map.free_count());
  const auto bounds = model.parameter_bounds();
  for (int k = 0; k < map.free_count(); ++k) {
    const Bounds& b = bounds[map.free_index[k]];
    problem.SetParameterLowerBound(x, k, b.lower / map.scale[k]);
    problem.SetParameterUpperBound(x, k, b.upper / map.scale[k]);
  }
}

// The priors as one residual block on x: r_i = (x_k − c_i) / s_i (linear).
class PriorCost final : public ceres::CostFunction {
 public:
  PriorCost(std::vector<PriorResidual> priors, int free_count) : priors_(std::move(priors)) {
    set_num_residuals(static_cast<int>(priors_.size()));
    mutable_parameter_block_sizes()->push_back(free_count);
  }
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const int p = parameter_block_sizes()[0];
    for (std::size_t i = 0; i < priors_.size(); ++i) {
      const PriorResidual& prior = priors_[i];
      residuals[i] = (parameters[0][prior.free_position] - prior.center_x) / prior.sigma_x;
      if (jacobians != nullptr && jacobians[0] != nullptr) {
        double* row = jacobians[0] + i * static_cast<std::size_t>(p);
        std::fill(row, row + p, 0.0);
        row[prior.free_position] = 1.0 / prior.sigma_x;
      }
    }
    return true;
  }

 private:
  std::vector<PriorResidual> priors_;
};

ceres::Solver::Options solver_options(const SolverSettings& options, int max_iterations) {
  ceres::Solver::Options solver;
  solver.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  solver.linear_solver_type = ceres::DENSE_QR;
  solver.max_num_iterations = max_iterations;
  solver.function_tolerance = options.function_tolerance;
  solver.parameter_tolerance = options.parameter_tolerance;
  solver.gradient_tolerance = options.gradient_tolerance;
  // One thread: the residual blocks are evaluated in parallel by EvaluationPreparer, and
  // Ceres' own threads would sum them in scheduling order (results differing run to run).
  solver.num_threads = 1;
  solver.logging_type = tracing() ? ceres::PER_MINIMIZER_ITERATION : ceres::SILENT;
  solver.minimizer_progress_to_stdout = tracing();
  // With bounds, Ceres follows each trust-region step with a projected line search that
  // evaluates the whole Jacobian at every trial point (about 3 Jacobians per iteration
  // here); the projected trust-region step alone converges as well at a third of the cost.
  solver.max_num_line_search_step_size_iterations = 0;
  // The stopping rules below read the user's parameter blocks.
  solver.update_state_every_iteration = true;
  // The window residuals are not smooth everywhere (contact with a stop at low speed, the
  // latch switches at sub-switch scales): allowing steps that raise the cost for a while
  // gets the solver through such rough valleys instead of crawling.
  solver.use_nonmonotonic_steps = true;
  return solver;
}

bool converged(const ceres::Solver::Summary& summary) {
  return summary.termination_type == ceres::CONVERGENCE ||
         summary.termination_type == ceres::USER_SUCCESS;
}

std::string termination_text(const ceres::Solver::Summary& summary) {
  if (summary.termination_type == ceres::USER_SUCCESS) {
    return "CONVERGENCE: the parameters settled (the stopping rule's own test)";
  }
  return std::string(ceres::TerminationTypeToString(summary.termination_type)) + ": " +
         summary.message;
}

void trace_summary(const ceres::Solver::Summary& summary) {
  if (tracing()) std::fprintf(stderr, "%s\n", summary.FullReport().c_str());
}

// Stops once two accepted steps in a row change no parameter by more than `tolerance` (x
// is in units of each parameter's scale). For the equation-error stage, whose result is
// only a start.
class RelativeStepCheck final : public ceres::IterationCallback {
 public:
  RelativeStepCheck(const std::vector<double>& x, double tolerance)
      : x_(x), previous_(x), tolerance_(tolerance) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override {
    if (summary.iteration == 0 || !summary.step_is_successful) return ceres::SOLVER_CONTINUE;
    double largest = 0.0;
    for (std::size_t k = 0; k < x_.size(); ++k) {
      largest = std::max(largest, std::abs(x_[k] - previous_[k]) / std::max(1.0, std::abs(x_[k])));
    }
    previous_ = x_;
    settled_steps_ = largest <= tolerance_ ? settled_steps_ + 1 : 0;
    return settled_steps_ >= 2 ? ceres::SOLVER_TERMINATE_SUCCESSFULLY : ceres::SOLVER_CONTINUE;
  }

 private:
  const std::vector<double>& x_;
  std::vector<double> previous_;
  double tolerance_;
  int settled_steps_ = 0;
};

// Stops when, from the Jacobian the solver has just computed, the Gauss–Newton step for x
// (window states eliminated) moves no determined parameter by more than `tolerance` of its
// standard uncertainty (the kind the fit reports): further iterations would change the result
// by less than the statistics can tell. Before the first step, with first_step_decrease, that
// step must also predict a decrease ½ gᵀ H⁻¹ g of at most kRoughCostChange of the cost (a
// start's misfit inflates every σ). Also stops after three accepted steps in a row that each
// moved every parameter by less than that and lowered the cost by less than kRoughCostChange:
// the cost is rough at this scale (latch switches, a stop) and Levenberg–Marquardt would crawl.
class PredictedStepCheck final : public ceres::IterationCallback {
 public:
  static constexpr double kRoughCostChange = 1e-3;  // relative, per step
  PredictedStepCheck(const WindowProblem& problem, double tolerance, const SolverSettings& settings)
      : problem_(problem), tolerance_(tolerance), settings_(settings), previous_(problem.x()) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override {
    if (!(tolerance_ > 0)) return ceres::SOLVER_CONTINUE;
    if (summary.iteration > 0 && !summary.step_is_successful) return ceres::SOLVER_CONTINUE;
    ReducedSystem system;
    if (!problem_.reduce(/*cached_only=*/true, system)) return ceres::SOLVER_CONTINUE;
    const Eigen::VectorXd sigma = standard_uncertainties(system, settings_.robust_uncertainty);
    const InformationInverse inverse = invert_information(system.information);
    const Eigen::VectorXd step = inverse.inverse * system.gradient;
    const std::vector<double>& x = problem_.x();
    double predicted = 0.0;
    double taken = 0.0;
    for (int k = 0; k < step.size(); ++k) {
      if (inverse.undetermined[k] || !(sigma(k) > 0)) continue;
      predicted = std::max(predicted, std::abs(step(k)) / sigma(k));
      taken = std::max(taken, std::abs(x[k] - previous_[k]) / sigma(k));
    }
    previous_ = x;
    // A step that still lowers the cost markedly is progress however small it is against
    // σ: far from the data (a model lacking an effect) σ is inflated by the residual.
    const bool small =
        taken <= tolerance_ && summary.cost_change <= kRoughCostChange * summary.cost;
    const double predicted_decrease = 0.5 * system.gradient.dot(step);
    const bool first_step_waits = summary.iteration == 0 && settings_.first_step_decrease &&
                                  predicted_decrease > kRoughCostChange * summary.cost;
    if (summary.iteration > 0) small_steps_ = small ? small_steps_ + 1 : 0;
    if (tracing()) {
      std::fprintf(stderr, "step taken %.3g, predicted %.3g standard uncertainties, -%.3g cost\n",
                   taken, predicted, predicted_decrease);
    }
    if (predicted <= tolerance_ && !first_step_waits) {
      reason_ = "the Gauss-Newton step predicts less than " + format_tolerance() +
                " standard uncertainty for every parameter";
      return ceres::SOLVER_TERMINATE_SUCCESSFULLY;
    }
    if (small_steps_ >= 3) {
      reason_ = "three accepted steps in a row moved no parameter by more than " +
                format_tolerance() + " standard uncertainty (the cost is rough at this scale)";
      return ceres::SOLVER_TERMINATE_SUCCESSFULLY;
    }
    return ceres::SOLVER_CONTINUE;
  }
  const std::string& reason() const { return reason_; }

 private:
  std::string format_tolerance() const {
    char text[32];
    std::snprintf(text, sizeof text, "%g", tolerance_);
    return text;
  }

  const WindowProblem& problem_;
  double tolerance_;
  const SolverSettings& settings_;  // the solve's, which outlive the check
  std::vector<double> previous_;
  int small_steps_ = 0;
  std::string reason_;
};

}  // namespace

Eigen::VectorXd standard_uncertainties(const ReducedSystem& system, bool robust) {
  const InformationInverse inverse = invert_information(system.information);
  const Eigen::MatrixXd covariance = robust ? robust_covariance(system, inverse.inverse).covariance
                                            : system.residual_variance() * inverse.inverse;
  return covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
}

RobustCovariance robust_covariance(const ReducedSystem& system, const Eigen::MatrixXd& inverse) {
  const int p = static_cast<int>(system.information.rows());
  const int windows = static_cast<int>(system.window_scores.size());
  RobustCovariance out;
  if (windows < 2) {
    out.covariance = Eigen::MatrixXd::Constant(p, p, kNaN);
    out.effective_windows = Eigen::VectorXd::Zero(p);
    return out;
  }
  const int rank = invert_information(system.information).rank;
  std::vector<Eigen::VectorXd> changes(windows);
  Eigen::VectorXd mean = Eigen::VectorXd::Zero(p);
  for (int w = 0; w < windows; ++w) {
    const InformationInverse without =
        invert_information(system.information - system.window_information[w]);
    changes[w] = (without.rank == rank ? without.inverse : inverse) * system.window_scores[w];
    mean += changes[w];
  }
  mean /= windows;
  Eigen::MatrixXd covariance = Eigen::MatrixXd::Zero(p, p);
  Eigen::VectorXd sum_of_squares = Eigen::VectorXd::Zero(p);
  for (const Eigen::VectorXd& change : changes) {
    const Eigen::VectorXd deviation = change - mean;
    covariance += deviation * deviation.transpose();
    sum_of_squares += deviation.cwiseAbs2().cwiseAbs2();
  }
  out.covariance = covariance * (static_cast<double>(windows - 1) / windows);
  out.effective_windows.resize(p);
  for (int k = 0; k < p; ++k) {
    out.effective_windows(k) =
        sum_of_squares(k) > 0 ? covariance(k, k) * covariance(k, k) / sum_of_squares(k) : 0.0;
  }
  return out;
}

double ReducedSystem::residual_variance() const {
  const int dof = residuals - static_cast<int>(information.rows()) - window_parameters;
  return dof > 0 ? sum_of_squares / dof : kNaN;
}

InformationInverse invert_information(const Eigen::MatrixXd& information) {
  const int p = static_cast<int>(information.rows());
  InformationInverse out;
  out.undetermined.assign(p, 0);
  Eigen::VectorXd unit(p);
  for (int k = 0; k < p; ++k) {
    unit(k) = information(k, k) > 0 ? 1.0 / std::sqrt(information(k, k)) : 0.0;
  }
  const Eigen::MatrixXd normalized = unit.asDiagonal() * information * unit.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(normalized);
  const double largest = eigen.eigenvalues().maxCoeff();
  Eigen::VectorXd inverse_eigen(p);
  for (int e = 0; e < p; ++e) {
    const double value = eigen.eigenvalues()(e);
    if (value > kRankTolerance * largest) {
      ++out.rank;
      inverse_eigen(e) = 1.0 / value;
      continue;
    }
    inverse_eigen(e) = 0.0;
    for (int k = 0; k < p; ++k) {
      const double share = eigen.eigenvectors()(k, e) * eigen.eigenvectors()(k, e);
      if (share > kNullSpaceShare) out.undetermined[k] = 1;
    }
  }
  for (int k = 0; k < p; ++k) {
    if (!(information(k, k) > 0)) out.undetermined[k] = 1;
  }
  out.inverse =
      unit.asDiagonal() *
      (eigen.eigenvectors() * inverse_eigen.asDiagonal() * eigen.eigenvectors().transpose()) *
      unit.asDiagonal();
  return out;
}

WindowProblem::WindowProblem(const DoorModel& model, const PreparedData& data,
                             const ParameterMap& map, const ProblemKind& kind,
                             const FitWeights& weights, std::vector<double> x0)
    : map_(map), x_(std::move(x0)) {
  preparer_ = std::make_unique<EvaluationPreparer>(model, map_, x_.data());
  setup_.model = &model;
  setup_.data = &data;
  setup_.map = &map_;
  setup_.substeps_per_sample = kind.windows.substeps_per_sample;
  setup_.rate_noise_rad_s = weights.rate_noise_rad_s;
  setup_.angle_noise_rad = weights.angle_noise_rad;
  setup_.angle_residuals = weights.angle_residuals;
  setup_.estimate_start_state = kind.estimate_start_states;
  setup_.residual_power = kind.residual_power;
  setup_.feasible = preparer_->flag();
  windows_ = split_windows(data, kind.windows);
  z_.assign(kind.estimate_start_states ? 2 * windows_.size() : 0, 0.0);
  ceres::Problem::Options problem_options;
  problem_options.evaluation_callback = preparer_.get();
  problem_ = std::make_unique<ceres::Problem>(problem_options);
  add_free_block(*problem_, x_.data(), model, map_);
  for (std::size_t w = 0; w < windows_.size(); ++w) {
    auto* cost = new CachingCost(make_window_cost(setup_, windows_[w]));
    costs_.push_back(cost);
    if (kind.estimate_start_states) {
      problem_->AddResidualBlock(cost, nullptr, x_.data(), z_.data() + 2 * w);
      preparer_->add(cost, {x_.data(), z_.data() + 2 * w});
    } else {
      problem_->AddResidualBlock(cost, nullptr, x_.data());
      preparer_->add(cost, {x_.data()});
    }
  }
  priors_ = weights.priors;
  if (!priors_.empty()) {
    problem_->AddResidualBlock(new PriorCost(priors_, map_.free_count()), nullptr, x_.data());
  }
}

WindowProblem::~WindowProblem() = default;

int WindowProblem::residual_count() const {
  int count = 0;
  for (const CachingCost* cost : costs_) count += cost->num_residuals();
  return count;
}

namespace {

// SolverSettings::stop_requested as a Ceres callback: ends the solve when the hook says so;
// the solve then throws StopRequested (throw_if_stopped()).
class StopCheck final : public ceres::IterationCallback {
 public:
  explicit StopCheck(const StopHook& hook) : hook_(hook) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary&) override {
    if (!stop_requested(hook_)) return ceres::SOLVER_CONTINUE;
    fired_ = true;
    return ceres::SOLVER_ABORT;
  }
  void throw_if_stopped(const char* where) const {
    if (fired_) throw StopRequested(where);
  }

 private:
  const StopHook& hook_;
  bool fired_ = false;
};

// SolverSettings::on_iteration as a Ceres callback.
class IterationReport final : public ceres::IterationCallback {
 public:
  explicit IterationReport(const std::function<void(int)>& report) : report_(report) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override {
    if (summary.iteration > 0) report_(summary.iteration);
    return ceres::SOLVER_CONTINUE;
  }

 private:
  const std::function<void(int)>& report_;
};

}  // namespace

WindowProblem::Outcome WindowProblem::solve(const SolverSettings& settings, int max_iterations,
                                            double uncertainty_tolerance) {
  ceres::Solver::Options solver = solver_options(settings, max_iterations);
  preparer_->set_threads(settings.threads);
  if (!z_.empty()) {
    // The window states are eliminated first (Schur complement): each appears in one
    // window only, so the reduced system is the size of x.
    solver.linear_solver_type = ceres::DENSE_SCHUR;
    auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
    for (std::size_t w = 0; w < windows_.size(); ++w)
      ordering->AddElementToGroup(z_.data() + 2 * w, 0);
    ordering->AddElementToGroup(x_.data(), 1);
    solver.linear_solver_ordering = ordering;
  }
  // Without the statistical stopping rule (the study's objective), the result must be the
  // best point seen: monotonic steps only.
  solver.use_nonmonotonic_steps = settings.nonmonotonic_steps && uncertainty_tolerance > 0;
  PredictedStepCheck check(*this, uncertainty_tolerance, settings);
  // The report first: Ceres calls no further callback after one that ends the solve.
  IterationReport report(settings.on_iteration);
  StopCheck stop(settings.stop_requested);
  solver.callbacks.push_back(&stop);
  if (settings.on_iteration) solver.callbacks.push_back(&report);
  solver.callbacks.push_back(&check);
  ceres::Solver::Summary summary;
  ceres::Solve(solver, problem_.get(), &summary);
  trace_summary(summary);
  stop.throw_if_stopped("the window fit");
  Outcome outcome;
  outcome.usable = summary.IsSolutionUsable();
  outcome.converged = converged(summary);
  outcome.iterations = static_cast<int>(summary.iterations.size()) - 1;
  outcome.initial_cost = summary.initial_cost;
  outcome.final_cost = summary.final_cost;
  outcome.termination = termination_text(summary);
  if (summary.termination_type == ceres::USER_SUCCESS)
    outcome.termination = "CONVERGENCE: " + check.reason();
  return outcome;
}

int WindowProblem::first_non_finite_window() const {
  const bool states = estimates_states();
  std::vector<double> residuals;
  for (std::size_t w = 0; w < windows_.size(); ++w) {
    const double* blocks[2] = {x_.data(), states ? z_.data() + 2 * w : nullptr};
    residuals.assign(static_cast<std::size_t>(costs_[w]->num_residuals()), 0.0);
    if (!costs_[w]->Evaluate(blocks, residuals.data(), nullptr)) return static_cast<int>(w);
    for (double r : residuals) {
      if (!std::isfinite(r)) return static_cast<int>(w);
    }
  }
  return -1;
}

bool WindowProblem::reduce(bool cached_only, ReducedSystem& out) const {
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  const int p = static_cast<int>(x_.size());
  const bool states = estimates_states();
  out = ReducedSystem{};
  out.information = Eigen::MatrixXd::Zero(p, p);
  out.gradient = Eigen::VectorXd::Zero(p);
  out.window_information.reserve(windows_.size());
  out.window_scores.reserve(windows_.size());
  out.windows = static_cast<int>(windows_.size());
  out.window_parameters = static_cast<int>(z_.size());
  if (!cached_only) preparer_->prepare_here(/*jacobians=*/true);
  for (std::size_t w = 0; w < windows_.size(); ++w) {
    const double* blocks[2] = {x_.data(), states ? z_.data() + 2 * w : nullptr};
    if (cached_only && !costs_[w]->cached_at(blocks)) return false;
    const std::vector<double>* residuals = nullptr;
    const std::vector<std::vector<double>>* jacobians = nullptr;
    if (!costs_[w]->evaluate_at(blocks, &residuals, &jacobians)) return false;
    const int count = static_cast<int>(residuals->size());
    const Eigen::Map<const RowMajor> a((*jacobians)[0].data(), count, p);
    const Eigen::Map<const Eigen::VectorXd> r(residuals->data(), count);
    Eigen::VectorXd score = a.transpose() * r;
    Eigen::MatrixXd information = a.transpose() * a;
    if (states) {
      const Eigen::Map<const RowMajor> b((*jacobians)[1].data(), count, 2);
      const Eigen::Matrix2d btb_inverse = (b.transpose() * b).inverse();
      const Eigen::MatrixXd bta = b.transpose() * a;
      information -= bta.transpose() * btb_inverse * bta;
      score -= bta.transpose() * (btb_inverse * (b.transpose() * r));
    }
    out.information += information;
    out.gradient += score;
    out.window_information.push_back(std::move(information));
    out.window_scores.push_back(std::move(score));
    out.sum_of_squares += r.squaredNorm();
    out.residuals += count;
  }
  for (const PriorResidual& prior : priors_) {
    const int k = prior.free_position;
    const double r = (x_[k] - prior.center_x) / prior.sigma_x;
    const double a = 1.0 / prior.sigma_x;
    out.information(k, k) += a * a;
    out.gradient(k) += a * r;
    out.sum_of_squares += r * r;
    out.residuals += 1;
  }
  return true;
}

namespace {

// The equation-error problem (analysis/fit/internal/fit_equation_error.h) over every sample of
// `data`, in chunks of 200 samples, on the free parameters `x` (bounds from the model). `x` and the
// arguments must outlive it; it does not move (the cost functions point into it).
class EquationErrorProblem {
 public:
  EquationErrorProblem(const DoorModel& model, const PreparedData& data, const ParameterMap& map,
                       const SolverSettings& options, std::vector<double>& x,
                       std::vector<std::vector<double>> rate_derivatives, double torque_scale_Nm)
      : preparer_(model, map, x.data()) {
    preparer_.set_threads(options.threads);
    setup_.model = &model;
    setup_.data = &data;
    setup_.map = &map;
    setup_.rate_derivative_rad_s2 = std::move(rate_derivatives);
    setup_.torque_scale_Nm = torque_scale_Nm;
    setup_.feasible = preparer_.flag();
    ceres::Problem::Options problem_options;
    problem_options.evaluation_callback = &preparer_;
    problem_ = std::make_unique<ceres::Problem>(problem_options);
    add_free_block(*problem_, x.data(), model, map);
    constexpr int kChunk = 200;
    for (std::size_t s = 0; s < data.strokes.size(); ++s) {
      const int n = static_cast<int>(data.strokes[s].size());
      for (int first = 0; first < n; first += kChunk) {
        const int count = std::min(kChunk, n - first);
        auto* cost =
            new CachingCost(make_equation_error_cost(setup_, static_cast<int>(s), first, count));
        data_blocks_.push_back(problem_->AddResidualBlock(cost, nullptr, x.data()));
        preparer_.add(cost, {x.data()});
        residuals_ += count;
      }
    }
  }
  EquationErrorProblem(const EquationErrorProblem&) = delete;
  EquationErrorProblem& operator=(const EquationErrorProblem&) = delete;

  ceres::Problem& problem() { return *problem_; }
  const std::vector<ceres::ResidualBlockId>& data_blocks() const { return data_blocks_; }
  int residuals() const { return residuals_; }

 private:
  EvaluationPreparer preparer_;
  EquationErrorSetup setup_;
  std::vector<ceres::ResidualBlockId> data_blocks_;
  int residuals_ = 0;
  std::unique_ptr<ceres::Problem> problem_;  // last: destroyed first
};

}  // namespace

EquationErrorOutcome solve_equation_error(const DoorModel& model, const PreparedData& data,
                                          const ParameterMap& map, const SolverSettings& options,
                                          std::vector<double> x0) {
  EquationErrorOutcome outcome;
  outcome.x = std::move(x0);
  EquationErrorProblem equation_error(model, data, map, options, outcome.x, rate_derivatives(data),
                                      1.0);
  ceres::Problem& problem = equation_error.problem();
  ceres::Solver::Options solver = solver_options(options, options.max_iterations);
  RelativeStepCheck check(outcome.x, options.equation_error_step_tolerance);
  StopCheck stop(options.stop_requested);
  solver.callbacks.push_back(&stop);
  solver.callbacks.push_back(&check);
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);
  trace_summary(summary);
  stop.throw_if_stopped("the equation-error fit");
  outcome.usable = summary.IsSolutionUsable();
  outcome.iterations = static_cast<int>(summary.iterations.size()) - 1;
  outcome.termination = summary.termination_type == ceres::USER_SUCCESS
                            ? "CONVERGENCE: two accepted steps changed no parameter by more than "
                              "equation_error_step_tolerance of its scale"
                            : termination_text(summary);
  return outcome;
}

TorqueMapOutcome solve_torque_map(const DoorModel& model, const PreparedData& data,
                                  const ParameterMap& map, const SolverSettings& options,
                                  std::vector<double> x0, const std::vector<PriorResidual>& priors,
                                  double torque_scale_Nm) {
  TorqueMapOutcome outcome;
  outcome.x = std::move(x0);
  std::vector<std::vector<double>> no_acceleration;  // J drops out
  for (const Stroke& stroke : data.strokes) no_acceleration.emplace_back(stroke.size(), 0.0);
  EquationErrorProblem torque_map(model, data, map, options, outcome.x, std::move(no_acceleration),
                                  torque_scale_Nm);
  ceres::Problem& problem = torque_map.problem();
  outcome.residuals = torque_map.residuals();
  if (!priors.empty()) {
    problem.AddResidualBlock(new PriorCost(priors, map.free_count()), nullptr, outcome.x.data());
  }
  // The commanded torque is exact (its best cost is ~0), so the fit's relative tolerances,
  // made for noisy data, are replaced by tight ones: the valley is followed to the end.
  ceres::Solver::Options solver = solver_options(options, std::max(options.max_iterations, 500));
  solver.function_tolerance = 1e-14;
  solver.parameter_tolerance = 1e-12;
  solver.gradient_tolerance = 1e-14;
  StopCheck stop(options.stop_requested);
  solver.callbacks.push_back(&stop);
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);
  trace_summary(summary);
  stop.throw_if_stopped("the commanded-torque fit");
  outcome.usable = summary.IsSolutionUsable();
  outcome.converged = summary.termination_type == ceres::CONVERGENCE;
  outcome.iterations = static_cast<int>(summary.iterations.size()) - 1;
  outcome.termination = termination_text(summary);
  if (!outcome.usable) return outcome;

  ceres::Problem::EvaluateOptions evaluate;
  evaluate.residual_blocks = torque_map.data_blocks();
  std::vector<double> residuals;
  problem.Evaluate(evaluate, nullptr, &residuals, nullptr, nullptr);
  for (double r : residuals) outcome.sum_of_squares += r * r;
  evaluate.residual_blocks.clear();  // every block: the priors' information too
  ceres::CRSMatrix jacobian;
  problem.Evaluate(evaluate, nullptr, nullptr, nullptr, &jacobian);
  const int p = map.free_count();
  outcome.information = Eigen::MatrixXd::Zero(p, p);
  Eigen::VectorXd row(p);
  for (int r = 0; r < jacobian.num_rows; ++r) {
    row.setZero();
    for (int k = jacobian.rows[r]; k < jacobian.rows[r + 1]; ++k) {
      row(jacobian.cols[k]) = jacobian.values[k];
    }
    outcome.information.selfadjointView<Eigen::Lower>().rankUpdate(row);
  }
  outcome.information = outcome.information.selfadjointView<Eigen::Lower>();
  return outcome;
}

double compare_with_ceres_covariance(WindowProblem& problem, const Eigen::MatrixXd& inverse,
                                     int num_threads) {
  const int p = static_cast<int>(problem.x().size());
  ceres::Covariance::Options options;
  options.algorithm_type = problem.estimates_states() ? ceres::SPARSE_QR : ceres::DENSE_SVD;
  options.num_threads = num_threads;
  ceres::Covariance covariance(options);
  std::vector<double> block(static_cast<std::size_t>(p) * p);
  const double* x = problem.x().data();
  if (!covariance.Compute(std::vector<const double*>{x}, &problem.problem()) ||
      !covariance.GetCovarianceBlock(x, x, block.data())) {
    return kNaN;
  }
  double largest = 0.0;
  for (int r = 0; r < p; ++r) {
    for (int c = 0; c < p; ++c) {
      const double scale = std::sqrt(inverse(r, r) * inverse(c, c));
      const double difference =
          std::abs(block[static_cast<std::size_t>(r) * p + c] - inverse(r, c));
      largest = std::max(largest, difference / scale);
    }
  }
  return largest;
}

}  // namespace doorbench
