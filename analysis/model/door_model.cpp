#include "analysis/model/door_model.h"

#include <ceres/jet.h>

#include <stdexcept>

#include "analysis/model/constraint_check.h"
#include "core/number_format.h"

namespace doorbench {

std::string validate_geometry(const DoorGeometry& geometry) {
  ConstraintCheck check("door");
  check.finite("handle_radius_m", geometry.handle_radius_m);
  check.finite("theta_max_rad", geometry.theta_max_rad);
  check.require(geometry.handle_radius_m > 0, "handle_radius_m", geometry.handle_radius_m,
                "handle_radius_m > 0");
  check.require(geometry.theta_max_rad > 0, "theta_max_rad", geometry.theta_max_rad,
                "theta_max_rad > 0");
  return check.message();
}

std::string_view to_string(ModelKind kind) {
  return kind == ModelKind::kSensory ? "sensory" : "physical";
}

std::optional<ModelKind> parse_model_kind(std::string_view text) {
  if (text == "sensory") return ModelKind::kSensory;
  if (text == "physical") return ModelKind::kPhysical;
  return std::nullopt;
}

namespace {

template <std::size_t N>
std::string validate_base(const std::vector<double>& values, const DoorGeometry& geometry,
                          std::string (*validate)(const std::array<double, N>&,
                                                  const DoorGeometry&)) {
  std::array<double, N> fixed{};
  std::copy(values.begin(), values.end(), fixed.begin());
  return validate(fixed, geometry);
}

std::string validate_effect(const EffectSetting& effect) {
  const effects::EffectInfo& info = effects::info(effect.kind);
  const std::string effect_name(info.name);
  if (effect.values.size() != info.parameters.size() ||
      effect.bounds.size() != info.parameters.size()) {
    return "effect " + effect_name + " needs " + std::to_string(info.parameters.size()) +
           " parameter values and bounds";
  }
  ConstraintCheck check("effect");
  for (std::size_t i = 0; i < info.parameters.size(); ++i) {
    const effects::EffectParameter& parameter = info.parameters[i];
    const std::string name = effect_name + "." + std::string(parameter.info.name);
    const double value = effect.values[i];
    check.finite(name, value);
    if (parameter.minimum > -1e300) {
      const std::string op = parameter.minimum_is_strict ? " > " : " >= ";
      const bool holds =
          parameter.minimum_is_strict ? value > parameter.minimum : value >= parameter.minimum;
      check.require(holds, name, value, name + op + format_number(parameter.minimum));
    }
  }
  return check.message();
}

}  // namespace

DoorModel::DoorModel(ModelKind kind, const DoorGeometry& geometry, std::vector<double> base_values,
                     std::vector<Bounds> base_bounds, std::vector<EffectSetting> effects)
    : kind_(kind), geometry_(geometry), effects_(std::move(effects)) {
  const bool sensory_model = kind == ModelKind::kSensory;
  base_parameter_count_ =
      sensory_model ? int{sensory::kParameterCount} : int{physical::kParameterCount};
  base_term_count_ = sensory_model ? int{sensory::kTermCount} : int{physical::kTermCount};
  if (static_cast<int>(base_values.size()) != base_parameter_count_ ||
      static_cast<int>(base_bounds.size()) != base_parameter_count_) {
    throw std::invalid_argument(
        std::string(to_string(kind)) + " model needs " + std::to_string(base_parameter_count_) +
        " parameter values and bounds, got " + std::to_string(base_values.size()));
  }
  const std::string message = sensory_model
                                  ? validate_base(base_values, geometry, &sensory::validate)
                                  : validate_base(base_values, geometry, &physical::validate);
  if (!message.empty()) throw std::invalid_argument(message);

  values_ = std::move(base_values);
  bounds_ = std::move(base_bounds);
  for (int i = 0; i < base_parameter_count_; ++i) {
    const ParameterInfo& info =
        sensory_model ? sensory::kParameterInfo[i] : physical::kParameterInfo[i];
    names_.emplace_back(info.name);
    units_.push_back(info.unit);
  }
  for (int i = 0; i < base_term_count_; ++i) {
    term_names_.emplace_back(sensory_model ? sensory::kTermNames[i] : physical::kTermNames[i]);
  }

  for (std::size_t e = 0; e < effects_.size(); ++e) {
    const EffectSetting& effect = effects_[e];
    for (std::size_t other = 0; other < e; ++other) {
      if (effects_[other].kind == effect.kind) {
        throw std::invalid_argument("effect " + std::string(effects::info(effect.kind).name) +
                                    " is switched on twice");
      }
    }
    if (std::string problem = validate_effect(effect); !problem.empty()) {
      throw std::invalid_argument(problem);
    }
    const effects::EffectInfo& info = effects::info(effect.kind);
    ActiveEffect active{effect.kind, static_cast<int>(values_.size()), -1};
    if (info.adds_torque) {
      active.term_index = static_cast<int>(term_names_.size());
      term_names_.emplace_back(info.name);
    }
    if (effect.kind == effects::Kind::kInertiaError)
      inertia_error_offset_ = active.parameter_offset;
    for (std::size_t i = 0; i < info.parameters.size(); ++i) {
      values_.push_back(effect.values[i]);
      bounds_.push_back(effect.bounds[i]);
      names_.push_back(std::string(info.name) + "." + std::string(info.parameters[i].info.name));
      units_.push_back(info.parameters[i].info.unit);
    }
    active_.push_back(active);
  }
  if (values_.size() > kMaxParameters || term_names_.size() > kMaxTerms) {
    throw std::invalid_argument("model has more parameters or terms than DoorModel supports");
  }
  if (inertia(values_.data()) <= 0) {
    throw std::invalid_argument(
        "effect inertia_error.delta_J = " + format_number(values_[inertia_error_offset_]) +
        " makes the inertia J + delta_J not positive");
  }
  if (!sensory_model) {
    latch_shape_ = physical::latch_shape(physical::Parameters<double>::from(values_.data()));
    using StateJet = ceres::Jet<double, 2>;
    std::array<StateJet, physical::kParameterCount> jets;
    for (int i = 0; i < physical::kParameterCount; ++i) jets[i] = StateJet(values_[i]);
    const auto shape = physical::latch_shape(physical::Parameters<StateJet>::from(jets.data()));
    latch_shape_jet_ = {shape.tan_o.a, shape.tan_c.a, shape.x1.a, shape.x2.a};
  }
}

std::optional<int> DoorModel::find_parameter(std::string_view name) const {
  for (int i = 0; i < parameter_count(); ++i) {
    if (names_[i] == name) return i;
  }
  return std::nullopt;
}

std::optional<int> DoorModel::switch_sharpness_index() const {
  if (kind_ == ModelKind::kSensory) return sensory::kBeta;
  return std::nullopt;
}

bool DoorModel::has_effect(effects::Kind kind) const {
  for (const EffectSetting& effect : effects_) {
    if (effect.kind == kind) return true;
  }
  return false;
}

DoorModel DoorModel::with_parameter_values(std::vector<double> values) const {
  if (static_cast<int>(values.size()) != parameter_count()) {
    throw std::invalid_argument("expected " + std::to_string(parameter_count()) +
                                " parameter values, got " + std::to_string(values.size()));
  }
  std::vector<double> base(values.begin(), values.begin() + base_parameter_count_);
  std::vector<Bounds> base_bounds(bounds_.begin(), bounds_.begin() + base_parameter_count_);
  std::vector<EffectSetting> effects = effects_;
  for (std::size_t e = 0; e < effects.size(); ++e) {
    const int offset = active_[e].parameter_offset;
    for (std::size_t i = 0; i < effects[e].values.size(); ++i) {
      effects[e].values[i] = values[offset + i];
    }
  }
  return DoorModel(kind_, geometry_, std::move(base), std::move(base_bounds), std::move(effects));
}

DoorModel DoorModel::with_effect(EffectSetting effect) const {
  std::vector<double> base(values_.begin(), values_.begin() + base_parameter_count_);
  std::vector<Bounds> base_bounds(bounds_.begin(), bounds_.begin() + base_parameter_count_);
  std::vector<EffectSetting> effects = effects_;
  bool replaced = false;
  for (EffectSetting& existing : effects) {
    if (existing.kind == effect.kind) {
      existing = effect;
      replaced = true;
    }
  }
  if (!replaced) effects.push_back(std::move(effect));
  return DoorModel(kind_, geometry_, std::move(base), std::move(base_bounds), std::move(effects));
}

double DoorModel::torque_Nm(double theta_rad, double omega_rad_s) const {
  std::array<double, kMaxTerms> terms;
  return evaluate_with(values_.data(), &latch_shape_, theta_rad, omega_rad_s, terms.data());
}

double DoorModel::torque_Nm(double theta_rad, double omega_rad_s, std::span<double> terms) const {
  if (static_cast<int>(terms.size()) < term_count()) {
    throw std::invalid_argument("torque_Nm: terms holds " + std::to_string(terms.size()) +
                                " values, the model has " + std::to_string(term_count()) +
                                " terms");
  }
  return evaluate_with(values_.data(), &latch_shape_, theta_rad, omega_rad_s, terms.data());
}

TorqueDerivatives DoorModel::torque_derivatives(double theta_rad, double omega_rad_s) const {
  using StateJet = ceres::Jet<double, 2>;
  std::array<StateJet, kMaxParameters> parameters;
  for (int i = 0; i < parameter_count(); ++i) parameters[i] = StateJet(values_[i]);
  std::array<StateJet, kMaxTerms> terms;
  // The parameters are constants here (no derivative part): the cached shape is exactly
  // what the Jet arithmetic would compute per call.
  const physical::LatchShape<StateJet> shape{
      StateJet(latch_shape_jet_.tan_o), StateJet(latch_shape_jet_.tan_c),
      StateJet(latch_shape_jet_.x1), StateJet(latch_shape_jet_.x2)};
  const StateJet torque = evaluate_with(parameters.data(), &shape, StateJet(theta_rad, 0),
                                        StateJet(omega_rad_s, 1), terms.data());
  return {torque.a, torque.v[0], torque.v[1]};
}

std::string unknown_parameter_problem(const DoorModel& model, const std::string& what,
                                      const std::vector<std::string>& names) {
  for (const std::string& name : names) {
    if (model.find_parameter(name)) continue;
    std::string list;
    for (int i = 0; i < model.parameter_count(); ++i) {
      list += (i > 0 ? ", " : "") + model.parameter_name(i);
    }
    return what + ": the " + std::string(to_string(model.kind())) + " model has no parameter '" +
           name + "' (its parameters: " + list + ")";
  }
  return "";
}

}  // namespace doorbench
