#pragma once
// A door model: a base model (sensory or physical) plus a set of effects, with its
// parameter values and bounds. Constant after construction (the MuJoCo split: this is
// the model; the simulator holds the mutable state). Evaluating it never allocates.
//
// Thread safety: a DoorModel is immutable, so any number of threads may evaluate one
// concurrently.
#include <array>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "analysis/model/effects.h"
#include "analysis/model/parameters.h"
#include "analysis/model/physical_model.h"
#include "analysis/model/sensory_model.h"

namespace doorbench {

enum class ModelKind { kSensory, kPhysical };
std::string_view to_string(ModelKind kind);
std::optional<ModelKind> parse_model_kind(std::string_view text);

// One effect switched on, with its values and bounds in the catalogue's order.
struct EffectSetting {
  effects::Kind kind;
  std::vector<double> values;
  std::vector<Bounds> bounds;
};

struct TorqueDerivatives {
  double torque_Nm = 0.0;
  double dtorque_dtheta_Nm_per_rad = 0.0;
  double dtorque_domega_Nm_s_per_rad = 0.0;
};

class DoorModel {
 public:
  // Enough for the physical model with every effect of the catalogue.
  static constexpr int kMaxParameters = 48;
  static constexpr int kMaxTerms = 16;

  // Checks the geometry, every base constraint and every effect's values; throws
  // std::invalid_argument with a one-line message naming the parameter otherwise.
  DoorModel(ModelKind kind, const DoorGeometry& geometry, std::vector<double> base_values,
            std::vector<Bounds> base_bounds, std::vector<EffectSetting> effects = {});

  ModelKind kind() const { return kind_; }
  const DoorGeometry& geometry() const { return geometry_; }

  // All parameters, base first then each effect's, with names such as "k_inf" and
  // "stribeck.d_s".
  int parameter_count() const { return static_cast<int>(values_.size()); }
  std::span<const double> parameter_values() const { return values_; }
  std::span<const Bounds> parameter_bounds() const { return bounds_; }
  const std::string& parameter_name(int index) const { return names_.at(index); }
  std::string_view parameter_unit(int index) const { return units_.at(index); }
  std::optional<int> find_parameter(std::string_view name) const;
  int base_parameter_count() const { return base_parameter_count_; }
  std::span<const EffectSetting> effects() const { return effects_; }
  bool has_effect(effects::Kind kind) const;
  // The parameter that sets how sharp the latch's switches are, or none: the sensory model's
  // beta (each switch turns over about 1/beta rad). A smaller value spreads every switch over
  // more angle, and the window cost over the latch angles is smoother. The physical model
  // has none.
  std::optional<int> switch_sharpness_index() const;

  // Terms: the base model's, then one per torque-adding effect.
  int term_count() const { return static_cast<int>(term_names_.size()); }
  const std::string& term_name(int index) const { return term_names_.at(index); }

  // The same model with other parameter values (checked as in the constructor).
  DoorModel with_parameter_values(std::vector<double> values) const;
  // The same model with one more effect (or its values replaced).
  DoorModel with_effect(EffectSetting effect) const;

  // J, including an inertia error when that effect is on.
  double inertia_kg_m2() const { return inertia(values_.data()); }

  // τ_m(θ, ω) in N*m, positive = opening.
  double torque_Nm(double theta_rad, double omega_rad_s) const;
  // τ_m and each term's contribution; `terms` must hold term_count() values.
  double torque_Nm(double theta_rad, double omega_rad_s, std::span<double> terms) const;
  // τ_m with ∂τ/∂θ and ∂τ/∂ω (forward-mode automatic differentiation).
  TorqueDerivatives torque_derivatives(double theta_rad, double omega_rad_s) const;

  // The generic evaluation for any scalar T (double or a Ceres Jet), over a parameter
  // array laid out as parameter_values(). Writes term_count() terms, returns τ_m.
  template <typename T>
  T evaluate(const T* parameters, const T& theta, const T& omega, T* terms) const;
  template <typename T>
  T inertia(const T* parameters) const;

 private:
  // `shape`: the physical latch's parameter-only values for `parameters` (the cache when
  // they are values_), or null to compute them here (any other parameter array).
  template <typename T>
  T evaluate_with(const T* parameters, const physical::LatchShape<T>* shape, const T& theta,
                  const T& omega, T* terms) const;

  struct ActiveEffect {
    effects::Kind kind;
    int parameter_offset;
    int term_index;  // −1 when it adds no torque
  };

  ModelKind kind_;
  DoorGeometry geometry_;
  int base_parameter_count_ = 0;
  int base_term_count_ = 0;
  std::vector<double> values_;
  std::vector<Bounds> bounds_;
  std::vector<std::string> names_;
  std::vector<std::string_view> units_;
  std::vector<std::string> term_names_;
  std::vector<EffectSetting> effects_;
  std::vector<ActiveEffect> active_;
  int inertia_error_offset_ = -1;
  // For the physical model: latch_shape(values_), computed once in the constructor so that
  // torque_Nm does not take tan per call (the values never change after it).
  physical::LatchShape<double> latch_shape_{};
  // The same computed in Ceres Jet arithmetic (its division multiplies by the reciprocal,
  // so the last bit can differ): what torque_derivatives used before the cache.
  physical::LatchShape<double> latch_shape_jet_{};
};

template <typename T>
T DoorModel::evaluate(const T* parameters, const T& theta, const T& omega, T* terms) const {
  return evaluate_with<T>(parameters, nullptr, theta, omega, terms);
}

template <typename T>
T DoorModel::evaluate_with(const T* parameters, const physical::LatchShape<T>* shape,
                           const T& theta, const T& omega, T* terms) const {
  T total;
  effects::BaseFriction<T> friction;
  if (kind_ == ModelKind::kSensory) {
    total = sensory::evaluate(parameters, geometry_.theta_max_rad, theta, omega, terms);
    friction = {parameters[sensory::kD1], parameters[sensory::kS]};
  } else {
    total =
        shape ? physical::evaluate(parameters, *shape, geometry_.theta_max_rad, theta, omega, terms)
              : physical::evaluate(parameters, geometry_.theta_max_rad, theta, omega, terms);
    friction = {parameters[physical::kTh], T(1.0) / parameters[physical::kWf]};
  }
  for (const ActiveEffect& effect : active_) {
    if (effect.term_index < 0) continue;
    const T term = effects::torque(effect.kind, parameters + effect.parameter_offset, friction,
                                   geometry_.handle_radius_m, theta, omega);
    terms[effect.term_index] = term;
    total += term;
  }
  return total;
}

template <typename T>
T DoorModel::inertia(const T* parameters) const {
  const T base = kind_ == ModelKind::kSensory ? parameters[sensory::kJ] : parameters[physical::kJd];
  return inertia_error_offset_ < 0 ? base : base + parameters[inertia_error_offset_];
}

// "" when each of `names` is a parameter of `model`; else, for the first that is not, "WHAT:
// the KIND model has no parameter 'NAME' (its parameters: J, k, ...)" (`what` names where the
// names came from, e.g. "--free").
std::string unknown_parameter_problem(const DoorModel& model, const std::string& what,
                                      const std::vector<std::string>& names);

}  // namespace doorbench
