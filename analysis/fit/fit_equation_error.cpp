#include "analysis/fit/internal/fit_equation_error.h"

#include <ceres/dynamic_autodiff_cost_function.h>

#include "analysis/fit/fit_start.h"

namespace doorbench {

std::vector<std::vector<double>> rate_derivatives(const PreparedData& data) {
  std::vector<std::vector<double>> out;
  out.reserve(data.strokes.size());
  for (const Stroke& stroke : data.strokes) out.push_back(rate_derivative(stroke));
  return out;
}

namespace {

class EquationError {
 public:
  EquationError(const EquationErrorSetup& setup, int stroke, int first, int count)
      : setup_(setup), stroke_(stroke), first_(first), count_(count) {}

  template <typename T>
  __attribute__((flatten)) bool operator()(T const* const* blocks, T* residuals) const {
    if (setup_.feasible != nullptr && !*setup_.feasible) return false;
    T parameters[DoorModel::kMaxParameters];
    T terms[DoorModel::kMaxTerms];
    setup_.map->fill(blocks[0], parameters);
    const DoorModel& model = *setup_.model;
    const Stroke& stroke = setup_.data->strokes[stroke_];
    const std::vector<double>& acceleration = setup_.rate_derivative_rad_s2[stroke_];
    const T inertia = model.inertia(static_cast<const T*>(parameters));
    const double r_h = model.geometry().handle_radius_m;
    const double inverse_scale = 1.0 / setup_.torque_scale_Nm;
    for (int j = 0; j < count_; ++j) {
      const int i = first_ + j;
      const T torque = model.evaluate(static_cast<const T*>(parameters), T(stroke.theta_rad[i]),
                                      T(stroke.omega_rad_s[i]), terms);
      residuals[j] = (inertia * acceleration[i] - torque - r_h * stroke.force_N[i]) * inverse_scale;
    }
    return true;
  }

 private:
  const EquationErrorSetup& setup_;
  int stroke_, first_, count_;
};

template <int Stride>
ceres::CostFunction* make_cost(const EquationErrorSetup& setup, int stroke, int first, int count) {
  auto* cost = new ceres::DynamicAutoDiffCostFunction<EquationError, Stride>(
      new EquationError(setup, stroke, first, count));
  cost->AddParameterBlock(setup.map->free_count());
  cost->SetNumResiduals(count);
  return cost;
}

}  // namespace

ceres::CostFunction* make_equation_error_cost(const EquationErrorSetup& setup, int stroke,
                                              int first, int count) {
  const int free = setup.map->free_count();
  if (free <= 4) return make_cost<4>(setup, stroke, first, count);
  if (free <= 8) return make_cost<8>(setup, stroke, first, count);
  return make_cost<16>(setup, stroke, first, count);
}

}  // namespace doorbench
