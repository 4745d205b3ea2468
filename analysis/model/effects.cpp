#include "analysis/model/effects.h"

#include <stdexcept>

namespace doorbench::effects {
namespace {

constexpr EffectParameter kViscousDamping[] = {
    {{"b", "N*m*s/rad", "viscous damping"}, 0.0, {0.0, 5.0}, 0.0, false}};
constexpr EffectParameter kGravityImbalance[] = {
    {{"g1", "N*m", "net gravity torque amplitude (imperfect balance)"},
     0.0,
     {-30.0, 30.0},
     -1e300,
     false}};
constexpr EffectParameter kStribeck[] = {
    {{"d_s", "N*m", "breakaway (static) friction level"}, 3.0, {0.0, 20.0}, 0.0, false},
    {{"w_s", "rad/s", "Stribeck speed"}, 0.05, {0.001, 1.0}, 0.0, true}};
constexpr EffectParameter kDirectionFriction[] = {
    {{"d_dir", "N*m", "extra dry friction when opening"}, 0.0, {0.0, 10.0}, 0.0, false}};
constexpr EffectParameter kSoftClose[] = {
    {{"b_sc", "N*m*s/rad", "soft-close damping"}, 0.0, {0.0, 50.0}, 0.0, false},
    {{"theta_sc", "rad", "angle below which the damper acts"}, 0.1, {0.0, 0.5}, 0.0, false},
    {{"beta_sc", "1/rad", "sharpness of the damper's switch (the spec's beta_f)"},
     10.0,
     {1.0, 200.0},
     0.0,
     true}};
constexpr EffectParameter kEndStop[] = {
    {{"k_e", "N*m/rad", "limit stiffness"}, 0.0, {0.0, 100000.0}, 0.0, false},
    {{"theta_e", "rad", "angle where the limit begins"}, 1.5, {-0.1, 1.7}, -1e300, false},
    {{"beta_e", "1/rad", "sharpness of the limit's switch (the spec's beta)"},
     3000.0,
     {100.0, 20000.0},
     0.0,
     true}};
constexpr EffectParameter kForceOffset[] = {
    {{"F_off", "N", "load-cell offset: it reads F_u + F_off"}, 0.0, {-20.0, 20.0}, -1e300, false}};
constexpr EffectParameter kInertiaError[] = {
    {{"delta_J", "kg*m^2", "inertia error: J becomes J + delta_J"},
     0.0,
     {-0.5, 2.0},
     -1e300,
     false}};

const EffectInfo kCatalogue[kKindCount] = {
    {Kind::kViscousDamping, "viscous_damping", "- b * omega", true, kViscousDamping},
    {Kind::kGravityImbalance, "gravity_imbalance", "+ g1 * sin(theta)", true, kGravityImbalance},
    {Kind::kStribeck, "stribeck", "- (d_s - d1) * exp(-(omega/w_s)^2) * tanh(s*omega)", true,
     kStribeck},
    {Kind::kDirectionFriction, "direction_friction", "- d_dir * max(0, tanh(s*omega))", true,
     kDirectionFriction},
    {Kind::kSoftClose, "soft_close", "- b_sc * omega * Sbar(theta; theta_sc, beta_sc)", true,
     kSoftClose},
    {Kind::kEndStop, "end_stop", "- k_e * (theta - theta_e) * S(theta; theta_e, beta_e)", true,
     kEndStop},
    {Kind::kForceOffset, "force_offset", "- r_h * F_off", true, kForceOffset},
    {Kind::kInertiaError, "inertia_error", "J -> J + delta_J", false, kInertiaError},
};

}  // namespace

std::span<const EffectInfo> catalogue() {
  return kCatalogue;
}

const EffectInfo& info(Kind kind) {
  const int index = static_cast<int>(kind);
  if (index < 0 || index >= kKindCount) throw std::out_of_range("unknown effect kind");
  return kCatalogue[index];
}

std::optional<Kind> find(std::string_view name) {
  for (const EffectInfo& effect : kCatalogue) {
    if (effect.name == name) return effect.kind;
  }
  return std::nullopt;
}

}  // namespace doorbench::effects
