// The catalogue of effects (door-models.md §4): each effect's torque at a point worked
// out by hand, added to the reference sensory model through an effects file.
#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <string>
#include <string_view>
#include <vector>

#include "analysis/model/door_model.h"
#include "analysis/model/parameter_file.h"

using Catch::Matchers::Contains;
using Catch::Matchers::StartsWith;
using Catch::Matchers::WithinAbs;
using Catch::Matchers::WithinRel;
using doorbench::DoorModel;
using doorbench::EffectSetting;
using doorbench::ModelKind;
using doorbench::parse_effects_file;
namespace effects = doorbench::effects;

namespace {

const DoorModel& sensory_base() {
  static const DoorModel model = doorbench::reference_model(ModelKind::kSensory);
  return model;
}

// The reference sensory model with the effects of `json` added through with_effect.
DoorModel with_effects(std::string_view json, const DoorModel& base = sensory_base()) {
  DoorModel model = base;
  for (EffectSetting& setting : parse_effects_file(json, "effects.json")) {
    model = model.with_effect(std::move(setting));
  }
  return model;
}

// The one effect's term and the change it makes to τ_m, at (θ, ω). The base model has
// five terms (sensory) or seven (physical); the effect's term comes after them.
struct Added {
  double term;
  double change;
};
Added added(const DoorModel& model, const DoorModel& base, double theta, double omega) {
  REQUIRE(model.term_count() == base.term_count() + 1);
  std::array<double, DoorModel::kMaxTerms> terms{};
  const double total = model.torque_Nm(theta, omega, terms);
  return {terms[base.term_count()], total - base.torque_Nm(theta, omega)};
}

void check_added(std::string_view json, double theta, double omega, double expected,
                 const DoorModel& base = sensory_base()) {
  INFO(json << " at theta = " << theta << ", omega = " << omega);
  const DoorModel model = with_effects(json, base);
  const Added a = added(model, base, theta, omega);
  CHECK_THAT(a.term, WithinRel(expected, 1e-10) || WithinAbs(expected, 1e-14));
  CHECK_THAT(a.change, WithinAbs(expected, 1e-9 * (1.0 + std::abs(expected))));
}

}  // namespace

TEST_CASE("Effects: viscous damping is -b omega", "[effects]") {
  // b = 0.4: ω = 0.5 → −0.2; ω = −1.5 → +0.6.
  check_added(R"({"viscous_damping": {"b": 0.4}})", 0.3, 0.5, -0.2);
  check_added(R"({"viscous_damping": {"b": 0.4}})", 1.0, -1.5, 0.6);
  const DoorModel model = with_effects(R"({"viscous_damping": {"b": 0.4}})");
  CHECK(model.term_name(5) == "viscous_damping");
  CHECK(model.has_effect(effects::Kind::kViscousDamping));
}

TEST_CASE("Effects: gravity imbalance is +g1 sin theta", "[effects]") {
  // g1 = 3, θ = 1: 3 sin 1 = 3 · 0.8414709848 = 2.5244129544.
  check_added(R"({"gravity_imbalance": {"g1": 3.0}})", 1.0, 0.2, 2.5244129544236895);
  // g1 = −2, θ = 0.5: −2 · 0.4794255386 = −0.9588510772.
  check_added(R"({"gravity_imbalance": {"g1": {"value": -2.0, "bounds": [-5, 5]}}})", 0.5, 0.0,
              -0.95885107720840600);
}

TEST_CASE("Effects: Stribeck friction borrows d1 and s from the sensory model", "[effects]") {
  // − (d_s − d1) exp(−(ω/w_s)²) tanh(s ω), d1 = 2.6, s = 25; d_s = 3.2, w_s = 0.05.
  const char* json = R"({"stribeck": {"d_s": 3.2, "w_s": 0.05}})";
  // ω = 0.05: −0.6 · e^−1 · tanh(1.25) = −0.6 · 0.3678794412 · 0.8482836400 = −0.1872396669.
  check_added(json, 0.3, 0.05, -0.18723966685346810);
  // ω = −0.1: −0.6 · e^−4 · tanh(−2.5) = 0.6 · 0.0183156389 · 0.9866142982 = 0.0108422827.
  check_added(json, 0.3, -0.1, 0.010842282724442110);
  // ω = 0.5: e^−100, gone.
  check_added(json, 0.3, 0.5, 0.0);
}

TEST_CASE("Effects: Stribeck on the physical model borrows T_h and 1/w_f", "[effects]") {
  // effects.h: for the physical model d1 → T_h = 0.6 and s → 1/w_f = 50.
  // d_s = 1, w_s = 0.05, ω = 0.05: −0.4 · e^−1 · tanh(2.5) = −0.4 · 0.3678794412 · 0.9866142982
  //   = −0.1451820467.
  const DoorModel physical = doorbench::reference_model(ModelKind::kPhysical);
  check_added(R"({"stribeck": {"d_s": 1.0, "w_s": 0.05}})", 0.3, 0.05, -0.14518204666228118,
              physical);
}

TEST_CASE("Effects: direction-dependent friction acts only when opening", "[effects]") {
  // − d_dir max(0, tanh(s ω)), s = 25, d_dir = 0.7: ω = 0.1 → −0.7 tanh 2.5 = −0.6906300087.
  const char* json = R"({"direction_friction": {"d_dir": 0.7}})";
  check_added(json, 0.4, 0.1, -0.69063000870600120);
  check_added(json, 0.4, -0.1, 0.0);
  check_added(json, 0.4, -2.0, 0.0);
  // ω = 2: tanh(50) = 1: −0.7.
  check_added(json, 0.4, 2.0, -0.7);
}

TEST_CASE("Effects: soft-close damper near closed", "[effects]") {
  // − b_sc ω S̄(θ; θ_sc, β_sc), b_sc = 5, θ_sc = 0.1, β_sc = 10.
  const char* json = R"({"soft_close": {"b_sc": 5, "theta_sc": 0.1, "beta_sc": 10}})";
  // At θ_sc, S̄ = ½: −5 · −0.4 · ½ = 1.
  check_added(json, 0.1, -0.4, 1.0);
  // θ = 0.15: S̄ = ½ (1 − tanh 0.5) = 1/(1 + e) = 0.2689414214: 2 · 0.2689414214 = 0.5378828427.
  check_added(json, 0.15, -0.4, 0.53788284273999024);
  // β_sc is the effect's own: β_sc = 20 at θ = 0.15 gives S̄ = ½ (1 − tanh 1),
  // −5 · −0.4 · S̄ = 1 − tanh 1 = 0.2384058440.
  check_added(R"({"soft_close": {"b_sc": 5, "theta_sc": 0.1, "beta_sc": 20}})", 0.15, -0.4,
              0.23840584404423515);
  // Closed (θ = −0.5, β_sc Δθ = −6, S̄ = 1/(1 + e^−12) = 0.9999938558) and far open
  // (θ = 1.5 with β_sc = 100, S̄ ≈ e^−280).
  check_added(json, -0.5, -0.4, 2.0 * 0.99999385582539779);
  check_added(R"({"soft_close": {"b_sc": 5, "theta_sc": 0.1, "beta_sc": 100}})", 1.5, -0.4, 0.0);
}

TEST_CASE("Effects: end stop / limit", "[effects]") {
  // − k_e (θ − θ_e) S(θ; θ_e, β_e), k_e = 2000, θ_e = 1.5, β_e = 1000.
  const char* json = R"({"end_stop": {"k_e": 2000, "theta_e": 1.5, "beta_e": 1000}})";
  // θ = 1.52 (20 widths past, S = 1 − 4e−18): −2000 · 0.02 = −40.
  check_added(json, 1.52, 0.0, -40.0);
  // θ = 1.5 + 1/1000: −2000 · 0.001 · ½ (1 + tanh 1) = −2 · 0.8807970780 = −1.7615941560.
  check_added(json, 1.5 + 1.0 / 1000.0, 0.3, -1.7615941559557646);
  // With β_e = 3000, θ = 1.5 + 1/3000: −(2/3) · 0.8807970780 = −0.5871980520.
  check_added(R"({"end_stop": {"k_e": 2000, "theta_e": 1.5, "beta_e": 3000}})", 1.5 + 1.0 / 3000.0,
              0.3, -0.58719805198525496);
  // Before it: nothing.
  check_added(json, 1.4, 0.3, 0.0);
}

TEST_CASE("Effects: force-sensor offset", "[effects]") {
  // The door feels r_h (F_measured − F_off): an extra −r_h F_off = −0.58 · 2 = −1.16 N·m,
  // everywhere.
  check_added(R"({"force_offset": {"F_off": 2.0}})", 0.3, 0.0, -1.16);
  check_added(R"({"force_offset": {"F_off": -1.5}})", 1.1, -0.7, 0.87);
}

TEST_CASE("Effects: inertia error changes J only", "[effects]") {
  const DoorModel model = with_effects(R"({"inertia_error": {"delta_J": 0.3}})");
  // J + ΔJ = 0.95 + 0.3 = 1.25.
  CHECK_THAT(model.inertia_kg_m2(), WithinRel(1.25, 1e-15));
  CHECK(model.term_count() == 5);  // no torque
  CHECK(model.torque_Nm(0.02, 0.3) == sensory_base().torque_Nm(0.02, 0.3));
  const DoorModel lighter = with_effects(R"({"inertia_error": {"delta_J": -0.45}})");
  CHECK_THAT(lighter.inertia_kg_m2(), WithinRel(0.5, 1e-15));
  // On the physical model: J_d + ΔJ.
  const DoorModel physical = with_effects(R"({"inertia_error": {"delta_J": 0.05}})",
                                          doorbench::reference_model(ModelKind::kPhysical));
  CHECK_THAT(physical.inertia_kg_m2(), WithinRel(1.0, 1e-15));
}

TEST_CASE("Effects: several at once add up", "[effects]") {
  // Constructor route: the base values plus two effects from one file.
  const auto settings = parse_effects_file(
      R"({"viscous_damping": {"b": 0.4}, "force_offset": {"F_off": 2.0},
          "inertia_error": {"delta_J": 0.3}})",
      "effects.json");
  REQUIRE(settings.size() == 3);
  const DoorModel& base = sensory_base();
  const std::vector<double> base_values(base.parameter_values().begin(),
                                        base.parameter_values().begin() + 17);
  const std::vector<doorbench::Bounds> base_bounds(base.parameter_bounds().begin(),
                                                   base.parameter_bounds().begin() + 17);
  const DoorModel model(ModelKind::kSensory, base.geometry(), base_values, base_bounds, settings);
  CHECK(model.term_count() == 7);
  CHECK(model.parameter_count() == 20);
  CHECK_THAT(model.inertia_kg_m2(), WithinRel(1.25, 1e-15));
  // θ = 0.02, ω = 0.5: −0.2 − 1.16 = −1.36 on top of the base.
  CHECK_THAT(model.torque_Nm(0.02, 0.5) - base.torque_Nm(0.02, 0.5), WithinAbs(-1.36, 1e-12));
  // The effect parameters are named after the effect and follow the base's 17.
  const auto b = model.find_parameter("viscous_damping.b");
  const auto f_off = model.find_parameter("force_offset.F_off");
  REQUIRE(b.has_value());
  REQUIRE(f_off.has_value());
  CHECK(*b >= 17);
  CHECK(*f_off >= 17);
  CHECK(model.parameter_values()[*b] == 0.4);
  CHECK(model.parameter_values()[*f_off] == 2.0);
}

TEST_CASE("Effects: with_effect twice replaces, a setting twice is rejected", "[effects]") {
  DoorModel model = with_effects(R"({"viscous_damping": {"b": 0.4}})");
  model = model.with_effect(parse_effects_file(R"({"viscous_damping": {"b": 1.0}})", "e.json")[0]);
  CHECK(model.term_count() == 6);
  CHECK_THAT(model.torque_Nm(0.3, 0.5) - sensory_base().torque_Nm(0.3, 0.5),
             WithinAbs(-0.5, 1e-12));  // −1.0 · 0.5, not −1.4 · 0.5
  const DoorModel& base = sensory_base();
  const std::vector<double> values(base.parameter_values().begin(), base.parameter_values().end());
  const std::vector<doorbench::Bounds> bounds(base.parameter_bounds().begin(),
                                              base.parameter_bounds().end());
  const EffectSetting damping{effects::Kind::kViscousDamping, {0.4}, {{0.0, 5.0}}};
  CHECK_THROWS_WITH(
      DoorModel(ModelKind::kSensory, base.geometry(), values, bounds, {damping, damping}),
      std::string("effect viscous_damping is switched on twice"));
}

TEST_CASE("Effects: unknown names and unknown or missing parameters are rejected", "[effects]") {
  CHECK_THROWS_AS(parse_effects_file(R"({"coulomb": {"d": 1}})", "effects.json"),
                  doorbench::ParameterFileError);
  CHECK_THROWS_WITH(
      parse_effects_file(R"({"coulomb": {"d": 1}})", "effects.json"),
      StartsWith("effects.json: coulomb: unknown effect") && Contains("viscous_damping"));
  CHECK_THROWS_WITH(parse_effects_file(R"({"viscous_damping": {"b": 0.1, "q": 1}})", "fx.json"),
                    std::string("fx.json: viscous_damping.q: unknown parameter"));
  CHECK_THROWS_WITH(parse_effects_file(R"({"stribeck": {"d_s": 3}})", "effects.json"),
                    std::string("effects.json: stribeck.w_s: missing parameter"));
  CHECK_THROWS_WITH(parse_effects_file(R"({"viscous_damping": {"b": "high"}})", "effects.json"),
                    StartsWith("effects.json: viscous_damping.b: expected"));
  CHECK_THROWS_WITH(
      parse_effects_file(R"({"viscous_damping": {"b": {"value": 1, "bounds": [3, 1]}}})",
                         "effects.json"),
      StartsWith("effects.json: viscous_damping.b.bounds:"));
  CHECK_THROWS_WITH(parse_effects_file(R"({"viscous_damping": 0.4})", "effects.json"),
                    StartsWith("effects.json: viscous_damping: expected an object"));
}

TEST_CASE("Effects: values that break an effect's limits are rejected", "[effects]") {
  auto add = [](std::string_view json) { return with_effects(json); };
  CHECK_THROWS_WITH(add(R"({"viscous_damping": {"b": -1}})"),
                    std::string("effect parameter viscous_damping.b = -1 breaks "
                                "viscous_damping.b >= 0"));
  CHECK_THROWS_WITH(add(R"({"stribeck": {"d_s": 3, "w_s": 0}})"),
                    std::string("effect parameter stribeck.w_s = 0 breaks stribeck.w_s > 0"));
  CHECK_THROWS_WITH(add(R"({"soft_close": {"b_sc": 1, "theta_sc": 0.1, "beta_sc": 0}})"),
                    std::string("effect parameter soft_close.beta_sc = 0 breaks "
                                "soft_close.beta_sc > 0"));
  // J + ΔJ = 0.95 − 1 ≤ 0.
  CHECK_THROWS_WITH(add(R"({"inertia_error": {"delta_J": -1}})"),
                    std::string("effect inertia_error.delta_J = -1 makes the inertia "
                                "J + delta_J not positive"));
  CHECK_THROWS_AS(add(R"({"viscous_damping": {"b": -1}})"), std::invalid_argument);
}
