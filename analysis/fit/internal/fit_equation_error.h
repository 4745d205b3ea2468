#pragma once
// The equation-error (inverse-dynamics) stage of the fit (docs/fitting.md, "The start").
// Before the windows are simulated, the equation of motion is fitted as it stands at every
// sample, with dω/dt taken from the data:
//
//   e_i = J dω/dt_i − r_h F_i − τ_m(θ_i, ω_i)
//
// No simulation is involved, so one evaluation costs one model evaluation per sample (the
// windows cost 8), and the cost has no divergent replays in it: it is a cheap, robust way
// to bring parameters that start far off (30 %) close to the windows' optimum. Its own
// optimum is biased (dω/dt is smoothed over ±5 ms, and θ and ω are noisy regressors),
// which the window fit then removes.
#include <vector>

#include "analysis/model/door_model.h"
#include "analysis/fit/fit_windows.h"
#include "analysis/preprocessing/strokes.h"

namespace ceres {
class CostFunction;
}

namespace doorbench {

// Must outlive the cost functions made from it.
struct EquationErrorSetup {
  const DoorModel* model = nullptr;
  const PreparedData* data = nullptr;
  const ParameterMap* map = nullptr;
  std::vector<std::vector<double>> rate_derivative_rad_s2;  // per stroke, per sample
  double torque_scale_Nm = 1.0;                             // residuals are e_i / this
  const bool* feasible = nullptr;                           // as in WindowResidualSetup
};

// dω/dt of every stroke (central differences over ±5 ms).
std::vector<std::vector<double>> rate_derivatives(const PreparedData& data);

// Residuals e_i / torque_scale at samples first .. first + count − 1 of one stroke, over
// one parameter block (the scaled free parameters). The caller owns it.
ceres::CostFunction* make_equation_error_cost(const EquationErrorSetup& setup, int stroke,
                                              int first, int count);

}  // namespace doorbench
