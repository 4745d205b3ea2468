// DoorModel::torque_derivatives (∂τ/∂θ, ∂τ/∂ω) and the Ceres Jet evaluation's parameter
// derivatives, against central finite differences of the plain torque.
#include <ceres/jet.h>

#include <algorithm>
#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <string>
#include <vector>

#include "analysis/model/door_model.h"
#include "analysis/model/parameter_file.h"

using Catch::Matchers::WithinAbs;
using Catch::Matchers::WithinRel;
using doorbench::DoorModel;
using doorbench::ModelKind;

namespace {

DoorModel sensory_with_effects() {
  DoorModel model = doorbench::reference_model(ModelKind::kSensory);
  for (auto& setting : doorbench::parse_effects_file(
           R"({"viscous_damping": {"b": 0.3}, "gravity_imbalance": {"g1": 1.5},
               "stribeck": {"d_s": 3.4, "w_s": 0.04}, "direction_friction": {"d_dir": 0.5},
               "soft_close": {"b_sc": 4, "theta_sc": 0.05, "beta_sc": 40},
               "end_stop": {"k_e": 800, "theta_e": 1.4, "beta_e": 300},
               "force_offset": {"F_off": 1.2}, "inertia_error": {"delta_J": 0.1}})",
           "effects.json")) {
    model = model.with_effect(std::move(setting));
  }
  return model;
}

DoorModel physical_with_effects() {
  DoorModel model = doorbench::reference_model(ModelKind::kPhysical);
  for (auto& setting : doorbench::parse_effects_file(
           R"({"stribeck": {"d_s": 1.1, "w_s": 0.03}, "viscous_damping": {"b": 0.2},
               "soft_close": {"b_sc": 4, "theta_sc": 0.05, "beta_sc": 40}})",
           "effects.json")) {
    model = model.with_effect(std::move(setting));
  }
  return model;
}

// The latch switches are 4/β = 0.0013 rad (sensory) and 4 e / r_l = 0.002 rad (physical)
// wide, with curvature on the scale of 1/β = 3.3e−4 rad: there a step of 1e−7 keeps the
// truncation error (h²/6 · f‴) near 1e−7 relative while roundoff (ε |τ| / h) stays below
// 1e−7 absolute. Elsewhere the torque varies on the scale of 1/β_f = 0.1 rad or more.
double theta_step(double theta) {
  return (theta > -0.01 && theta < 0.08) ? 1e-7 : 1e-6;
}
// Friction varies on the scale of w_f = 0.02 rad/s (and 1/s = 0.04, w_s ≥ 0.03).
constexpr double kOmegaStep = 1e-7;

// The angles: both sides of each latch angle and of the physical cam's corners, avoiding
// the true kinks (the stops at 0 and θ_max, the seal at 0.01) by ≥ 1000 steps.
const std::vector<double> kThetas = {-0.02,  -0.003, 0.002, 0.0045,  0.00698, 0.008,  0.0115,
                                     0.0125, 0.016,  0.02,  0.026,   0.02793, 0.0298, 0.031,
                                     0.0355, 0.0384, 0.045, 0.06109, 0.065,   0.09,   0.3,
                                     0.6109, 1.0,    1.3,   1.41,    1.5,     1.6};
const std::vector<double> kOmegas = {-0.8, -0.05, -0.012, 0.003, 0.02, 0.3, 1.2};

void check_state_derivatives(const DoorModel& model) {
  int checked = 0;
  for (double theta : kThetas) {
    for (double omega : kOmegas) {
      const double h = theta_step(theta);
      const doorbench::TorqueDerivatives d = model.torque_derivatives(theta, omega);
      const double torque = model.torque_Nm(theta, omega);
      const double fd_theta =
          (model.torque_Nm(theta + h, omega) - model.torque_Nm(theta - h, omega)) / (2 * h);
      const double fd_omega = (model.torque_Nm(theta, omega + kOmegaStep) -
                               model.torque_Nm(theta, omega - kOmegaStep)) /
                              (2 * kOmegaStep);
      INFO("theta = " << theta << ", omega = " << omega << ", torque = " << torque);
      // Jet arithmetic rounds differently (it divides by multiplying with 1/b).
      CHECK_THAT(d.torque_Nm, WithinAbs(torque, 1e-13 * (1.0 + std::abs(torque))));
      // Roundoff of the difference quotient: a few ε |τ| / h.
      const double roundoff_theta = 1e-15 * (std::abs(torque) + 10.0) / h;
      const double roundoff_omega = 1e-15 * (std::abs(torque) + 10.0) / kOmegaStep;
      CHECK_THAT(d.dtorque_dtheta_Nm_per_rad,
                 WithinAbs(fd_theta, 1e-6 * std::abs(fd_theta) + roundoff_theta));
      CHECK_THAT(d.dtorque_domega_Nm_s_per_rad,
                 WithinAbs(fd_omega, 1e-6 * std::abs(fd_omega) + roundoff_omega));
      ++checked;
    }
  }
  CHECK(checked == static_cast<int>(kThetas.size() * kOmegas.size()));
}

// Parameter derivatives through evaluate<Jet>: seed parameters `indices`, compare with
// central differences of torque_Nm over with_parameter_values.
template <int N>
void check_parameter_derivatives(const DoorModel& model, const std::array<int, N>& indices,
                                 double theta, double omega) {
  using Jet = ceres::Jet<double, N>;
  const auto values = model.parameter_values();
  std::array<Jet, DoorModel::kMaxParameters> parameters;
  for (int i = 0; i < model.parameter_count(); ++i) parameters[i] = Jet(values[i]);
  for (int k = 0; k < N; ++k) parameters[indices[k]].v[k] = 1.0;
  std::array<Jet, DoorModel::kMaxTerms> terms;
  const Jet torque = model.evaluate(parameters.data(), Jet(theta), Jet(omega), terms.data());
  CHECK_THAT(torque.a,
             WithinAbs(model.torque_Nm(theta, omega), 1e-13 * (1.0 + std::abs(torque.a))));
  for (int k = 0; k < N; ++k) {
    const int index = indices[k];
    const double h = 1e-6 * std::max(std::abs(values[index]), 1e-3);
    std::vector<double> plus(values.begin(), values.end()), minus = plus;
    plus[index] += h;
    minus[index] -= h;
    const double fd = (model.with_parameter_values(plus).torque_Nm(theta, omega) -
                       model.with_parameter_values(minus).torque_Nm(theta, omega)) /
                      (2 * h);
    INFO("d torque / d " << model.parameter_name(index) << " at theta = " << theta
                         << ", omega = " << omega);
    const double roundoff = 1e-15 * (std::abs(torque.a) + 10.0) / h;
    CHECK_THAT(torque.v[k], WithinAbs(fd, 1e-5 * std::abs(fd) + roundoff));
  }
}

}  // namespace

TEST_CASE("Derivatives: sensory model, worked by hand", "[derivatives]") {
  const DoorModel model = doorbench::reference_model(ModelKind::kSensory);
  // Stiff zone, θ = 0.02, ω = 0: τ = −(k θ + k_inf (θ − θ0)), ∂τ/∂θ = −(40 + 1054) = −1094;
  // ∂τ/∂ω = −s tanh′(0) (d1 − d2 S̄(θ; θ4)) = −25 (2.6 − 1.3 · 0.99999...) ≈ −32.5 (S̄ = 1 − 5e−6).
  auto d = model.torque_derivatives(0.02, 0.0);
  CHECK_THAT(d.dtorque_dtheta_Nm_per_rad, WithinRel(-1094.0, 1e-9));
  CHECK_THAT(d.dtorque_domega_Nm_s_per_rad, WithinRel(-25.0 * (2.6 - 1.3), 1e-4));
  // Middle of the snap zone at speed: ∂τ/∂ω = c W − friction′ ≈ 3 (sech²(12.5) ≈ 5.6e−11).
  d = model.torque_derivatives(0.033165, 0.5);
  CHECK_THAT(d.dtorque_domega_Nm_s_per_rad, WithinRel(3.0, 1e-8));
  // Middle of the latching zone, at rest (so the friction's θ-slope is 0): ∂τ/∂θ = −k_lock = −767.
  d = model.torque_derivatives(0.049745, 0.0);
  CHECK_THAT(d.dtorque_dtheta_Nm_per_rad, WithinRel(-767.0, 1e-8));
  // Beyond θ_max: the stop adds −k_stop and −c_stop.
  const auto inside = model.torque_derivatives(1.5, 0.2);
  const auto beyond = model.torque_derivatives(1.6, 0.2);
  CHECK(beyond.dtorque_dtheta_Nm_per_rad < inside.dtorque_dtheta_Nm_per_rad - 4990.0);
  CHECK_THAT(beyond.dtorque_domega_Nm_s_per_rad - inside.dtorque_domega_Nm_s_per_rad,
             WithinAbs(-20.0, 1e-3));
}

TEST_CASE("Derivatives: physical model, worked by hand", "[derivatives]") {
  const DoorModel model = doorbench::reference_model(ModelKind::kPhysical);
  // θ = 0.5, ω = 1 (far from the latch and the seal; tanh(50) = 1):
  // ∂τ/∂ω = −b_h − (T_h + mu_g T)/w_f · sech²(50) ≈ −0.05.
  auto d = model.torque_derivatives(0.5, 1.0);
  CHECK_THAT(d.dtorque_domega_Nm_s_per_rad, WithinRel(-0.05, 1e-9));
  // At rest, ∂τ/∂ω = −b_h − (T_h + mu_g T(θ)) / w_f. θ = π/2: T = 381.2058070,
  // −0.05 − (0.6 + 2.2872348) / 0.02 = −144.4117421.
  d = model.torque_derivatives(1.5707963267948966, 0.0);
  CHECK_THAT(d.dtorque_domega_Nm_s_per_rad,
             WithinRel(-0.05 - (0.6 + 2.2872348417211243) / 0.02, 1e-9));
  // Gravity alone at π/2 has zero slope; ∂τ/∂θ there is the spring's and is finite.
  CHECK(std::isfinite(d.dtorque_dtheta_Nm_per_rad));
}

TEST_CASE("Derivatives: sensory model against finite differences", "[derivatives]") {
  check_state_derivatives(doorbench::reference_model(ModelKind::kSensory));
}

TEST_CASE("Derivatives: physical model against finite differences", "[derivatives]") {
  check_state_derivatives(doorbench::reference_model(ModelKind::kPhysical));
}

TEST_CASE("Derivatives: models with effects against finite differences", "[derivatives]") {
  check_state_derivatives(sensory_with_effects());
  check_state_derivatives(physical_with_effects());
}

TEST_CASE("Derivatives: Jet parameter derivatives, sensory", "[derivatives]") {
  const DoorModel model = doorbench::reference_model(ModelKind::kSensory);
  // k, k_inf, k_lock, theta0, theta1, theta2, theta3, c, d2, beta.
  const std::array<int, 10> indices = {1, 2, 3, 4, 5, 6, 7, 8, 10, 13};
  for (double theta : {0.007, 0.02, 0.0278, 0.033, 0.0385, 0.05, 0.061}) {
    check_parameter_derivatives<10>(model, indices, theta, 0.3);
  }
  // By hand, stiff zone θ = 0.02: ∂τ/∂k_inf = −(θ − θ0) = −0.01302, ∂τ/∂k = −0.02.
  using Jet = ceres::Jet<double, 2>;
  std::array<Jet, DoorModel::kMaxParameters> p;
  for (int i = 0; i < model.parameter_count(); ++i) p[i] = Jet(model.parameter_values()[i]);
  p[1].v[0] = 1.0;  // k
  p[2].v[1] = 1.0;  // k_inf
  std::array<Jet, DoorModel::kMaxTerms> terms;
  const Jet t = model.evaluate(p.data(), Jet(0.02), Jet(0.0), terms.data());
  CHECK_THAT(t.v[0], WithinRel(-0.02, 1e-9));
  CHECK_THAT(t.v[1], WithinRel(-0.01302, 1e-9));
}

TEST_CASE("Derivatives: Jet parameter derivatives, physical and effects", "[derivatives]") {
  const DoorModel model = physical_with_effects();
  // k_s, L0, F0, B_u, T_h, w_f, k_l, F_l0, alpha_o, alpha_c, mu_l, e, and stribeck.d_s.
  const int d_s = *model.find_parameter("stribeck.d_s");
  const std::array<int, 13> indices = {3, 4, 5, 8, 10, 12, 15, 16, 18, 19, 20, 21, d_s};
  for (double theta : {0.0072, 0.0116, 0.01665, 0.0295, 0.6}) {
    for (double omega : {-0.02, 0.05}) {
      check_parameter_derivatives<13>(model, indices, theta, omega);
    }
  }
}
