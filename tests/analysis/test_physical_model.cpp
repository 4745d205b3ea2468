// The detailed physical model of door-models.md §3 and §3.1 on the reference door, each
// part worked out by hand from the spec's geometry and formulas.
#include <ceres/jet.h>

#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
#include <string>
#include <string_view>
#include <vector>

#include "analysis/model/door_model.h"
#include "analysis/model/parameter_file.h"

using Catch::Matchers::Contains;
using Catch::Matchers::StartsWith;
using Catch::Matchers::WithinAbs;
using Catch::Matchers::WithinRel;
using doorbench::Bounds;
using doorbench::DoorGeometry;
using doorbench::DoorModel;
using doorbench::ModelKind;

namespace {

// reference-door.json's "physical" section, in the file's order.
// clang-format off
enum {
  kMd, kLc, kJd, kKs, kL0, kF0, kAx, kAy, kBu, kBv, kTh, kBh, kWf, kMuG, kRl, kKl, kFl0, kH,
  kAlphaO, kAlphaC, kMuL, kE, kKSeal, kThetaSeal, kKStop, kCStop, kCount
};
// clang-format on
const std::vector<double> kReference = {
    7.5,   0.3, 0.95,   2450.0, 0.3,   250.0,  0.0,    -0.35, -0.05,  0.0,   0.6,  0.05,   0.02,
    0.006, 0.6, 6000.0, 15.0,   0.004, 0.5236, 0.3491, 0.15,  0.0003, 150.0, 0.01, 5000.0, 20.0};
const DoorGeometry kGeometry{0.58, 1.5708};
constexpr double kPi = std::numbers::pi;

std::vector<Bounds> wide_bounds() {
  return std::vector<Bounds>(kCount, {-1e9, 1e9});
}

DoorModel model_from(const std::vector<double>& values) {
  return DoorModel(ModelKind::kPhysical, kGeometry, values, wide_bounds());
}

DoorModel model_with(int index, double value) {
  std::vector<double> values = kReference;
  values[index] = value;
  return model_from(values);
}

const DoorModel& physical_reference() {
  static const DoorModel model = model_from(kReference);
  return model;
}

// One named term of `model` at (θ, ω).
double term(const DoorModel& model, std::string_view name, double theta, double omega) {
  std::array<double, DoorModel::kMaxTerms> terms{};
  model.torque_Nm(theta, omega, terms);
  for (int i = 0; i < model.term_count(); ++i) {
    if (model.term_name(i) == name) return terms[i];
  }
  FAIL("no term named " << name);
  return 0.0;
}
double term(std::string_view name, double theta, double omega) {
  return term(physical_reference(), name, theta, omega);
}

}  // namespace

TEST_CASE("Physical: the reference door's parts, inertia and parameters", "[physical]") {
  CHECK(physical_reference().term_count() == 7);
  CHECK(physical_reference().inertia_kg_m2() == 0.95);  // J = J_d
  const DoorModel shipped = doorbench::reference_model(ModelKind::kPhysical);
  REQUIRE(shipped.parameter_count() == kCount);
  for (int i = 0; i < kCount; ++i) CHECK(shipped.parameter_values()[i] == kReference[i]);
  // No switch sharpness: the fit's softer-switch starts skip the physical model.
  CHECK(!shipped.switch_sharpness_index().has_value());
}

TEST_CASE("Physical: gravity", "[physical]") {
  // m_d g l_c = 7.5 · 9.80665 · 0.3 = 22.0649625 N·m, times sin θ, opening.
  CHECK(term("gravity", 0.0, 0.0) == 0.0);
  CHECK_THAT(term("gravity", kPi / 2, 0.0), WithinRel(22.0649625, 1e-12));
  CHECK_THAT(term("gravity", kPi / 4, 0.0), WithinRel(22.0649625 * 0.70710678118654752, 1e-12));
  CHECK_THAT(term("gravity", 0.3, 1.0), WithinRel(6.5206422779747079, 1e-12));
}

TEST_CASE("Physical: balancing spring on the reference door", "[physical]") {
  // A = (0, −0.35), B(θ) = −0.05 (sin θ, cos θ). A − B = (0.05 sin θ, −0.35 + 0.05 cos θ),
  // L² = 0.125 − 0.035 cos θ. B × (A − B) = B × A = B_x A_y − B_y A_x = 0.0175 sin θ,
  // so torque = −T · 0.0175 sin θ / L.
  // θ = 0: B = (0, −0.05), on the line to A: no moment.
  CHECK_THAT(term("spring", 0.0, 0.0), WithinAbs(0.0, 1e-12));
  // θ = π/4: L² = 0.125 − 0.035 · 0.70710678 = 0.10025126, L = 0.31662480;
  // T = 250 + 2450 · 0.01662480 = 290.73075; torque = −290.73075 · 0.0175 · 0.70710678 / 0.31662480
  //   = −11.3623745.
  CHECK_THAT(term("spring", kPi / 4, 0.0), WithinRel(-11.362374547929263, 1e-10));
  // θ = π/2: L = √0.125 = 0.35355339, T = 250 + 2450 · 0.05355339 = 381.20581;
  // torque = −381.20581 · 0.0175 / 0.35355339 = −18.8687248.
  CHECK_THAT(term("spring", kPi / 2, 0.0), WithinRel(-18.868724778716712, 1e-10));
  // The spring closes the door against gravity: net +3.196 N·m at π/2.
  CHECK_THAT(term("gravity", kPi / 2, 0.0) + term("spring", kPi / 2, 0.0),
             WithinRel(22.0649625 - 18.868724778716712, 1e-10));
  // The spring does not depend on ω.
  CHECK_THAT(term("spring", kPi / 4, -0.8), WithinRel(-11.362374547929263, 1e-10));
}

TEST_CASE("Physical: balancing spring with the lever off the door's axis", "[physical]") {
  std::vector<double> values = kReference;
  values[kBv] = 0.02;
  values[kAx] = 0.03;
  const DoorModel model = model_from(values);
  // θ = 1.2 (sin 0.93203909, cos 0.36235775):
  // B = −0.05 (0.93203909, 0.36235775) + 0.02 (0.36235775, −0.93203909) = (−0.03935480,
  // −0.03675867); A − B = (0.06935480, −0.31324133), L = 0.32082740, T = 250 + 2450 · 0.02082740 =
  // 301.02713; B × (A − B) = (−0.03935480)(−0.31324133) − (−0.03675867)(0.06935480) = 0.01487694;
  // torque = −301.02713 · 0.01487694 / 0.32082740 = −13.9587905.
  CHECK_THAT(term(model, "spring", 1.2, 0.0), WithinRel(-13.958790456616459, 1e-10));
  // θ = π/2 with A_x = 0: B = (−0.05, −0.02), A − B = (0.05, −0.33), L = √0.1114 = 0.33376639,
  // T = 250 + 2450 · 0.03376639 = 332.72764; B × (A − B) = 0.0165 + 0.001 = 0.0175;
  // torque = −332.72764 · 0.0175 / 0.33376639 = −17.4455368.
  values[kAx] = 0.0;
  CHECK_THAT(term(model_from(values), "spring", kPi / 2, 0.0),
             WithinRel(-17.445536842097859, 1e-10));
}

TEST_CASE("Physical: a slack spring pulls nothing", "[physical]") {
  // L0 = 0.4: at θ = 0.3, L² = 0.125 − 0.035 cos 0.3 = 0.0915627, L = 0.30259 < L0: T = 0.
  const DoorModel model = model_with(kL0, 0.4);
  CHECK(term(model, "spring", 0.3, 0.0) == 0.0);
  CHECK(term(model, "guide_friction", 0.3, 0.5) == 0.0);
  // Reference L0 = 0.3: stretched, T = 250 + 2450 · 0.00259416 = 256.35568,
  // torque = −256.35568 · 0.0175 sin 0.3 / 0.30259416 = −4.38134690.
  CHECK_THAT(term("spring", 0.3, 0.0), WithinRel(-4.3813469028093892, 1e-10));
}

TEST_CASE("Physical: hinge and spring-guide friction", "[physical]") {
  // Hinge: −T_h tanh(ω / w_f) − b_h ω.
  // ω = 0.5: tanh(25) = 1 − 4e−22: −0.6 − 0.025 = −0.625.
  CHECK_THAT(term("hinge_friction", 0.3, 0.5), WithinRel(-0.625, 1e-12));
  // ω = −0.01: tanh(−0.5) = −0.46211715726: 0.6 · 0.46211715726 + 0.05 · 0.01 = 0.27777029436.
  CHECK_THAT(term("hinge_friction", 0.3, -0.01), WithinRel(0.27777029435600586, 1e-12));
  CHECK(term("hinge_friction", 0.3, 0.0) == 0.0);
  // Guide: −mu_g T tanh(ω / w_f). At π/2, T = 381.20580695: −0.006 · 381.20580695 = −2.2872348417.
  CHECK_THAT(term("guide_friction", kPi / 2, 0.5), WithinRel(-2.2872348417211243, 1e-10));
  // At π/4 closing, T = 290.73075491: +0.006 · 290.73075491 = 1.7443845294.
  CHECK_THAT(term("guide_friction", kPi / 4, -0.5), WithinRel(1.744384529437696, 1e-10));
  // Larger where the spring is stretched more (door open).
  CHECK(std::abs(term("guide_friction", 1.4, 0.5)) > std::abs(term("guide_friction", 0.2, 0.5)));
}

// The latch (§3.1). tan α_o = tan 0.5236 = 0.57735509, tan α_c = tan 0.3491 = 0.36399;
// x1 = 0.004 / 0.57735509 = 0.00692818, x2 = x1 + 0.004 / 0.36399 = 0.01791693 (θ = 0.0298615).
// atan μ_l = atan 0.15 = 0.14888995.
// Away from the corners (by ≥ 8 e), y ≈ the ideal ramp, y′ ≈ ± tan α and the gate ≈ 1, so F_x
// is the ideal ramp force to about 1e−3 (the corners' smoothing leaks e^−8 ≈ 3e−4 into y′).
TEST_CASE("Physical: latch on the rising ramp", "[physical]") {
  // θ = 0.0072: x = 0.6 · 0.0072 = 0.00432 (14 e from 0, 9 e of height from the softmin corner);
  // y = 0.00432 · 0.57735509 = 0.00249417, N = 15 + 6000 · 0.00249417 = 29.96496.
  const double n = 15.0 + 6000.0 * 0.00432 * std::tan(0.5236);
  // Opening: F_x = −N tan(α_o + atan μ_l) = −29.96496 · tan(0.67248995) = −29.96496 · 0.79630 =
  // −23.8615.
  const double opening = -n * std::tan(0.5236 + std::atan(0.15));
  CHECK_THAT(opening, WithinRel(-23.861548, 1e-6));  // the hand value above
  CHECK_THAT(term("latch", 0.0072, 0.5), WithinRel(0.6 * opening, 2e-3));
  // Closing: the friction flips, F_x = −N tan(α_o − atan μ_l) = −29.96496 · 0.39329 = −11.78497.
  const double closing = -n * std::tan(0.5236 - std::atan(0.15));
  CHECK_THAT(term("latch", 0.0072, -0.5), WithinRel(0.6 * closing, 2e-3));
  // Both pull the door shut (resist unlatching, pull it in when closing).
  CHECK(term("latch", 0.0072, 0.5) < 0.0);
  CHECK(term("latch", 0.0072, -0.5) < 0.0);
}

TEST_CASE("Physical: latch on the falling ramp", "[physical]") {
  // θ = 0.01665: x = 0.00999 (x2 − x = 0.00792, 9.6 e of height from 0); y = 0.00792 · 0.36399
  // = 0.00288355, N = 15 + 6000 · 0.00288355 = 32.30128.
  const double tan_c = std::tan(0.3491);
  const double n = 15.0 + 6000.0 * (0.004 / std::tan(0.5236) + 0.004 / tan_c - 0.00999) * tan_c;
  CHECK_THAT(n, WithinRel(32.312829, 1e-6));  // the hand value above
  // Opening: F_x = +N tan(α_c − atan μ_l) = 32.31283 · tan(0.20021) = 32.31283 · 0.20293 = 6.5572.
  const double opening = n * std::tan(0.3491 - std::atan(0.15));
  CHECK_THAT(term("latch", 0.01665, 0.5), WithinRel(0.6 * opening, 2e-3));
  CHECK(term("latch", 0.01665, 0.5) > 0.0);  // pushes the door out
  // Closing: F_x = +N tan(α_c + atan μ_l) = 32.31283 · 0.54370 = 17.5683 (resists closing).
  const double closing = n * std::tan(0.3491 + std::atan(0.15));
  CHECK_THAT(term("latch", 0.01665, -0.5), WithinRel(0.6 * closing, 2e-3));
}

TEST_CASE("Physical: latch with the smoothing, recomputed from 3.1", "[physical]") {
  // The exact smoothed formula, written out from §3.1 in long double with the naive
  // exponentials (all arguments here are below 100 in size, so nothing overflows).
  const long double r_l = 0.6, k_l = 6000, f_l0 = 15, h = 0.004, e = 0.0003, mu = 0.15, w_f = 0.02;
  const long double tan_o = std::tan(0.5236L), tan_c = std::tan(0.3491L);
  const long double x2 = h / tan_o + h / tan_c;
  auto y = [&](long double x) {
    const long double a = x * tan_o, b = (x2 - x) * tan_c;
    const long double z = -e * std::log(std::exp(-a / e) + std::exp(-b / e));
    return e * std::log(1 + std::exp(z / e));
  };
  auto force = [&](long double theta, long double omega) {
    const long double x = r_l * theta, dx = 1e-9L;
    const long double slope = (y(x + dx) - y(x - dx)) / (2 * dx);
    const long double gate = 0.5L * (1 + std::tanh(x / e)) - 0.5L * (1 + std::tanh((x - x2) / e));
    const long double n = (f_l0 + k_l * y(x)) * gate;
    const long double m = mu * std::tanh(omega / w_f);
    return static_cast<double>(-n * (slope + m) / (1 - slope * m));
  };
  // Near the corners too, where the ideal-ramp formulas do not hold.
  for (double theta :
       {0.0, 0.0005, 0.002, 0.0072, 0.0112, 0.01155, 0.0125, 0.01665, 0.028, 0.0298, 0.0305}) {
    for (double omega : {-0.5, -0.01, 0.0, 0.004, 0.5}) {
      INFO("theta = " << theta << ", omega = " << omega);
      CHECK_THAT(term("latch", theta, omega), WithinAbs(0.6 * force(theta, omega), 1e-6));
    }
  }
  // At rest there is no friction: θ = 0.0072, F_x = −N y′ with y′ ≈ tan α_o, ≈ −17.3 N.
  CHECK_THAT(term("latch", 0.0072, 0.0), WithinRel(0.6 * -29.96496 * 0.57735509, 2e-3));
}

TEST_CASE("Physical: latch is zero away from the catch", "[physical]") {
  // θ = 0.05: x = 0.03 = x2 + 40 e: gate ≈ e^−80.
  CHECK_THAT(term("latch", 0.05, 0.5), WithinAbs(0.0, 1e-12));
  CHECK_THAT(term("latch", 0.05, -0.5), WithinAbs(0.0, 1e-12));
  CHECK_THAT(term("latch", 0.5, 0.5), WithinAbs(0.0, 1e-12));
  // Before the catch (θ = −0.01, x = −20 e): gate ≈ e^−40.
  CHECK_THAT(term("latch", -0.01, 0.5), WithinAbs(0.0, 1e-12));
}

TEST_CASE("Physical: door seal and end stops", "[physical]") {
  // Seal: k_seal (θ_seal − θ) below θ_seal = 0.01: 150 · 0.006 = 0.9 at θ = 0.004.
  CHECK_THAT(term("seal", 0.004, 0.0), WithinRel(0.9, 1e-12));
  CHECK_THAT(term("seal", 0.0, 0.3), WithinRel(1.5, 1e-12));
  CHECK(term("seal", 0.02, 0.0) == 0.0);
  CHECK(term("seal", 1.0, 0.0) == 0.0);
  // Stops: θ = 1.6: −(5000 · 0.0292 + 20 · 0.1) = −148; θ = −0.01, ω = −0.2: +54.
  CHECK_THAT(term("stops", 1.6, 0.1), WithinRel(-148.0, 1e-9));
  CHECK_THAT(term("stops", -0.01, -0.2), WithinRel(54.0, 1e-12));
  CHECK(term("stops", 0.8, 1.0) == 0.0);
}

TEST_CASE("Physical: tau_m is the sum of the parts", "[physical]") {
  // θ = π/2, ω = 0.5: gravity 22.0649625, spring −18.8687248, hinge −0.625,
  // guide −2.2872348, latch 0, seal 0, stops (π/2 = 1.5707963 < θ_max = 1.5708) 0:
  // τ_m = 0.2840029.
  CHECK_THAT(physical_reference().torque_Nm(kPi / 2, 0.5),
             WithinRel(22.0649625 - 18.868724778716712 - 0.625 - 2.2872348417211243, 1e-9));
  for (double theta : {-0.01, 0.0, 0.005, 0.0072, 0.012, 0.02, 0.04, 0.5, 1.2, 1.6}) {
    for (double omega : {-0.6, -0.01, 0.0, 0.03, 0.7}) {
      std::array<double, 7> t{};
      const double total = physical_reference().torque_Nm(theta, omega, t);
      double sum = 0.0;
      for (double v : t) sum += v;
      CHECK_THAT(total, WithinAbs(sum, 1e-12));
      CHECK(physical_reference().torque_Nm(theta, omega) == total);
    }
  }
}

TEST_CASE("Physical: a self-locking cam is rejected", "[physical]") {
  // μ_l tan(max(α_o, α_c)) ≥ 0.9 is rejected.
  // μ_l = 1.6, α_o = 0.5236: 1.6 · 0.57735509 = 0.9238 ≥ 0.9.
  CHECK_THROWS_WITH(model_with(kMuL, 1.6), StartsWith("physical parameter mu_l = 1.6 breaks "
                                                      "mu_l * tan(max(alpha_o, alpha_c)) < 0.9") &&
                                               Contains("self-locking"));
  // The steeper ramp is the closing one: α_c = 1.2, μ_l = 0.4: 0.4 · tan 1.2 = 1.0289.
  std::vector<double> values = kReference;
  values[kAlphaC] = 1.2;
  values[kMuL] = 0.4;
  CHECK_THROWS_WITH(model_from(values),
                    StartsWith("physical parameter mu_l = 0.4 breaks") && Contains("self-locking"));
  // μ_l = 0.34: 0.34 · 2.5721516 = 0.8745 < 0.9: accepted.
  values[kMuL] = 0.34;
  CHECK_NOTHROW(model_from(values));
  // The reference: 0.15 · 0.57735509 = 0.0866: fine.
  CHECK_NOTHROW(model_from(kReference));
}

TEST_CASE("Physical: other constraint messages", "[physical]") {
  using M = std::string;
  CHECK_THROWS_WITH(model_with(kMd, 0.0), M("physical parameter m_d = 0 breaks m_d > 0"));
  CHECK_THROWS_WITH(model_with(kJd, -1.0), M("physical parameter J_d = -1 breaks J_d > 0"));
  CHECK_THROWS_WITH(model_with(kWf, 0.0), M("physical parameter w_f = 0 breaks w_f > 0"));
  CHECK_THROWS_WITH(model_with(kE, 0.0), M("physical parameter e = 0 breaks e > 0"));
  CHECK_THROWS_WITH(model_with(kH, -0.004), M("physical parameter h = -0.004 breaks h > 0"));
  CHECK_THROWS_WITH(model_with(kAlphaO, 1.6),
                    M("physical parameter alpha_o = 1.6 breaks 0 < alpha_o < pi/2"));
  CHECK_THROWS_WITH(model_with(kAlphaC, 0.0),
                    M("physical parameter alpha_c = 0 breaks 0 < alpha_c < pi/2"));
  CHECK_THROWS_WITH(model_with(kKStop, 0.0), M("physical parameter k_stop = 0 breaks k_stop > 0"));
  CHECK_THROWS_WITH(model_with(kMuG, -0.001),
                    M("physical parameter mu_g = -0.001 breaks mu_g >= 0"));
  CHECK_THROWS_AS(model_with(kMd, 0.0), std::invalid_argument);
}

TEST_CASE("Physical: the cached latch shape gives what the per-call evaluation gives, to the bit",
          "[physical]") {
  // DoorModel keeps tan(alpha_o), tan(alpha_c) and the cam's corners from its constructor;
  // the generic evaluate() computes them from the parameter array each call. Both must agree
  // exactly, also after with_parameter_values (which must refresh the cache).
  const DoorModel reference = doorbench::reference_model(ModelKind::kPhysical);
  std::vector<double> values(reference.parameter_values().begin(),
                             reference.parameter_values().end());
  values[doorbench::physical::kAlphaO] *= 1.2;
  values[doorbench::physical::kAlphaC] *= 0.8;
  values[doorbench::physical::kH] *= 1.1;
  const DoorModel changed = reference.with_parameter_values(values);
  for (const DoorModel* model : {&reference, &changed}) {
    std::array<double, DoorModel::kMaxTerms> cached{}, generic{};
    int compared = 0;
    for (double theta = -0.02; theta < 1.6; theta += 0.0007) {
      for (double omega : {-2.0, -0.3, 0.0, 0.01, 0.7, 2.5}) {
        const double a = model->torque_Nm(theta, omega, cached);
        const double b =
            model->evaluate(model->parameter_values().data(), theta, omega, generic.data());
        INFO("theta " << theta << " omega " << omega);
        REQUIRE(a == b);
        for (int i = 0; i < model->term_count(); ++i) REQUIRE(cached[i] == generic[i]);
        ++compared;
      }
    }
    REQUIRE(compared > 10000);
    // torque_derivatives (cached shape) against Jets through the generic evaluate.
    using StateJet = ceres::Jet<double, 2>;
    std::array<StateJet, DoorModel::kMaxParameters> parameters;
    for (int i = 0; i < model->parameter_count(); ++i) {
      parameters[std::size_t(i)] = StateJet(model->parameter_values()[std::size_t(i)]);
    }
    std::array<StateJet, DoorModel::kMaxTerms> terms;
    for (double theta = -0.02; theta < 1.6; theta += 0.0031) {
      const double omega = 0.4 - theta;
      const auto d = model->torque_derivatives(theta, omega);
      const StateJet jet =
          model->evaluate(parameters.data(), StateJet(theta, 0), StateJet(omega, 1), terms.data());
      INFO("theta " << theta);
      REQUIRE(d.torque_Nm == jet.a);
      REQUIRE(d.dtorque_dtheta_Nm_per_rad == jet.v[0]);
      REQUIRE(d.dtorque_domega_Nm_s_per_rad == jet.v[1]);
    }
  }
  // And the cache is the changed model's own: another latch, another torque in the latch.
  REQUIRE(changed.torque_Nm(0.02, 0.1) != reference.torque_Nm(0.02, 0.1));
}
