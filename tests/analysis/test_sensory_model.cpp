// The simplified (sensory) model of door-models.md §2 on the reference door, each term
// worked out by hand, and every constraint of the §2 table.
#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <string>
#include <vector>

#include "analysis/model/door_model.h"
#include "analysis/model/parameter_file.h"
#include "analysis/model/sensory_model.h"

using Catch::Matchers::WithinAbs;
using Catch::Matchers::WithinRel;
using doorbench::Bounds;
using doorbench::DoorGeometry;
using doorbench::DoorModel;
using doorbench::ModelKind;

namespace {

// reference-door.json, written out: J, k, k_inf, k_lock, theta0..theta3, c, d1, d2, s,
// theta4, beta, beta_f, k_stop, c_stop.
const std::vector<double> kReference = {0.95,   40.0,    1054.0, 767.0,  0.00698, 0.02793,
                                        0.0384, 0.06109, 3.0,    2.6,    1.3,     25.0,
                                        0.6109, 3000.0,  10.0,   5000.0, 20.0};
const DoorGeometry kGeometry{0.58, 1.5708};
// clang-format off
enum { kJ, kK, kKInf, kKLock, kT0, kT1, kT2, kT3, kC, kD1, kD2, kS, kT4, kBeta, kBetaF, kKStop,
       kCStop };
// clang-format on
enum { kUnlatch, kSnap, kLatch, kFriction, kStops };

std::vector<Bounds> wide_bounds() {
  return std::vector<Bounds>(kReference.size(), {-1e9, 1e9});
}

DoorModel model_with(int index, double value) {
  std::vector<double> values = kReference;
  values[index] = value;
  return DoorModel(ModelKind::kSensory, kGeometry, values, wide_bounds());
}

const DoorModel& wide_sensory_reference() {
  static const DoorModel model(ModelKind::kSensory, kGeometry, kReference, wide_bounds());
  return model;
}

std::array<double, 5> terms_at(double theta, double omega) {
  std::array<double, 5> terms{};
  wide_sensory_reference().torque_Nm(theta, omega, terms);
  return terms;
}

std::array<double, 17> as_array(const std::vector<double>& v) {
  std::array<double, 17> a{};
  for (std::size_t i = 0; i < a.size(); ++i) a[i] = v[i];
  return a;
}

}  // namespace

TEST_CASE("Sensory: the reference door has 5 terms and J = 0.95", "[sensory]") {
  REQUIRE(wide_sensory_reference().term_count() == 5);
  CHECK(wide_sensory_reference().inertia_kg_m2() == 0.95);
  // The compiled-in reference door carries the same values as the spec's file.
  const DoorModel shipped = doorbench::reference_model(ModelKind::kSensory);
  REQUIRE(shipped.parameter_count() == 17);
  for (int i = 0; i < 17; ++i) CHECK(shipped.parameter_values()[i] == kReference[i]);
  CHECK(shipped.geometry().handle_radius_m == 0.58);
  CHECK(shipped.geometry().theta_max_rad == 1.5708);
  // beta sets how sharp the latch's switches are (the fit's softer-switch starts lower it).
  REQUIRE(shipped.switch_sharpness_index().has_value());
  CHECK(shipped.parameter_name(*shipped.switch_sharpness_index()) == "beta");
}

TEST_CASE("Sensory: unlatching term in the stiff zone", "[sensory]") {
  // θ = 0.02, between θ0 = 0.00698 and θ1 = 0.02793, ≥ 39 switch widths from each:
  // τ_o = −(40 · 0.02 + 1054 · (0.02 − 0.00698)) = −(0.8 + 13.72308) = −14.52308.
  auto t = terms_at(0.02, 0.0);
  CHECK_THAT(t[kUnlatch], WithinRel(-14.52308, 1e-9));
  // Soft zone, θ = 0.003 (β (θ0 − θ) = 11.9, S(θ; θ0) ≈ 4.5e−11):
  // τ_o = −(40 · 0.003 + 1054 · (−0.00398) · 4.5e−11) = −0.12 to 1e−9.
  t = terms_at(0.003, 0.0);
  CHECK_THAT(t[kUnlatch], WithinAbs(-0.12, 1e-9));
  // Well past θ1 (θ = 0.05): released, 0.
  t = terms_at(0.05, 0.0);
  CHECK_THAT(t[kUnlatch], WithinAbs(0.0, 1e-12));
  // At θ1 itself S̄ = ½: τ_o = −½ (40 · 0.02793 + 1054 · 0.02095) = −½ · 23.1985 = −11.59925.
  t = terms_at(0.02793, 0.0);
  CHECK_THAT(t[kUnlatch], WithinRel(-11.59925, 1e-9));
  // It does not depend on ω.
  CHECK_THAT(terms_at(0.02, -0.7)[kUnlatch], WithinRel(-14.52308, 1e-9));
}

TEST_CASE("Sensory: snap term in the middle of the snap zone", "[sensory]") {
  // θ = (θ1 + θ2)/2 = 0.033165, 15.7 widths from both edges: W = 1 − 4.6e−14.
  // τ_t = + c ω W = 3 · ω.
  CHECK_THAT(terms_at(0.033165, 0.5)[kSnap], WithinRel(1.5, 1e-12));
  CHECK_THAT(terms_at(0.033165, -0.2)[kSnap], WithinRel(-0.6, 1e-12));
  // It pushes along the motion (negative damping): same sign as ω.
  CHECK(terms_at(0.035, 0.1)[kSnap] > 0.0);
  CHECK(terms_at(0.035, -0.1)[kSnap] < 0.0);
  // Outside the zone: nothing (θ = 0.02 and θ = 0.05 are ≥ 23 widths outside).
  CHECK_THAT(terms_at(0.02, 0.5)[kSnap], WithinAbs(0.0, 1e-12));
  CHECK_THAT(terms_at(0.05, 0.5)[kSnap], WithinAbs(0.0, 1e-12));
  // At θ2 the window is ½: 3 · 0.4 · ½ = 0.6.
  CHECK_THAT(terms_at(0.0384, 0.4)[kSnap], WithinRel(0.6, 1e-9));
}

TEST_CASE("Sensory: latching term in the middle of the latching zone", "[sensory]") {
  // θ = (θ2 + θ3)/2 = 0.049745: τ_c = 767 · (0.06109 − 0.049745) = 767 · 0.011345 = 8.701615.
  CHECK_THAT(terms_at(0.049745, 0.0)[kLatch], WithinRel(8.701615, 1e-12));
  // θ = 0.045: 767 · 0.01609 = 12.34103 (pushes the door open, whatever ω).
  CHECK_THAT(terms_at(0.045, -0.4)[kLatch], WithinRel(12.34103, 1e-12));
  // Outside: 0 (below θ2 by 0.0184 and beyond θ3 by 0.039).
  CHECK_THAT(terms_at(0.02, 0.0)[kLatch], WithinAbs(0.0, 1e-12));
  CHECK_THAT(terms_at(0.1, 0.0)[kLatch], WithinAbs(0.0, 1e-12));
}

TEST_CASE("Sensory: friction when open and near closed", "[sensory]") {
  // τ_f = − tanh(25 ω) (2.6 − 1.3 S̄(θ; 0.6109, 10)).
  // At θ = θ4, S̄ = ½ and tanh(25) = 1 − 4e−22: τ_f = −(2.6 − 0.65) = −1.95, sign opposes ω.
  CHECK_THAT(terms_at(0.6109, 1.0)[kFriction], WithinRel(-1.95, 1e-12));
  CHECK_THAT(terms_at(0.6109, -1.0)[kFriction], WithinRel(1.95, 1e-12));
  // Open, θ = 1.5: S̄ = ½ (1 − tanh 8.891) = 1.894e−8, τ_f = −(2.6 − 2.46e−8) = −2.59999997537825.
  CHECK_THAT(terms_at(1.5, 1.0)[kFriction], WithinRel(-2.5999999753782529, 1e-12));
  // Near closed, θ = 0.1: S̄ = ½ (1 + tanh 5.109) = 1 − 3.65e−5,
  // τ_f = −(2.6 − 1.3 (1 − 3.65e−5)) = −1.30004745767759.
  CHECK_THAT(terms_at(0.1, 1.0)[kFriction], WithinRel(-1.3000474576775947, 1e-12));
  // Slow, closing: tanh(25 · −0.02) = −tanh(0.5) = −0.46211715726,
  // τ_f = 0.46211715726 · 1.30004745767759 = 0.60077423544507.
  CHECK_THAT(terms_at(0.1, -0.02)[kFriction], WithinRel(0.60077423544507291, 1e-12));
  // No friction at rest.
  CHECK(terms_at(0.3, 0.0)[kFriction] == 0.0);
  // Larger when open than near closed (d1 > d1 − d2).
  CHECK(std::abs(terms_at(1.2, 0.5)[kFriction]) > std::abs(terms_at(0.2, 0.5)[kFriction]));
}

TEST_CASE("Sensory: end stops beyond theta_max and below 0", "[sensory]") {
  // θ = 1.6 > θ_max = 1.5708: −(5000 · 0.0292 + 20 · 0.1) = −(146 + 2) = −148.
  CHECK_THAT(terms_at(1.6, 0.1)[kStops], WithinRel(-148.0, 1e-9));
  // θ = −0.01 < 0, ω = −0.2: −(5000 · −0.01 + 20 · −0.2) = 54.
  CHECK_THAT(terms_at(-0.01, -0.2)[kStops], WithinRel(54.0, 1e-12));
  // In between: nothing, even when moving.
  CHECK(terms_at(0.5, 1.0)[kStops] == 0.0);
  CHECK(terms_at(0.0, -1.0)[kStops] == 0.0);
  CHECK(terms_at(1.5708, 1.0)[kStops] == 0.0);
}

TEST_CASE("Sensory: tau_m is the sum of the five terms", "[sensory]") {
  // θ = 0.02, ω = 0: only the unlatching term: −14.52308.
  CHECK_THAT(wide_sensory_reference().torque_Nm(0.02, 0.0), WithinRel(-14.52308, 1e-9));
  // θ = 0.045, ω = −0.4: latch 12.34103, friction −tanh(−10) · (2.6 − 1.3 · S̄(0.045; θ4, 10))
  // = +1.30001579231425, snap ≈ −8e−18: 13.64104579231425.
  CHECK_THAT(wide_sensory_reference().torque_Nm(0.045, -0.4), WithinRel(13.641045792314245, 1e-12));
  // θ = −0.01, ω = −0.2: unlatch +0.4, friction +1.29988722369518, stops +54 = 55.6998872236952.
  CHECK_THAT(wide_sensory_reference().torque_Nm(-0.01, -0.2), WithinRel(55.699887223695178, 1e-12));
  // θ = 1.6, ω = 0.1: friction −tanh(2.5) (2.6 − 1.3 S̄) = −2.56519717190613, stops −148.
  CHECK_THAT(wide_sensory_reference().torque_Nm(1.6, 0.1), WithinRel(-150.56519717190613, 1e-12));
  // And the terms add to the total everywhere.
  for (double theta : {-0.02, 0.0, 0.005, 0.01, 0.028, 0.035, 0.04, 0.06, 0.3, 0.6, 1.4, 1.6}) {
    for (double omega : {-1.0, -0.03, 0.0, 0.02, 0.8}) {
      std::array<double, 5> t{};
      const double total = wide_sensory_reference().torque_Nm(theta, omega, t);
      CHECK_THAT(total, WithinAbs(t[0] + t[1] + t[2] + t[3] + t[4], 1e-12));
      CHECK(wide_sensory_reference().torque_Nm(theta, omega) == total);
    }
  }
}

TEST_CASE("Sensory: peak unlatch and latch forces", "[sensory]") {
  const auto values = as_array(kReference);
  // (k θ1 + k_inf (θ1 − θ0)) / r_h = (40 · 0.02793 + 1054 · 0.02095) / 0.58
  //   = (1.1172 + 22.0813) / 0.58 = 23.1985 / 0.58 = 39.99741379310345 N.
  CHECK_THAT(doorbench::sensory::peak_unlatch_force_N(values, kGeometry),
             WithinRel(39.997413793103448, 1e-12));
  // k_lock (θ3 − θ2) / r_h = 767 · 0.02269 / 0.58 = 17.40323 / 0.58 = 30.00556896551724 N.
  CHECK_THAT(doorbench::sensory::peak_latch_force_N(values, kGeometry),
             WithinRel(30.005568965517241, 1e-12));
  // "About": the model's largest unlatching force is within 10% of the formula.
  double largest = 0.0;
  for (int i = 0; i <= 4000; ++i) {
    const double theta = 0.04 * i / 4000.0;
    largest = std::max(largest, -terms_at(theta, 0.0)[kUnlatch] / 0.58);
  }
  CHECK(largest < 39.9974);
  CHECK(largest > 0.9 * 39.9974);
}

TEST_CASE("Sensory: every constraint of the parameter table is enforced", "[sensory]") {
  using M = std::string;
  CHECK_THROWS_WITH(model_with(kJ, 0.0), M("sensory parameter J = 0 breaks J > 0"));
  CHECK_THROWS_WITH(model_with(kJ, -0.5), M("sensory parameter J = -0.5 breaks J > 0"));
  CHECK_THROWS_WITH(model_with(kK, -1.0), M("sensory parameter k = -1 breaks k >= 0"));
  CHECK_THROWS_WITH(model_with(kKInf, -2.5), M("sensory parameter k_inf = -2.5 breaks k_inf >= 0"));
  CHECK_THROWS_WITH(model_with(kKLock, -3.0),
                    M("sensory parameter k_lock = -3 breaks k_lock >= 0"));
  CHECK_THROWS_WITH(model_with(kT0, 0.0),
                    M("sensory parameter theta0 = 0 breaks 0 < theta0 < theta1"));
  CHECK_THROWS_WITH(model_with(kT0, 0.03),
                    M("sensory parameter theta0 = 0.03 breaks 0 < theta0 < theta1 "
                      "(theta1 = 0.02793)"));
  CHECK_THROWS_WITH(model_with(kT0, 0.02793),
                    M("sensory parameter theta0 = 0.02793 breaks 0 < theta0 < theta1 "
                      "(theta1 = 0.02793)"));
  CHECK_THROWS_WITH(model_with(kT1, 0.04),
                    M("sensory parameter theta1 = 0.04 breaks theta1 < theta2 (theta2 = 0.0384)"));
  CHECK_THROWS_WITH(model_with(kT2, 0.07),
                    M("sensory parameter theta2 = 0.07 breaks theta2 < theta3 (theta3 = 0.06109)"));
  CHECK_THROWS_WITH(model_with(kT3, 1.6),
                    M("sensory parameter theta3 = 1.6 breaks theta3 < theta_max "
                      "(theta_max = 1.5708)"));
  CHECK_THROWS_WITH(model_with(kT3, 1.5708),
                    M("sensory parameter theta3 = 1.5708 breaks theta3 < theta_max "
                      "(theta_max = 1.5708)"));
  CHECK_THROWS_WITH(model_with(kC, -0.1), M("sensory parameter c = -0.1 breaks c >= 0"));
  CHECK_THROWS_WITH(model_with(kD1, 1.0),
                    M("sensory parameter d1 = 1 breaks d1 >= d2 >= 0 (d2 = 1.3)"));
  CHECK_THROWS_WITH(model_with(kD2, -0.2), M("sensory parameter d2 = -0.2 breaks d1 >= d2 >= 0"));
  CHECK_THROWS_WITH(model_with(kS, 0.0), M("sensory parameter s = 0 breaks s > 0"));
  CHECK_THROWS_WITH(model_with(kT4, 0.0),
                    M("sensory parameter theta4 = 0 breaks 0 < theta4 < theta_max"));
  CHECK_THROWS_WITH(model_with(kT4, 2.0),
                    M("sensory parameter theta4 = 2 breaks 0 < theta4 < theta_max "
                      "(theta_max = 1.5708)"));
  CHECK_THROWS_WITH(model_with(kBeta, 0.0), M("sensory parameter beta = 0 breaks beta > 0"));
  CHECK_THROWS_WITH(model_with(kBetaF, -10.0),
                    M("sensory parameter beta_f = -10 breaks beta_f > 0"));
  CHECK_THROWS_WITH(model_with(kKStop, 0.0), M("sensory parameter k_stop = 0 breaks k_stop > 0"));
  CHECK_THROWS_WITH(model_with(kCStop, -1.0),
                    M("sensory parameter c_stop = -1 breaks c_stop >= 0"));
  // A value that is not a number at all.
  CHECK_THROWS_WITH(model_with(kC, std::nan("")),
                    Catch::Matchers::StartsWith("sensory parameter c = ") &&
                        Catch::Matchers::Contains("not a finite number"));
  // The error type is std::invalid_argument.
  CHECK_THROWS_AS(model_with(kJ, 0.0), std::invalid_argument);
}

TEST_CASE("Sensory: the edges of the constraints that allow equality are accepted", "[sensory]") {
  CHECK_NOTHROW(model_with(kK, 0.0));
  CHECK_NOTHROW(model_with(kKInf, 0.0));
  CHECK_NOTHROW(model_with(kKLock, 0.0));
  CHECK_NOTHROW(model_with(kC, 0.0));
  CHECK_NOTHROW(model_with(kD2, 0.0));
  CHECK_NOTHROW(model_with(kD1, 1.3));  // d1 = d2
  CHECK_NOTHROW(model_with(kCStop, 0.0));
  // Parameters only checked against each other: the same change with other values passes.
  std::vector<double> values = kReference;
  values[kT3] = 1.5;
  values[kT4] = 1.57;
  CHECK_NOTHROW(DoorModel(ModelKind::kSensory, kGeometry, values, wide_bounds()));
}

TEST_CASE("Sensory: a broken geometry is rejected", "[sensory]") {
  CHECK_THROWS_WITH(
      DoorModel(ModelKind::kSensory, DoorGeometry{0.0, 1.5708}, kReference, wide_bounds()),
      std::string("door parameter handle_radius_m = 0 breaks handle_radius_m > 0"));
  CHECK_THROWS_WITH(
      DoorModel(ModelKind::kSensory, DoorGeometry{0.58, -1.0}, kReference, wide_bounds()),
      std::string("door parameter theta_max_rad = -1 breaks theta_max_rad > 0"));
}
