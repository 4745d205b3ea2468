#include "analysis/model/perceptual_controls.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "core/number_format.h"

namespace doorbench::perceptual {
namespace {

constexpr ControlInfo kControls[] = {
    {Control::kHeaviness, "heaviness", "kg*m^2", "inertia J"},
    {Control::kLatchEffort, "latch_effort", "N", "peak handle force to unlatch"},
    {Control::kClosingEffort, "closing_effort", "N", "peak handle force to latch"},
    {Control::kSnap, "snap", "N*m*s", "momentum the snap zone adds: c (theta2 - theta1)"},
    {Control::kSmoothness, "smoothness", "N", "dry friction at the handle when open: d1 / r_h"},
    {Control::kFrictionBalance, "friction_balance", "1",
     "d2 / d1: share of the friction that goes near closed"},
    {Control::kFrictionChange, "friction_change", "rad", "theta4: where the friction changes"},
};

void require_sensory(const DoorModel& model) {
  if (model.kind() != ModelKind::kSensory) {
    throw std::invalid_argument("perceptual controls act on the sensory model only");
  }
}

std::string_view name_of(Control control) {
  for (const ControlInfo& info : kControls) {
    if (info.control == control) return info.name;
  }
  return "?";
}

}  // namespace

std::span<const ControlInfo> controls() {
  return kControls;
}

std::optional<Control> find(std::string_view name) {
  for (const ControlInfo& info : kControls) {
    if (info.name == name) return info.control;
  }
  return std::nullopt;
}

double read(const DoorModel& model, Control control) {
  require_sensory(model);
  const auto p = sensory::Parameters<double>::from(model.parameter_values().data());
  const double r_h = model.geometry().handle_radius_m;
  switch (control) {
    case Control::kHeaviness:
      return p.J;
    case Control::kLatchEffort:
      return (p.k * p.theta1 + p.k_inf * (p.theta1 - p.theta0)) / r_h;
    case Control::kClosingEffort:
      return p.k_lock * (p.theta3 - p.theta2) / r_h;
    case Control::kSnap:
      return p.c * (p.theta2 - p.theta1);
    case Control::kSmoothness:
      return p.d1 / r_h;
    case Control::kFrictionBalance:
      return p.d1 > 0 ? p.d2 / p.d1 : 0.0;
    case Control::kFrictionChange:
      return p.theta4;
  }
  return 0.0;
}

DoorModel set(const DoorModel& model, Control control, double value) {
  require_sensory(model);
  if (!std::isfinite(value)) {
    throw std::invalid_argument(std::string(name_of(control)) + " must be a finite number");
  }
  std::vector<double> values(model.parameter_values().begin(), model.parameter_values().end());
  const auto p = sensory::Parameters<double>::from(values.data());
  const double r_h = model.geometry().handle_radius_m;
  switch (control) {
    case Control::kHeaviness:
      values[sensory::kJ] = value;
      break;
    case Control::kLatchEffort: {
      const double soft_share_N = p.k * p.theta1 / r_h;
      if (value < soft_share_N) {
        throw std::invalid_argument("latch_effort " + format_number(value) +
                                    " N is below what the soft spring alone gives, k theta1 / r_h "
                                    "= " +
                                    format_number(soft_share_N) + " N");
      }
      values[sensory::kKInf] = (value * r_h - p.k * p.theta1) / (p.theta1 - p.theta0);
      break;
    }
    case Control::kClosingEffort:
      values[sensory::kKLock] = value * r_h / (p.theta3 - p.theta2);
      break;
    case Control::kSnap:
      values[sensory::kC] = value / (p.theta2 - p.theta1);
      break;
    case Control::kSmoothness: {
      const double ratio = p.d1 > 0 ? p.d2 / p.d1 : 0.0;
      values[sensory::kD1] = value * r_h;
      values[sensory::kD2] = ratio * value * r_h;
      break;
    }
    case Control::kFrictionBalance:
      if (value < 0 || value > 1) {
        throw std::invalid_argument("friction_balance " + format_number(value) +
                                    " is outside [0, 1] (d2 / d1 with d1 >= d2 >= 0)");
      }
      values[sensory::kD2] = value * p.d1;
      break;
    case Control::kFrictionChange:
      values[sensory::kTheta4] = value;
      break;
  }
  return model.with_parameter_values(std::move(values));
}

double snap_width_rad(const DoorModel& model) {
  require_sensory(model);
  const auto p = sensory::Parameters<double>::from(model.parameter_values().data());
  return p.theta2 - p.theta1;
}

DoorModel set_snap_width(const DoorModel& model, double width_rad) {
  require_sensory(model);
  std::vector<double> values(model.parameter_values().begin(), model.parameter_values().end());
  values[sensory::kTheta2] = values[sensory::kTheta1] + width_rad;
  return model.with_parameter_values(std::move(values));
}

}  // namespace doorbench::perceptual
