#pragma once
// Multiple shooting on windows, the core of the fit (docs/fitting.md). Every stroke is cut
// into short windows; each window starts from the MEASURED state (θ, ω) at its first
// sample and is integrated over its samples under the measured force (linear between
// samples) by the classic 4th-order Runge–Kutta formula at a fixed sub-step of the
// sample interval. The integration is a template on the scalar, so that Ceres' Jets give
// the parameter Jacobians through the simulation.
//
// Why windows and not whole strokes: door-models.md §6. A whole stroke replayed open-loop
// diverges from the recording where the hand holds the door against the latch (0.2 N of
// force noise decides when it breaks through); a window restarts from the measured state.
#include <cmath>
#include <vector>

#include "analysis/model/door_model.h"
#include "analysis/preprocessing/strokes.h"

namespace ceres {
class CostFunction;
}

namespace doorbench {

// Samples first .. first + count − 1 of one stroke (count ≥ 2). The first sample is the
// window's start state; every later sample gets a residual.
struct FitWindow {
  int stroke = 0;  // index into PreparedData::strokes
  int first = 0;
  int count = 0;
};

struct WindowOptions {
  double window_s = 0.2;
  int substeps_per_sample = 2;
  // One window per stroke: the whole stroke replayed from its first state (the study's
  // objective; ill-posed as a fit, door-models.md §6).
  bool whole_strokes = false;
  // Windows that share no sample (the next starts one sample after the last ends), for
  // windows whose start state is estimated: every measurement then enters the fit once.
  bool disjoint = false;
  // Angles where the model's torque jumps (the end stops at 0 and θ_max, whose damping
  // switches on at contact): no window spans a sample interval in which the measured angle
  // crosses one of them while |ω| > cut_rate_rad_s at both ends. An impact makes the
  // residuals kinked functions of the parameters and Levenberg–Marquardt crawl; cut there,
  // the next window restarts from the state after the impact.
  std::vector<double> cut_angles_rad;
  double cut_rate_rad_s = 0.01;
};

// A time step longer than this many times the stroke's median step is a gap in the
// recording, as is every gap preprocessing marks (Stroke::gap_before).
inline constexpr double kWindowGapFactor = 5.0;

// The gaps of `stroke`, increasing: each sample i such that the recording has a gap between
// samples i − 1 and i (marked in Stroke::gap_before, or a step longer than kWindowGapFactor
// times the stroke's median step).
std::vector<int> stroke_gaps(const Stroke& stroke);

// Cuts every stroke into windows of window_s (measured on the stroke's clock). Consecutive
// windows share their boundary sample unless `disjoint`: the end of one window is the
// start state of the next, so every sample except a stroke's first is a residual exactly
// once. Impacts (see WindowOptions) end a piece: windows restart after them. A last piece
// shorter than half a window joins the window before it. Strokes with fewer than 2 samples
// give no window.
//
// Gaps cost windows, not strokes: the windows are laid over a gap as if its samples were
// there (a window still ends where window_s has passed on the clock), and every window that
// spans a gap (has the gap between two of its samples) is left out; the stroke's other
// windows are the same as without the gap. With whole_strokes a gap ends a piece as an
// impact does.
struct WindowSplit {
  std::vector<FitWindow> windows;      // the windows fitted
  std::vector<FitWindow> across_gaps;  // those left out: each spans a gap (stroke_gaps)
};
WindowSplit split_windows_and_gaps(const PreparedData& data, const WindowOptions& options);
std::vector<FitWindow> split_windows(const PreparedData& data, const WindowOptions& options);

// Where every model parameter's value comes from: a free parameter k is x[k] · scale[k]
// (the solver sees dimensionless x), stored at model index free_index[k]; every other
// parameter keeps base_values.
struct ParameterMap {
  std::vector<double> base_values;  // all parameters, in the model's order
  std::vector<int> free_index;
  std::vector<double> scale;

  int free_count() const { return static_cast<int>(free_index.size()); }

  // Fills all parameter_count() values of `full` from the scaled free values `x`.
  template <typename T>
  void fill(const T* x, T* full) const {
    for (std::size_t i = 0; i < base_values.size(); ++i) full[i] = T(base_values[i]);
    for (std::size_t k = 0; k < free_index.size(); ++k) full[free_index[k]] = x[k] * scale[k];
  }
  std::vector<double> values(const double* x) const;
  std::vector<double> scaled(const std::vector<double>& values) const;  // x of given values
};

namespace window_detail {
inline double scalar_part(double value) {
  return value;
}
template <typename Jet>
double scalar_part(const Jet& value) {
  return value.a;
}
}  // namespace window_detail

// A state beyond this rate (rad/s) means the integration has run away (a trial parameter
// set far off); the window reports failure instead of overflowing.
inline constexpr double kRunawayRate_rad_s = 1e3;

// Integrates `window` of `stroke` from the start state (theta0, omega0) with the model's
// parameters `parameters` (all of them, T = double or a ceres::Jet) and calls
// sink(j, θ, ω) at sample first + j for j = 1 .. count − 1. τ_u = r_h F_u (the model's
// handle radius) with F_u linear between samples; `substeps` classic RK4 steps per sample
// interval. Returns false when
// the state stops being finite or runs away.
template <typename T, typename Sink>
bool integrate_window(const DoorModel& model, const T* parameters, const Stroke& stroke,
                      const FitWindow& window, int substeps, const T& theta0, const T& omega0,
                      Sink&& sink) {
  const double handle_radius_m = model.geometry().handle_radius_m;
  T terms[DoorModel::kMaxTerms];
  const T inverse_inertia = T(1.0) / model.inertia(parameters);
  T theta = theta0;
  T omega = omega0;
  const double fraction = 1.0 / substeps;
  for (int j = 1; j < window.count; ++j) {
    const int k = window.first + j - 1;
    const double h = (stroke.time_s[k + 1] - stroke.time_s[k]) * fraction;
    const double half_h = 0.5 * h;
    const double sixth_h = h / 6.0;
    const double tau_k = handle_radius_m * stroke.force_N[k];
    const double tau_step =
        handle_radius_m * (stroke.force_N[k + 1] - stroke.force_N[k]) * fraction;
    for (int m = 0; m < substeps; ++m) {
      const double tau_start = tau_k + tau_step * m;
      const double tau_middle = tau_start + 0.5 * tau_step;
      const double tau_end = tau_start + tau_step;
      const T a1 = (model.evaluate(parameters, theta, omega, terms) + tau_start) * inverse_inertia;
      const T theta2 = theta + omega * half_h;
      const T omega2 = omega + a1 * half_h;
      const T a2 =
          (model.evaluate(parameters, theta2, omega2, terms) + tau_middle) * inverse_inertia;
      const T theta3 = theta + omega2 * half_h;
      const T omega3 = omega + a2 * half_h;
      const T a3 =
          (model.evaluate(parameters, theta3, omega3, terms) + tau_middle) * inverse_inertia;
      const T theta4 = theta + omega3 * h;
      const T omega4 = omega + a3 * h;
      const T a4 = (model.evaluate(parameters, theta4, omega4, terms) + tau_end) * inverse_inertia;
      theta += (omega + (omega2 + omega3) * 2.0 + omega4) * sixth_h;
      omega += (a1 + (a2 + a3) * 2.0 + a4) * sixth_h;
    }
    const double w = window_detail::scalar_part(omega);
    const double a = window_detail::scalar_part(theta);
    if (!std::isfinite(w) || !std::isfinite(a) || std::abs(w) > kRunawayRate_rad_s) return false;
    sink(j, theta, omega);
  }
  return true;
}

// What the window residuals need, shared by every window of one problem. Must outlive the
// cost functions made from it.
struct WindowResidualSetup {
  const DoorModel* model = nullptr;
  const PreparedData* data = nullptr;
  const ParameterMap* map = nullptr;
  int substeps_per_sample = 2;
  double rate_noise_rad_s = 1.0;  // σ_ω: rate residuals are divided by it
  double angle_noise_rad = 1.0;   // σ_θ
  bool angle_residuals = true;
  // Estimate each window's start state: a second parameter block z (2 values) puts the
  // start at (θ_meas + σ_θ z0, ω_meas + σ_ω z1), and z0, z1 are residuals too (the
  // measured start state with its noise as a prior). Otherwise the start is the measured
  // state.
  bool estimate_start_state = false;
  // Sample residuals r are returned as r·|r|^(power − 1): power 1 is least squares; a
  // larger power makes Σ r² the L_(2·power) norm, an approximation of the largest error.
  int residual_power = 1;
  // When set, the residuals fail to evaluate (the trial step is rejected) while *feasible
  // is false: the fit's check of the model's constraints sets it before each evaluation.
  const bool* feasible = nullptr;
};

// Residuals of one window: z0, z1 when the start state is estimated; then at each sample
// after the first (ω_sim − ω_meas)/σ_ω, each followed by (θ_sim − θ_meas)/σ_θ when
// angle_residuals.
int window_residual_count(const WindowResidualSetup& setup, const FitWindow& window);

// A ceres::DynamicAutoDiffCostFunction over the setup's scaled free parameters (one block)
// and, when the start state is estimated, the window's z (a second block of 2). The caller
// (usually a ceres::Problem) owns it.
ceres::CostFunction* make_window_cost(const WindowResidualSetup& setup, const FitWindow& window);

}  // namespace doorbench
