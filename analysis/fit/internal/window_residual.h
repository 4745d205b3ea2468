#pragma once
// The window residual's functor (analysis/fit/fit_windows.h, make_window_cost) and its cost
// function for one Jet stride, internal to the fit. The strides are instantiated in two
// translation units (fit_windows.cpp: 4, 8 and 16; fit_windows_wide.cpp: 24), the longest
// compilations of the project, so that a fresh build runs them on two cores at once.
#include <ceres/dynamic_autodiff_cost_function.h>

#include "analysis/fit/fit_windows.h"

namespace doorbench::fit_detail {

// The window's residuals as a functor for ceres::DynamicAutoDiffCostFunction: the scaled
// free parameters, and the window's start-state offset z when it is estimated.
class WindowResidual {
 public:
  WindowResidual(const WindowResidualSetup& setup, const FitWindow& window)
      : setup_(setup), window_(window) {}

  // flatten: GCC inlines the whole integration, model and Jet arithmetic into one body; the
  // Jacobian costs 30% less than with its own inlining choices (measured).
  template <typename T>
  __attribute__((flatten)) bool operator()(T const* const* blocks, T* residuals) const {
    if (setup_.feasible != nullptr && !*setup_.feasible) return false;
    T parameters[DoorModel::kMaxParameters];
    setup_.map->fill(blocks[0], parameters);
    const Stroke& stroke = setup_.data->strokes[window_.stroke];
    const double rate_weight = 1.0 / setup_.rate_noise_rad_s;
    const double angle_weight = 1.0 / setup_.angle_noise_rad;
    const bool with_angle = setup_.angle_residuals;
    const int power = setup_.residual_power;
    auto shape = [power](T r) {
      if (power == 1) return r;
      using std::abs;
      const T magnitude = abs(r);
      for (int i = 1; i < power; ++i) r *= magnitude;
      return r;
    };
    T* out = residuals;
    T theta0(stroke.theta_rad[window_.first]);
    T omega0(stroke.omega_rad_s[window_.first]);
    if (setup_.estimate_start_state) {
      const T* z = blocks[1];
      theta0 += z[0] * setup_.angle_noise_rad;
      omega0 += z[1] * setup_.rate_noise_rad_s;
      *out++ = z[0];
      *out++ = z[1];
    }
    auto sink = [&](int j, const T& theta, const T& omega) {
      const int sample = window_.first + j;
      *out++ = shape((omega - stroke.omega_rad_s[sample]) * rate_weight);
      if (with_angle) *out++ = shape((theta - stroke.theta_rad[sample]) * angle_weight);
    };
    return integrate_window(*setup_.model, static_cast<const T*>(parameters), stroke, window_,
                            setup_.substeps_per_sample, theta0, omega0, sink);
  }

 private:
  const WindowResidualSetup& setup_;
  FitWindow window_;
};

template <int Stride>
ceres::CostFunction* make_cost(const WindowResidualSetup& setup, const FitWindow& window) {
  auto* cost = new ceres::DynamicAutoDiffCostFunction<WindowResidual, Stride>(
      new WindowResidual(setup, window));
  cost->AddParameterBlock(setup.map->free_count());
  if (setup.estimate_start_state) cost->AddParameterBlock(2);
  cost->SetNumResiduals(window_residual_count(setup, window));
  return cost;
}

// make_cost<24>, compiled on its own (fit_windows_wide.cpp).
ceres::CostFunction* make_wide_window_cost(const WindowResidualSetup& setup,
                                           const FitWindow& window);

}  // namespace doorbench::fit_detail
