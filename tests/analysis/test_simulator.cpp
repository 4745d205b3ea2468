// The simulator (analysis/simulation/simulator.h), the virtual hand
// (analysis/simulation/virtual_hand.h) and the run summary (analysis/simulation/run_summary.h):
// energy balance, order of convergence, accuracy through the latch, replay of a recorded force,
// exact solutions and every message.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "analysis/model/door_model.h"
#include "analysis/model/parameter_file.h"
#include "analysis/model/physical_model.h"
#include "analysis/model/sensory_model.h"
#include "analysis/simulation/run_summary.h"
#include "analysis/simulation/simulator.h"
#include "analysis/simulation/trajectory_io.h"
#include "analysis/simulation/virtual_hand.h"
#include "tests/support/allocation_counter.h"

using Catch::Matchers::Contains;
using Catch::Matchers::Equals;
using Catch::Matchers::WithinAbs;
using Catch::Matchers::WithinRel;
using doorbench::DoorModel;
using doorbench::DoorState;
using doorbench::DoorStepper;
using doorbench::ModelKind;
using doorbench::RecordedForce;
using doorbench::SimulationOptions;
using doorbench::Trajectory;
using doorbench::UserForce;
using doorbench::VirtualHand;
using doorbench::VirtualHandOptions;

namespace {

constexpr double kPi = std::numbers::pi;

std::vector<double> uniform_times(double start_s, double end_s, std::size_t intervals) {
  std::vector<double> times(intervals + 1);
  for (std::size_t i = 0; i <= intervals; ++i) {
    times[i] =
        start_s + (end_s - start_s) * static_cast<double>(i) / static_cast<double>(intervals);
  }
  times.back() = end_s;
  return times;
}

// The reference physical door with every dissipative and latch/seal part switched off:
// T_h = b_h = mu_g = 0, k_l = F_l0 = 0, k_seal = 0. Gravity, the balancing spring and the
// end stops (which never act for 0 < θ < θ_max) remain, all conservative.
DoorModel frictionless_physical_door() {
  const DoorModel reference = doorbench::reference_model(ModelKind::kPhysical);
  std::vector<double> values(reference.parameter_values().begin(),
                             reference.parameter_values().end());
  namespace p = doorbench::physical;
  for (int index : {p::kTh, p::kBh, p::kMuG, p::kKl, p::kFl0, p::kKSeal}) values[index] = 0.0;
  return reference.with_parameter_values(values);
}

// The potential energy of the frictionless door, worked from the spec (§3), not from the
// model's code: gravity τ = +m_d g l_c sin θ = −dV/dθ gives V = m_d g l_c cos θ; the spring
// (tension F0 + k_s (L − L0) for L ≥ L0) stores F0 (L − L0) + ½ k_s (L − L0)².
double potential_energy_J(const DoorModel& model, double theta) {
  namespace p = doorbench::physical;
  const auto v = model.parameter_values();
  const double gravity = v[p::kMassDoor] * p::kGravity_m_s2 * v[p::kLc] * std::cos(theta);
  const double b_x = v[p::kBu] * std::sin(theta) + v[p::kBv] * std::cos(theta);
  const double b_y = v[p::kBu] * std::cos(theta) - v[p::kBv] * std::sin(theta);
  const double length = std::hypot(v[p::kAx] - b_x, v[p::kAy] - b_y);
  const double stretch = std::max(0.0, length - v[p::kL0]);
  return gravity + v[p::kF0] * stretch + 0.5 * v[p::kKs] * stretch * stretch;
}

// A smooth hand: a PD grip on the handle tracking a raised-cosine move from `from` to
// `to` over `duration`, held afterwards. Everything is infinitely differentiable in t, θ
// and ω on [0, duration], which the convergence study needs.
class SmoothHand final : public UserForce {
 public:
  SmoothHand(double from, double to, double duration, double handle_radius_m,
             double stiffness_N_per_m = 800.0, double damping_N_s_per_m = 40.0)
      : from_(from),
        to_(to),
        duration_(duration),
        r_h_(handle_radius_m),
        stiffness_(stiffness_N_per_m),
        damping_(damping_N_s_per_m) {}
  double force_N(double t, double theta, double omega) const override {
    const double phase = kPi * std::min(t, duration_) / duration_;
    const double theta_ref = from_ + (to_ - from_) * 0.5 * (1.0 - std::cos(phase));
    const double omega_ref =
        t < duration_ ? (to_ - from_) * 0.5 * kPi / duration_ * std::sin(phase) : 0.0;
    return stiffness_ * r_h_ * (theta_ref - theta) + damping_ * r_h_ * (omega_ref - omega);
  }

 private:
  double from_, to_, duration_, r_h_;
  double stiffness_;  // N/m along the handle's arc
  double damping_;    // N*s/m
};

SimulationOptions tolerances_tighter_by(double factor) {
  SimulationOptions options;
  options.relative_tolerance /= factor;
  options.angle_tolerance_rad /= factor;
  options.rate_tolerance_rad_s /= factor;
  return options;
}

Trajectory hand_run(const DoorModel& model, const SimulationOptions& options,
                    const VirtualHandOptions& hand_options = {}) {
  const VirtualHand hand(hand_options, model.geometry().handle_radius_m);
  const std::vector<double> times =
      uniform_times(0.0, hand.duration_s(), static_cast<std::size_t>(hand.duration_s() * 1000));
  return doorbench::simulate(model, hand, DoorState{}, times, options);
}

double max_abs_difference(const std::vector<double>& a, const std::vector<double>& b,
                          std::size_t count) {
  double largest = 0.0;
  for (std::size_t i = 0; i < count; ++i) largest = std::max(largest, std::abs(a[i] - b[i]));
  return largest;
}

double max_abs_difference(const std::vector<double>& a, const std::vector<double>& b) {
  REQUIRE(a.size() == b.size());
  return max_abs_difference(a, b, a.size());
}

}  // namespace

// ---------------------------------------------------------------------------------------
// 1. Energy balance
// ---------------------------------------------------------------------------------------

TEST_CASE("Simulator: on a frictionless door the user's work is the change of energy",
          "[simulator][energy]") {
  const DoorModel door = frictionless_physical_door();
  const double r_h = door.geometry().handle_radius_m;
  const double inertia = door.inertia_kg_m2();
  // From 0.2 rad to 1.3 rad in 2 s, then 0.5 s of holding.
  const SmoothHand hand(0.2, 1.3, 2.0, r_h);
  const DoorState initial{0.0, 0.2, 0.0, 0.0};
  const std::vector<double> times = uniform_times(0.0, 2.5, 25000);  // 0.1 ms output
  // Tight tolerances: the balance then tests the energy bookkeeping (user_work_J rides
  // along in the Runge–Kutta stages), not the integrator's default accuracy.
  SimulationOptions options = tolerances_tighter_by(1000.0);
  const Trajectory run = doorbench::simulate(door, hand, initial, times, options);

  // The stops must never act: the door stays strictly inside 0 < θ < θ_max.
  const auto [lowest, highest] = std::minmax_element(run.theta_rad.begin(), run.theta_rad.end());
  REQUIRE(*lowest > 0.1);
  REQUIRE(*highest < door.geometry().theta_max_rad - 0.1);
  REQUIRE(*highest > 1.2);  // a large range: the spring and gravity change a lot

  const double theta_end = run.theta_rad.back();
  const double omega_end = run.omega_rad_s.back();
  const double kinetic_change = 0.5 * inertia * (omega_end * omega_end - 0.0);
  const double potential_change =
      potential_energy_J(door, theta_end) - potential_energy_J(door, initial.theta_rad);
  const double energy_change = kinetic_change + potential_change;

  // The work of τ_u, independently: the trapezoid rule over the output's τ_u·ω at 0.1 ms.
  // By Euler–Maclaurin its error is about h²/12 · (f'(T) − f'(0)) with f = τ_u ω; the door
  // starts at rest with no force and ends nearly at rest, so this is ~1e-10 J or less
  // (measured 4e-11 J).
  double trapezoid_J = 0.0;
  for (std::size_t i = 1; i < run.size(); ++i) {
    const double dt = run.time_s[i] - run.time_s[i - 1];
    trapezoid_J +=
        0.5 * dt *
        (run.tau_u_Nm[i] * run.omega_rad_s[i] + run.tau_u_Nm[i - 1] * run.omega_rad_s[i - 1]);
  }
  // τ_u recorded by the simulator is r_h F_u of the hand at the output state.
  CHECK_THAT(run.tau_u_Nm[1234], WithinRel(r_h * run.force_N[1234], 1e-15));

  const double work = run.user_work_J;
  WARN("energy balance: work of tau_u " << work << " J (trapezoid " << trapezoid_J
                                        << " J), dKE + dPE = " << energy_change << " J, residual "
                                        << work - energy_change << " J, trapezoid residual "
                                        << trapezoid_J - energy_change << " J");
  // The energy changes by several joules, so the balance is far from trivially 0 = 0.
  REQUIRE(std::abs(potential_change) > 1.0);
  // Tolerances. The integrated work: 1e-9 of the work (4e-9 J). Round-off over the
  // ~25000 steps is at most ~25000 · 1e-16 · 4 J = 1e-11 J, and at 1000× tighter
  // tolerances the state is accurate to ~1e-12; a modelling or bookkeeping slip (a sign or
  // a factor in the spring or gravity torque, the work of the wrong torque or state) shows
  // far above 1e-9. Measured: ~1e-14 J. The trapezoid: 1e-8 of the work (4e-8 J),
  // a hundred times its own error estimate above.
  CHECK(std::abs(work - energy_change) < 1e-9 * std::abs(work));
  CHECK(std::abs(trapezoid_J - energy_change) < 1e-8 * std::abs(work));
  // At the default tolerances, with only the end as output (so steps up to max_step_s),
  // the balance holds to the integrator's accuracy; allowed 1e-7 of the work (measured
  // ~1e-14 J: steps of at most 1 ms are tiny for this smooth motion).
  const std::vector<double> ends = {0.0, 2.5};
  const Trajectory default_run = doorbench::simulate(door, hand, initial, ends);
  const double default_residual =
      default_run.user_work_J -
      (0.5 * inertia * default_run.omega_rad_s.back() * default_run.omega_rad_s.back() +
       potential_energy_J(door, default_run.theta_rad.back()) -
       potential_energy_J(door, initial.theta_rad));
  WARN("energy balance at the default tolerances: residual " << default_residual << " J");
  CHECK(std::abs(default_residual) < 1e-7 * std::abs(work));
  // And the stepper's DoorState carries the same work as the Trajectory.
  DoorState state = initial;
  DoorStepper stepper(door, options);
  stepper.advance(state, 2.5, hand);
  CHECK_THAT(state.user_work_J, WithinRel(work, 1e-7));
  CHECK_THAT(state.theta_rad, WithinAbs(theta_end, 1e-8));
}

// ---------------------------------------------------------------------------------------
// 2. Order of convergence
// ---------------------------------------------------------------------------------------

TEST_CASE("Simulator: the fixed-step method converges at 5th order", "[simulator][order]") {
  const DoorModel door = frictionless_physical_door();
  const SmoothHand hand(0.2, 1.2, 1.0, door.geometry().handle_radius_m);
  const DoorState initial{0.0, 0.2, 0.0, 0.0};
  constexpr double kEnd = 1.0;  // the move's end: the hand is smooth up to here
  const std::vector<double> times = {0.0, kEnd};

  auto final_state = [&](double step) {
    SimulationOptions options;
    options.method = SimulationOptions::Method::kFixedStep;
    options.fixed_step_s = step;
    const Trajectory run = doorbench::simulate(door, hand, initial, times, options);
    CHECK(run.stats.rejected_steps == 0);
    CHECK(run.stats.accepted_steps == static_cast<long>(std::lround(kEnd / step)));
    return std::pair{run.theta_rad.back(), run.omega_rad_s.back()};
  };
  constexpr double h = 0.02;
  const auto reference = final_state(h / 64);
  const auto coarse = final_state(h);
  const auto medium = final_state(h / 2);
  const auto fine = final_state(h / 4);
  const double e_theta[3] = {std::abs(coarse.first - reference.first),
                             std::abs(medium.first - reference.first),
                             std::abs(fine.first - reference.first)};
  const double e_omega[3] = {std::abs(coarse.second - reference.second),
                             std::abs(medium.second - reference.second),
                             std::abs(fine.second - reference.second)};
  const double order_theta_1 = std::log2(e_theta[0] / e_theta[1]);
  const double order_theta_2 = std::log2(e_theta[1] / e_theta[2]);
  const double order_omega_1 = std::log2(e_omega[0] / e_omega[1]);
  const double order_omega_2 = std::log2(e_omega[1] / e_omega[2]);
  WARN("fixed-step errors at t = 1 s for h = 20, 10, 5 ms: theta "
       << e_theta[0] << ", " << e_theta[1] << ", " << e_theta[2] << " rad; omega " << e_omega[0]
       << ", " << e_omega[1] << ", " << e_omega[2] << " rad/s; measured orders theta "
       << order_theta_1 << ", " << order_theta_2 << "; omega " << order_omega_1 << ", "
       << order_omega_2);
  // The errors are far above round-off (~1e-14 here) and the h/64 reference's own error
  // (about e(h/4) / 16^5 ≈ 1e-17).
  REQUIRE(e_theta[2] > 1e-11);
  REQUIRE(e_omega[2] > 1e-10);
  CHECK(order_theta_1 > 4.5);
  CHECK(order_theta_1 < 5.7);
  CHECK(order_theta_2 > 4.5);
  CHECK(order_theta_2 < 5.7);
  CHECK(order_omega_1 > 4.5);
  CHECK(order_omega_1 < 5.7);
  CHECK(order_omega_2 > 4.5);
  CHECK(order_omega_2 < 5.7);
}

// ---------------------------------------------------------------------------------------
// 3. Accuracy through the latch
// ---------------------------------------------------------------------------------------

TEST_CASE("Simulator: the default tolerances are accurate through the latch",
          "[simulator][accuracy]") {
  for (ModelKind kind : {ModelKind::kSensory, ModelKind::kPhysical}) {
    const DoorModel door = doorbench::reference_model(kind);
    const Trajectory base = hand_run(door, SimulationOptions{});
    for (double factor : {10.0, 1000.0}) {
      const Trajectory tight = hand_run(door, tolerances_tighter_by(factor));
      REQUIRE(tight.size() == 10001);
      const double d_theta = max_abs_difference(base.theta_rad, tight.theta_rad);
      const double d_omega = max_abs_difference(base.omega_rad_s, tight.omega_rad_s);
      WARN(doorbench::to_string(kind)
           << " model, default vs tolerances " << factor << "x tighter: max |d theta| = " << d_theta
           << " rad, max |d omega| = " << d_omega << " rad/s (" << base.stats.accepted_steps
           << " vs " << tight.stats.accepted_steps << " steps)");
      INFO(doorbench::to_string(kind) << " model, tolerances " << factor << "x tighter");
      CHECK(d_theta < 1e-5);
      CHECK(d_omega < 1e-3);
    }
    // The run goes through the latch both ways: opened to the target, then closed.
    CHECK(*std::max_element(base.theta_rad.begin(), base.theta_rad.end()) > 1.3);
    CHECK(base.theta_rad.back() < 0.02);
  }
}

// ---------------------------------------------------------------------------------------
// 4. Recorded-force replay
// ---------------------------------------------------------------------------------------

TEST_CASE("Simulator: replaying the hand's force reproduces the run before the latch",
          "[simulator][replay]") {
  const DoorModel door = doorbench::reference_model(ModelKind::kSensory);
  const Trajectory run = hand_run(door, SimulationOptions{});
  // Through the CSV exchange layout in memory: force, initial state.
  const doorbench::Recording recording = doorbench::to_recording(run, "test");
  const RecordedForce force = doorbench::recorded_force(recording);
  const DoorState initial = doorbench::initial_state(recording);
  CHECK(initial.time_s == 0.0);
  CHECK(initial.theta_rad == run.theta_rad[0]);
  CHECK(initial.omega_rad_s == run.omega_rad_s[0]);
  // The recorded force reads back the hand's force at every sample time.
  for (std::size_t i : {0u, 1000u, 1234u, 5000u, 10000u}) {
    CHECK(force.force_N(run.time_s[i], 0.0, 0.0) == run.force_N[i]);
  }

  const Trajectory replay = doorbench::simulate(door, force, initial, run.time_s);
  constexpr std::size_t kFirst = 1501;  // t <= 1.5 s
  const double d_theta = max_abs_difference(run.theta_rad, replay.theta_rad, kFirst);
  const double d_omega = max_abs_difference(run.omega_rad_s, replay.omega_rad_s, kFirst);
  WARN("replay over the first 1.5 s: max |d theta| = "
       << d_theta << " rad, max |d omega| = " << d_omega << " rad/s; door at "
       << run.theta_rad[kFirst - 1] << " rad at 1.5 s");
  // The door is moving by then: the comparison is not of two doors at rest.
  REQUIRE(run.theta_rad[kFirst - 1] > 0.005);
  CHECK(d_theta < 1e-4);
  CHECK(d_omega < 1e-2);
}

// ---------------------------------------------------------------------------------------
// 5. Simple checks
// ---------------------------------------------------------------------------------------

TEST_CASE("Simulator: a constant force on a free door gives uniform acceleration",
          "[simulator][exact]") {
  const DoorModel reference = doorbench::reference_model(ModelKind::kSensory);
  std::vector<double> values(reference.parameter_values().begin(),
                             reference.parameter_values().end());
  namespace s = doorbench::sensory;
  for (int index : {s::kK, s::kKInf, s::kKLock, s::kC, s::kD1, s::kD2}) values[index] = 0.0;
  const DoorModel door = reference.with_parameter_values(values);
  const double r_h = door.geometry().handle_radius_m;
  const double inertia = door.inertia_kg_m2();
  REQUIRE(door.torque_Nm(0.7, 0.3) == 0.0);  // nothing acts on the free door

  constexpr double kForce = 2.0;
  const RecordedForce force({0.0}, {kForce});  // one sample, held for ever
  const DoorState initial{0.0, 0.5, 0.1, 0.0};
  const std::vector<double> times = uniform_times(0.0, 0.5, 50);
  for (auto method :
       {SimulationOptions::Method::kAdaptive, SimulationOptions::Method::kFixedStep}) {
    SimulationOptions options;
    options.method = method;
    options.fixed_step_s = 1e-3;
    const Trajectory run = doorbench::simulate(door, force, initial, times, options);
    const double acceleration = r_h * kForce / inertia;
    for (std::size_t i = 0; i < run.size(); ++i) {
      const double t = run.time_s[i];
      CHECK_THAT(run.theta_rad[i], WithinAbs(0.5 + 0.1 * t + 0.5 * acceleration * t * t, 1e-9));
      CHECK_THAT(run.omega_rad_s[i], WithinAbs(0.1 + acceleration * t, 1e-9));
      CHECK(run.force_N[i] == kForce);
    }
    // The work of the constant torque is τ_u Δθ.
    CHECK_THAT(run.user_work_J, WithinAbs(r_h * kForce * (run.theta_rad.back() - 0.5), 1e-9));
    CHECK(run.theta_rad.back() < door.geometry().theta_max_rad);
  }
}

TEST_CASE("Simulator: a recorded force interpolates linearly and holds its ends",
          "[simulator][recorded]") {
  const RecordedForce force({0.0, 1.0, 3.0}, {10.0, 20.0, -20.0});
  CHECK(force.force_N(-1.0, 0.0, 0.0) == 10.0);
  CHECK(force.force_N(0.0, 0.0, 0.0) == 10.0);
  CHECK_THAT(force.force_N(0.25, 0.0, 0.0), WithinAbs(12.5, 1e-12));
  CHECK(force.force_N(1.0, 0.0, 0.0) == 20.0);
  CHECK_THAT(force.force_N(2.0, 0.0, 0.0), WithinAbs(0.0, 1e-12));
  CHECK_THAT(force.force_N(2.5, 5.0, -3.0), WithinAbs(-10.0, 1e-12));  // the state is ignored
  CHECK(force.force_N(3.0, 0.0, 0.0) == -20.0);
  CHECK(force.force_N(100.0, 0.0, 0.0) == -20.0);

  CHECK_THROWS_WITH(RecordedForce({0.0, 1.0, 1.0}, {1.0, 2.0, 3.0}),
                    Equals("recorded force: time 1 s is not after 1 s"));
  CHECK_THROWS_WITH(RecordedForce({0.0, 2.0, 1.5}, {1.0, 2.0, 3.0}),
                    Equals("recorded force: time 1.5 s is not after 2 s"));
  CHECK_THROWS_WITH(RecordedForce({0.0, std::nan(""), 1.5}, {1.0, 2.0, 3.0}),
                    Contains("is not after 0 s"));
  CHECK_THROWS_WITH(RecordedForce({0.0, 1.0}, {1.0}),
                    Equals("recorded force needs as many forces as times, and at least one"));
  CHECK_THROWS_WITH(RecordedForce({}, {}),
                    Equals("recorded force needs as many forces as times, and at least one"));
  CHECK_THROWS_AS(RecordedForce({0.0, 0.0}, {1.0, 1.0}), std::invalid_argument);
}

TEST_CASE("Simulator: options are validated with a message naming the option",
          "[simulator][options]") {
  CHECK(SimulationOptions{}.validate().empty());
  auto message_with = [](auto change) {
    SimulationOptions options;
    change(options);
    return options.validate();
  };
  CHECK(message_with([](SimulationOptions& o) { o.relative_tolerance = 0; }) ==
        "simulation option relative_tolerance must be > 0");
  CHECK(message_with([](SimulationOptions& o) { o.relative_tolerance = std::nan(""); }) ==
        "simulation option relative_tolerance must be > 0");
  CHECK(message_with([](SimulationOptions& o) { o.angle_tolerance_rad = -1e-9; }) ==
        "simulation option angle_tolerance_rad must be > 0");
  CHECK(message_with([](SimulationOptions& o) { o.rate_tolerance_rad_s = 0; }) ==
        "simulation option rate_tolerance_rad_s must be > 0");
  CHECK(message_with([](SimulationOptions& o) { o.max_step_s = INFINITY; }) ==
        "simulation option max_step_s must be > 0");
  CHECK(message_with([](SimulationOptions& o) { o.min_step_s = 0; }) ==
        "simulation option min_step_s must be > 0 and at most max_step_s");
  CHECK(message_with([](SimulationOptions& o) { o.min_step_s = 2e-3; }) ==
        "simulation option min_step_s must be > 0 and at most max_step_s");
  CHECK(message_with([](SimulationOptions& o) { o.fixed_step_s = -1e-4; }) ==
        "simulation option fixed_step_s must be > 0");

  // The stepper (and so simulate) refuses them with the same message.
  const DoorModel door = doorbench::reference_model(ModelKind::kSensory);
  SimulationOptions bad;
  bad.fixed_step_s = 0;
  CHECK_THROWS_WITH(DoorStepper(door, bad), Equals("simulation option fixed_step_s must be > 0"));
  const RecordedForce none({0.0}, {0.0});
  const std::vector<double> times = {0.0, 0.1};
  CHECK_THROWS_WITH(doorbench::simulate(door, none, DoorState{}, times, bad),
                    Equals("simulation option fixed_step_s must be > 0"));
}

TEST_CASE("Simulator: simulate rejects bad output times", "[simulator][options]") {
  const DoorModel door = doorbench::reference_model(ModelKind::kSensory);
  const RecordedForce none({0.0}, {0.0});
  const DoorState initial{0.5, 0.0, 0.0, 0.0};
  const std::vector<double> empty;
  CHECK_THROWS_WITH(doorbench::simulate(door, none, initial, empty),
                    Equals("simulate: no output times"));
  const std::vector<double> late_start = {0.6, 0.7};
  CHECK_THROWS_WITH(doorbench::simulate(door, none, initial, late_start),
                    Equals("simulate: the first output time must be the initial state's"));
  const std::vector<double> repeated = {0.5, 0.75, 0.75};
  CHECK_THROWS_WITH(doorbench::simulate(door, none, initial, repeated),
                    Equals("simulate: output time 0.75 s is not after 0.75 s"));
  const std::vector<double> backwards = {0.5, 1.0, 0.8};
  CHECK_THROWS_WITH(doorbench::simulate(door, none, initial, backwards),
                    Equals("simulate: output time 0.8 s is not after 1 s"));
  // One output time is the initial state itself.
  const std::vector<double> only_start = {0.5};
  const Trajectory run = doorbench::simulate(door, none, initial, only_start);
  REQUIRE(run.size() == 1);
  CHECK(run.time_s[0] == 0.5);
  CHECK(run.theta_rad[0] == 0.0);
  CHECK(run.user_work_J == 0.0);
  CHECK(run.term_names.size() == 5);
  CHECK(run.terms_Nm.size() == 5);
}

// The stepper is what a fixed-rate loop (the haptic tick) calls: once constructed, advancing
// through the latch, the stops and the hand's release must not allocate. The counter is the
// global operator new replacement of tests/analysis/test_allocation.cpp.
TEST_CASE("DoorStepper: advancing allocates nothing after construction",
          "[simulator][stepper][allocation]") {
  for (ModelKind kind : {ModelKind::kSensory, ModelKind::kPhysical}) {
    const DoorModel door = doorbench::reference_model(kind);
    const VirtualHand hand(VirtualHandOptions{}, door.geometry().handle_radius_m);
    for (auto method :
         {SimulationOptions::Method::kAdaptive, SimulationOptions::Method::kFixedStep}) {
      SimulationOptions options;
      options.method = method;
      DoorStepper stepper(door, options);
      DoorState state;
      const long long before = doorbench::testing::allocations();
      for (int tick = 1; tick <= 10000; ++tick) stepper.advance(state, tick * 1e-3, hand);
      const long long allocated = doorbench::testing::allocations() - before;
      INFO(to_string(kind) << " model, "
                           << (method == SimulationOptions::Method::kAdaptive ? "adaptive"
                                                                              : "fixed step"));
      CHECK(allocated == 0);
      CHECK(state.time_s == 10.0);  // the whole open-close really ran
      CHECK(stepper.stats().accepted_steps >= 10000);
    }
  }
}

// ---------------------------------------------------------------------------------------
// 6. Virtual hand
// ---------------------------------------------------------------------------------------

TEST_CASE("Virtual hand: the reference trajectory's endpoints and phases", "[virtual_hand]") {
  const VirtualHandOptions options;  // 10 s: rest 1 s, open 3.5 s, pause 1 s, close 3.5 s
  const VirtualHand hand(options, 0.58);
  CHECK(hand.duration_s() == 10.0);

  const VirtualHand::Reference start = hand.reference(0.0);
  CHECK(start.theta_rad == 0.0);
  CHECK(start.omega_rad_s == 0.0);
  CHECK(start.grip == 1.0);
  CHECK(hand.reference(1.0).theta_rad == 0.0);  // the opening starts after the rest
  CHECK_THAT(hand.reference(4.5).theta_rad, WithinAbs(options.target_angle_rad, 1e-12));
  CHECK_THAT(hand.reference(4.5).omega_rad_s, WithinAbs(0.0, 1e-12));
  CHECK_THAT(hand.reference(5.0).theta_rad, WithinAbs(options.target_angle_rad, 1e-12));
  // Minimum jerk: half way in the middle, at the peak speed 1.875 Δθ / T.
  CHECK_THAT(hand.reference(2.75).theta_rad, WithinAbs(0.5 * options.target_angle_rad, 1e-12));
  CHECK_THAT(hand.reference(2.75).omega_rad_s,
             WithinAbs(1.875 * options.target_angle_rad / 3.5, 1e-12));
  CHECK_THAT(hand.reference(9.0).theta_rad, WithinAbs(-options.closing_overshoot_rad, 1e-12));
  CHECK_THAT(hand.reference(7.25).theta_rad,
             WithinAbs(0.5 * (options.target_angle_rad - options.closing_overshoot_rad), 1e-12));
  CHECK(hand.reference(7.25).omega_rad_s < 0);
  CHECK_THAT(hand.reference(10.0).theta_rad, WithinAbs(-options.closing_overshoot_rad, 1e-12));

  // Strokes: 1 while opening [1, 4.5), 2 while closing and holding [5.5, 9.3), else 0.
  CHECK(hand.stroke_at(0.5) == 0);
  CHECK(hand.stroke_at(1.0) == 1);
  CHECK(hand.stroke_at(4.49) == 1);
  CHECK(hand.stroke_at(4.5) == 0);
  CHECK(hand.stroke_at(5.49) == 0);
  CHECK(hand.stroke_at(5.5) == 2);
  CHECK(hand.stroke_at(9.29) == 2);
  CHECK(hand.stroke_at(9.31) == 0);
  CHECK(hand.stroke_at(9.9) == 0);

  // Grip: held through the hold (to 9.3 s), smoothly let go over 0.2 s.
  CHECK(hand.reference(9.3).grip == 1.0);
  CHECK_THAT(hand.reference(9.4).grip, WithinAbs(0.5, 1e-12));
  CHECK(hand.reference(9.5).grip == 0.0);
  CHECK(hand.reference(9.8).grip == 0.0);

  // A short run: the 0.5 s of hold and release shrink in proportion to the 0.2 s final
  // rest (hold 0.12 s, release 0.08 s), so the hand has let go by the end.
  VirtualHandOptions short_options;
  short_options.duration_s = 2.0;
  const VirtualHand short_hand(short_options, 0.58);
  CHECK_THAT(short_hand.reference(1.8).theta_rad,
             WithinAbs(-short_options.closing_overshoot_rad, 1e-12));
  CHECK(short_hand.reference(1.91).grip == 1.0);
  CHECK_THAT(short_hand.reference(1.96).grip, WithinAbs(0.5, 1e-9));
  CHECK(short_hand.reference(2.0).grip == 0.0);
  CHECK(short_hand.stroke_at(1.91) == 2);
  CHECK(short_hand.stroke_at(1.93) == 0);
  CHECK(short_hand.force_N(2.0, 1.0, 0.0) == 0.0);
}

TEST_CASE("Virtual hand: the force is a clamped PD grip that lets go", "[virtual_hand]") {
  VirtualHandOptions options;
  const VirtualHand hand(options, 0.58);
  // At rest on target: a small error gives stiffness · arc error + damping · arc rate error.
  CHECK_THAT(hand.force_N(0.5, -0.01, 0.02),
             WithinAbs(2000.0 * 0.58 * 0.01 + 60.0 * 0.58 * -0.02, 1e-12));
  // A large error saturates at max_force_N in either direction.
  CHECK(hand.force_N(4.5, 0.0, 0.0) == 250.0);
  CHECK(hand.force_N(0.5, 1.0, 0.0) == -250.0);
  // Half let go: half the (clamped) force.
  CHECK_THAT(hand.force_N(9.4, 1.0, 0.0), WithinAbs(-125.0, 1e-9));
  // Released: nothing, whatever the door does.
  CHECK(hand.force_N(9.5, 1.0, 0.0) == 0.0);
  CHECK(hand.force_N(9.9, -0.5, 3.0) == 0.0);

  options.max_force_N = 40.0;
  const VirtualHand weak(options, 0.58);
  CHECK(weak.force_N(4.5, 0.0, 0.0) == 40.0);
  CHECK(weak.force_N(4.5, 0.0, 1e6) == -40.0);
}

TEST_CASE("Virtual hand: options are validated with a message naming the option",
          "[virtual_hand]") {
  CHECK(VirtualHandOptions{}.validate().empty());
  auto message_with = [](auto change) {
    VirtualHandOptions options;
    change(options);
    return options.validate();
  };
  const std::string fractions =
      "virtual hand fractions must leave time for the closing: 2 * rest + opening + pause "
      "<= 0.95";
  const std::string hold = "virtual hand hold_s must be >= 0 and release_s > 0";
  const std::string gains =
      "virtual hand stiffness_N_per_m and max_force_N must be > 0, damping_N_s_per_m >= 0";
  CHECK(message_with([](VirtualHandOptions& o) { o.target_angle_rad = 0; }) ==
        "virtual hand target_angle_rad must be > 0");
  CHECK(message_with([](VirtualHandOptions& o) { o.duration_s = -1; }) ==
        "virtual hand duration_s must be > 0");
  CHECK(message_with([](VirtualHandOptions& o) { o.opening_fraction = 0.75; }) == fractions);
  CHECK(message_with([](VirtualHandOptions& o) { o.rest_fraction = -0.1; }) == fractions);
  CHECK(message_with([](VirtualHandOptions& o) { o.opening_fraction = 0; }) == fractions);
  CHECK(message_with([](VirtualHandOptions& o) { o.closing_overshoot_rad = -0.01; }) ==
        "virtual hand closing_overshoot_rad must be >= 0");
  CHECK(message_with([](VirtualHandOptions& o) { o.hold_s = -0.1; }) == hold);
  CHECK(message_with([](VirtualHandOptions& o) { o.release_s = 0; }) == hold);
  CHECK(message_with([](VirtualHandOptions& o) { o.hold_s = INFINITY; }) == hold);
  CHECK(message_with([](VirtualHandOptions& o) { o.rest_fraction = 0; }) ==
        "virtual hand rest_fraction must be > 0 (the hand lets go then)");
  // A hold and release longer than the final rest are allowed: they shrink to fit.
  CHECK(message_with([](VirtualHandOptions& o) { o.hold_s = 0.9; }).empty());
  CHECK(message_with([](VirtualHandOptions& o) { o.stiffness_N_per_m = 0; }) == gains);
  CHECK(message_with([](VirtualHandOptions& o) { o.damping_N_s_per_m = -1; }) == gains);
  CHECK(message_with([](VirtualHandOptions& o) { o.max_force_N = 0; }) == gains);

  VirtualHandOptions bad;
  bad.duration_s = 0;
  CHECK_THROWS_WITH(VirtualHand(bad, 0.58), Equals("virtual hand duration_s must be > 0"));
  CHECK_THROWS_WITH(VirtualHand(VirtualHandOptions{}, 0.0),
                    Equals("virtual hand: handle radius must be > 0"));
}

// ---------------------------------------------------------------------------------------
// 7. Run summary
// ---------------------------------------------------------------------------------------

TEST_CASE("Run summary: the sensory reference door's demo run", "[run_summary]") {
  const DoorModel door = doorbench::reference_model(ModelKind::kSensory);
  const Trajectory run = hand_run(door, SimulationOptions{});
  const doorbench::RunSummary summary = doorbench::summarize_run(door, run);
  // The spec's approximate peaks (§2): (k θ1 + k_inf (θ1 − θ0)) / r_h and d1 / r_h.
  const double spec_unlatch_N = (40.0 * 0.02793 + 1054.0 * (0.02793 - 0.00698)) / 0.58;
  const double spec_latch_N = 767.0 * (0.06109 - 0.0384) / 0.58;
  const double spec_friction_N = 2.6 / 0.58;
  REQUIRE_THAT(spec_unlatch_N, WithinAbs(40.0, 0.1));
  WARN("summary: peak unlatch " << summary.peak_unlatch_force_N << " N (spec ~" << spec_unlatch_N
                                << "), peak latch " << summary.peak_latch_force_N << " N (spec ~"
                                << spec_latch_N << "), free friction "
                                << summary.free_movement_friction_N << " N (spec ~"
                                << spec_friction_N << ")");
  CHECK_THAT(summary.peak_unlatch_force_N, WithinRel(spec_unlatch_N, 0.15));
  CHECK_THAT(summary.free_movement_friction_N, WithinRel(spec_friction_N, 0.20));
  CHECK_THAT(summary.peak_latch_force_N, WithinRel(spec_latch_N, 0.25));
  // The run itself: opened to about the target, closed and latched at the end.
  CHECK_THAT(summary.largest_angle_rad, WithinAbs(1.3963, 0.05));
  CHECK(summary.final_angle_rad < 0.02);
  CHECK(summary.largest_opening_hand_force_N > summary.peak_unlatch_force_N);
  CHECK(summary.largest_opening_hand_force_N <= 250.0);
  CHECK(summary.largest_speed_rad_s > 1.875 * 1.3963 / 3.5 * 0.8);
  CHECK_THAT(summary.final_angle_rad, WithinAbs(run.theta_rad.back(), 0.0));
}

// Fractions that add up to exactly 1 in decimal (2·0.1 + 0.7 + 0.1) sum to 0.9999999999999999
// in binary and pass `2 * rest + opening + pause < 1`, leaving a closing of zero length
// (closing_start_s = closing_end_s = 9 s). minimum_jerk then divides 0 by 0 at t = 9 s
// and the hand's force there is NaN — at an output time of a 1 kHz run.
TEST_CASE("Virtual hand: fractions leaving no closing are refused or harmless", "[virtual_hand]") {
  VirtualHandOptions options;
  options.opening_fraction = 0.7;
  const bool refused = !options.validate().empty();
  INFO("validate() says: '" << options.validate() << "'");
  if (!refused) {
    const VirtualHand hand(options, 0.58);
    const double force = hand.force_N(9.0, 0.0, 0.0);
    INFO("force at t = 9 s: " << force << " N");
    CHECK(std::isfinite(hand.reference(9.0).theta_rad));
    CHECK(std::isfinite(force));
    // A 1 kHz run lands on t = 9 s, where the NaN force stops it.
    const DoorModel door = doorbench::reference_model(ModelKind::kSensory);
    CHECK_NOTHROW(hand_run(door, SimulationOptions{}, options));
  } else {
    CHECK(refused);
  }
}

// The stepper caches the derivative at the start of the next step (first-same-as-last)
// and keys the cache on the state's time only. A caller that moves the state (multiple
// shooting from a measured state, spec §6) or changes the hand at the same time must
// still get the same answer as a fresh stepper.
TEST_CASE("Simulator: a reused stepper follows a state changed between advances",
          "[simulator][stepper]") {
  const DoorModel door = frictionless_physical_door();
  const SmoothHand hand(0.2, 1.2, 1.0, door.geometry().handle_radius_m);
  for (auto method :
       {SimulationOptions::Method::kAdaptive, SimulationOptions::Method::kFixedStep}) {
    SimulationOptions options;
    options.method = method;
    DoorStepper reused(door, options);
    DoorState state{0.0, 0.2, 0.0, 0.0};
    reused.advance(state, 0.5, hand);
    // A new start at the same time: another angle and rate.
    DoorState restarted{0.5, state.theta_rad + 0.1, state.omega_rad_s - 0.5, 0.0};
    DoorState fresh_state = restarted;
    reused.advance(restarted, 0.6, hand);
    DoorStepper fresh(door, options);
    fresh.advance(fresh_state, 0.6, hand);
    INFO((method == SimulationOptions::Method::kAdaptive ? "adaptive" : "fixed step")
         << ": theta reused " << restarted.theta_rad << " vs fresh " << fresh_state.theta_rad
         << ", omega reused " << restarted.omega_rad_s << " vs fresh " << fresh_state.omega_rad_s);
    CHECK_THAT(restarted.theta_rad, WithinAbs(fresh_state.theta_rad, 1e-8));
    CHECK_THAT(restarted.omega_rad_s, WithinAbs(fresh_state.omega_rad_s, 1e-6));
    CHECK_THAT(restarted.user_work_J, WithinAbs(fresh_state.user_work_J, 1e-8));
  }
}
