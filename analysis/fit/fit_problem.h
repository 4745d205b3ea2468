#pragma once
// The least-squares problems behind fit_model (analysis/fit/fitting.h), on Ceres: the window
// problem (multiple shooting, window start states optionally estimated), the
// equation-error problem, their stopping rules, and the Gauss–Newton system of the free
// parameters with the window states eliminated, from which the uncertainties follow.
// Internal to the fit; documented in docs/fitting.md.
#include <Eigen/Core>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "analysis/fit/fit_windows.h"
#include "analysis/model/door_model.h"
#include "analysis/preprocessing/strokes.h"
#include "core/stop_request.h"

namespace ceres {
class CostFunction;
class Problem;
}  // namespace ceres

namespace doorbench {

// What the solvers here need of the caller's options (fit_model's FitOptions, the
// commanded-torque fit's): Ceres' tolerances and iteration limit, the stopping rules' kind of
// uncertainty and the number of evaluation threads.
struct SolverSettings {
  int max_iterations = 100;
  double function_tolerance = 1e-6;
  double parameter_tolerance = 1e-8;
  double gradient_tolerance = 1e-10;
  // The equation-error stage's step rule (FitOptions::equation_error_step_tolerance).
  double equation_error_step_tolerance = 1e-2;
  // The predicted-step rule measures steps in the window-robust uncertainty (else classical).
  bool robust_uncertainty = true;
  // FitOptions::nonmonotonic_steps (taken only with the predicted-step rule).
  bool nonmonotonic_steps = true;
  // FitOptions::first_step_decrease: the predicted-step rule before the first step also asks
  // for a predicted cost decrease of at most 0.1 %.
  bool first_step_decrease = true;
  int threads = 1;  // evaluation threads, the caller's among them (>= 1)
  // Called after each solver iteration with the iterations of this solve so far, on the
  // solve's calling thread; may be empty.
  std::function<void(int iterations)> on_iteration;
  // Asked after each solver iteration (core/stop_request.h): true ends the solve there and it
  // throws StopRequested. May be empty.
  StopHook stop_requested;
};

// A prior on one free parameter in solver units: the residual (x_k − center_x) / sigma_x.
struct PriorResidual {
  int free_position = 0;  // k, the position in x
  double center_x = 0.0;
  double sigma_x = 1.0;
};

struct FitWeights {
  double rate_noise_rad_s = 1.0;  // σ_ω
  double angle_noise_rad = 1.0;   // σ_θ
  bool angle_residuals = true;
  // FitOptions::priors on free parameters (none: the problem is exactly the plain fit's).
  std::vector<PriorResidual> priors;
};

// How a window problem is posed.
struct ProblemKind {
  WindowOptions windows;
  bool estimate_start_states = false;
  int residual_power = 1;
};

// The Gauss–Newton system of the free parameters x at one point, the window states (when
// estimated) eliminated window by window: with J_w = [A_w B_w] (x and z columns) and
// P_w = I − B_w (B_wᵀB_w)⁻¹ B_wᵀ,
//   H = Σ_w A_wᵀ P_w A_w,  g_w = A_wᵀ P_w r_w,  g = Σ_w g_w.
struct ReducedSystem {
  Eigen::MatrixXd information;                      // H
  Eigen::VectorXd gradient;                         // g
  std::vector<Eigen::MatrixXd> window_information;  // H_w = A_wᵀ P_w A_w
  std::vector<Eigen::VectorXd> window_scores;       // g_w
  double sum_of_squares = 0.0;                      // Σ r²
  int residuals = 0;
  int windows = 0;
  int window_parameters = 0;  // 2 per window when the start states are estimated

  // σ² = SSR / (n − p), p counting the window states; NaN without degrees of freedom.
  double residual_variance() const;
};

// H's pseudo-inverse, computed in normalized coordinates (unit diagonal) so that the rank
// test does not depend on the parameters' units: an eigenvalue below kRankTolerance of
// the largest is a direction the data does not determine, and a parameter with more than
// kNullSpaceShare of such a direction is named undetermined.
struct InformationInverse {
  Eigen::MatrixXd inverse;
  int rank = 0;
  std::vector<char> undetermined;
};
inline constexpr double kRankTolerance = 1e-10;
inline constexpr double kNullSpaceShare = 0.1;
InformationInverse invert_information(const Eigen::MatrixXd& information);

// The window-robust covariance: the delete-one-window jackknife of the linearized
// estimate, (W − 1)/W Σ_w (d_w − d̄)(d_w − d̄)ᵀ with d_w = (H − H_w)⁻¹ g_w, the change of
// x when window w is left out (the cluster-robust "CR3" estimator). It holds when errors
// are correlated within a window (process noise, a start state's error) and, unlike the
// plain sandwich H⁻¹ (Σ g_w g_wᵀ) H⁻¹, does not understate the spread of parameters that
// a few windows determine (the closing latch is seen in one window per closing stroke).
// A window without which H loses rank contributes H⁺ g_w instead.
//
// effective_windows[k] = (Σ_w c_wk)² / Σ_w c_wk², c_wk = (d_wk − d̄_k)², is how many windows
// the spread of parameter k effectively rests on: with few (under 10), its robust
// uncertainty is itself uncertain (as a t-distribution's with that many degrees of freedom).
struct RobustCovariance {
  Eigen::MatrixXd covariance;
  Eigen::VectorXd effective_windows;
};
RobustCovariance robust_covariance(const ReducedSystem& system, const Eigen::MatrixXd& inverse);
// √ of the diagonal of the robust or the classical (σ² H⁺) covariance, in solver units.
Eigen::VectorXd standard_uncertainties(const ReducedSystem& system, bool robust);

// The identifiable free set at the optimum (docs/fitting.md, "Identifiable parameters"):
// the free parameters (indices into the system's rows, increasing) that, with the others
// held where they are, the data determine — none in a direction of H below kRankTolerance
// and each with a standard uncertainty (robust or classical, in solver units like x) at most
// relative_limit × |x|. Backward elimination: while one is not determined, the one of those
// with the largest part in the weakest eigenvector of the normalized H (the Jacobian's
// smallest singular vector) is dropped. Linearized at x: a refit of the set can move.
std::vector<int> identifiable_subset(const ReducedSystem& system, const Eigen::VectorXd& x,
                                     bool robust, double relative_limit);

class CachingCost;
class EvaluationPreparer;

// One least-squares problem over windows: a ceres::Problem with the scaled free
// parameters x (bounded by the parameter file's bounds) and, when the start states are
// estimated, each window's z. The model, data and map must outlive it.
class WindowProblem {
 public:
  WindowProblem(const DoorModel& model, const PreparedData& data, const ParameterMap& map,
                const ProblemKind& kind, const FitWeights& weights, std::vector<double> x0);
  ~WindowProblem();
  WindowProblem(const WindowProblem&) = delete;
  WindowProblem& operator=(const WindowProblem&) = delete;

  // Levenberg–Marquardt from the current x and z. Besides Ceres' own tests it stops when
  // the Gauss–Newton step predicts that no free parameter would move by more than
  // `uncertainty_tolerance` of its standard uncertainty (the kind settings name; before the
  // first step, also a predicted cost decrease of at most 0.1 % when settings ask it), or when
  // three accepted steps in a row moved none by more than that; 0 turns these tests off.
  struct Outcome {
    bool usable = false;
    bool converged = false;
    int iterations = 0;
    double initial_cost = 0.0;
    double final_cost = 0.0;
    std::string termination;
  };
  Outcome solve(const SolverSettings& settings, int max_iterations, double uncertainty_tolerance);

  // The reduced system at the current x and z (the priors' residuals included in H, g and
  // Σ r², as observations outside every window); from the Jacobians the solver last computed
  // when they were taken here, else evaluated now (unless cached_only). False when a
  // window cannot be evaluated (or, with cached_only, is not cached here).
  bool reduce(bool cached_only, ReducedSystem& out) const;

  // The first window whose residuals at the current x and z cannot be evaluated or are not
  // finite (a blow-up the solver could not start from); -1 when every window is finite.
  int first_non_finite_window() const;

  std::vector<double>& x() { return x_; }
  const std::vector<double>& x() const { return x_; }
  std::vector<double>& z() { return z_; }
  const std::vector<double>& z() const { return z_; }
  bool estimates_states() const { return !z_.empty(); }
  const std::vector<FitWindow>& windows() const { return windows_; }
  int residual_count() const;
  ceres::Problem& problem() { return *problem_; }

 private:
  ParameterMap map_;
  std::vector<double> x_;
  std::vector<double> z_;
  std::unique_ptr<EvaluationPreparer> preparer_;
  WindowResidualSetup setup_;
  std::vector<FitWindow> windows_;
  std::vector<CachingCost*> costs_;  // owned by the problem
  std::vector<PriorResidual> priors_;
  std::unique_ptr<ceres::Problem> problem_;  // last: destroyed first
};

// The equation-error stage (analysis/fit/internal/fit_equation_error.h) from x0; x holds the result
// when usable.
struct EquationErrorOutcome {
  bool usable = false;
  int iterations = 0;
  std::string termination;
  std::vector<double> x;
};
EquationErrorOutcome solve_equation_error(const DoorModel& model, const PreparedData& data,
                                          const ParameterMap& map, const SolverSettings& settings,
                                          std::vector<double> x0);

// The commanded-torque problem (analysis/fit/commanded_torque.h): the equation-error residuals
// with dω/dt = 0 on strokes whose force is −τ_cmd / r_h, i.e. (τ_cmd − τ_m(θ, ω)) /
// torque_scale at every sample, plus `priors`; solved to Ceres' own convergence from x0.
// `information` is JᵀJ at the result (priors included) in solver units, `sum_of_squares`
// the data residuals' Σ r² (priors excluded).
struct TorqueMapOutcome {
  bool usable = false;
  bool converged = false;
  int iterations = 0;
  std::string termination;
  std::vector<double> x;
  double sum_of_squares = 0.0;
  int residuals = 0;
  Eigen::MatrixXd information;
};
TorqueMapOutcome solve_torque_map(const DoorModel& model, const PreparedData& data,
                                  const ParameterMap& map, const SolverSettings& settings,
                                  std::vector<double> x0, const std::vector<PriorResidual>& priors,
                                  double torque_scale_Nm);

// The largest element-wise difference between ceres::Covariance's (JᵀJ)⁻¹ for x over the
// whole problem and `inverse`, relative to √(C_ii C_jj); NaN when Ceres cannot compute it.
double compare_with_ceres_covariance(WindowProblem& problem, const Eigen::MatrixXd& inverse,
                                     int num_threads);

// The solver's unit for a free parameter: its start's magnitude, or a tenth of its bounds'
// width when the start is (nearly) zero (analysis/fit/fitting.cpp).
double parameter_scale(double start, const Bounds& bounds);

}  // namespace doorbench
