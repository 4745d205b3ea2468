#pragma once
// The catalogue of extra effects (door-models.md §4) that the residual loop may add
// to a base model. Each effect owns its parameters and bounds and is off unless named.
#include <array>
#include <optional>
#include <span>
#include <string_view>

#include "analysis/model/parameters.h"
#include "analysis/model/switches.h"

namespace doorbench::effects {

enum class Kind : int {
  kViscousDamping,
  kGravityImbalance,
  kStribeck,
  kDirectionFriction,
  kSoftClose,
  kEndStop,
  kForceOffset,
  kInertiaError,
};
inline constexpr int kKindCount = 8;

struct EffectParameter {
  ParameterInfo info;
  double default_value;
  Bounds default_bounds;
  double minimum;          // values below are rejected
  bool minimum_is_strict;  // reject == minimum too
};

struct EffectInfo {
  Kind kind;
  std::string_view name;     // as written in effects files and `tau_<name>_Nm` columns
  std::string_view formula;  // the torque it adds, in the spec's notation
  bool adds_torque;          // false for the inertia error, which changes J instead
  std::span<const EffectParameter> parameters;
};

// The catalogue, in the order above.
std::span<const EffectInfo> catalogue();
const EffectInfo& info(Kind kind);
std::optional<Kind> find(std::string_view name);

// What an effect may borrow from its base model: the kinetic dry-friction level d1
// (N*m) and its speed sensitivity s (s/rad). For the sensory model these are d1 and s;
// for the physical model the hinge's Coulomb friction T_h and 1/w_f.
template <typename T>
struct BaseFriction {
  T level_Nm;
  T speed_sensitivity_s_per_rad;
};

// The torque (N*m, positive = opening) of one effect with parameter values `p`.
template <typename T>
T torque(Kind kind, const T* p, const BaseFriction<T>& base, double handle_radius_m, const T& theta,
         const T& omega) {
  using std::exp;
  using std::sin;
  using std::tanh;
  switch (kind) {
    case Kind::kViscousDamping:  // − b ω
      return -p[0] * omega;
    case Kind::kGravityImbalance:  // + g1 sin θ
      return p[0] * sin(theta);
    case Kind::kStribeck: {  // − (d_s − d1) exp(−(ω/w_s)²) tanh(s ω)
      const T ratio = omega / p[1];
      return -(p[0] - base.level_Nm) * exp_minus(ratio * ratio) *
             tanh(base.speed_sensitivity_s_per_rad * omega);
    }
    case Kind::kDirectionFriction: {  // − d_dir max(0, tanh(s ω))
      const T shape = tanh(base.speed_sensitivity_s_per_rad * omega);
      return shape > T(0.0) ? -p[0] * shape : T(0.0);
    }
    case Kind::kSoftClose:  // − b_sc ω S̄(θ; θ_sc, β_sc)
      return -p[0] * omega * switch_off(theta, p[1], p[2]);
    case Kind::kEndStop:  // − k_e (θ − θ_e) S(θ; θ_e, β_e)
      return -p[0] * (theta - p[1]) * switch_on(theta, p[1], p[2]);
    case Kind::kForceOffset:  // the door feels r_h (F_measured − F_off)
      return -T(handle_radius_m) * p[0];
    case Kind::kInertiaError:
      return T(0.0);
  }
  return T(0.0);
}

}  // namespace doorbench::effects
