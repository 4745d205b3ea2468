#pragma once
// Integrates the door's equation of motion J dω/dt = τ_u + τ_m(θ, ω) (door-models.md §1).
//
// Method: explicit Dormand–Prince 5(4) with error control on θ and ω (or, for
// convergence studies and fixed-rate loops, the same 5th-order formula at a fixed
// step). The latch switches are about 0.08° wide; error control shrinks the step
// there and lets it grow in free movement. Step, tolerances and the measured error
// are in docs/simulator.md.
//
// The model is constant; the state (DoorState) is the mutable part; a DoorStepper
// owns scratch space only and allocates nothing after construction.
#include <span>
#include <string>
#include <vector>

#include "analysis/model/door_model.h"

namespace doorbench {

// The force the user's hand applies at the handle, tangent to its arc (N, positive =
// opening), as a function of time and the door's state.
class UserForce {
 public:
  virtual ~UserForce() = default;
  virtual double force_N(double time_s, double theta_rad, double omega_rad_s) const = 0;
};

// A recorded force, linearly interpolated between samples, held at the ends.
// Thread safety: immutable; safe to share.
class RecordedForce final : public UserForce {
 public:
  // Times must be strictly increasing and as many as forces (throws otherwise).
  RecordedForce(std::vector<double> time_s, std::vector<double> force_N);
  double force_N(double time_s, double theta_rad, double omega_rad_s) const override;

 private:
  std::vector<double> time_s_;
  std::vector<double> force_N_;
};

struct SimulationOptions {
  enum class Method { kAdaptive, kFixedStep };
  Method method = Method::kAdaptive;
  // Error control (adaptive): a step is accepted when, for θ and ω, the local error
  // estimate is below absolute + relative · |value|.
  double relative_tolerance = 1e-7;
  double angle_tolerance_rad = 1e-9;
  double rate_tolerance_rad_s = 1e-7;
  double max_step_s = 1e-3;   // also never beyond the next output time
  double min_step_s = 1e-10;  // below this the run fails rather than crawl
  // Below this average step the run fails rather than crawl (adaptive): at most this many
  // steps (accepted and rejected) per second of door, counted from the stepper's first
  // advance (at least one second's worth). The reference door needs about 1400; a door
  // whose parameters make the equation stiff (an out-of-bounds friction of 1e6 N·m) would
  // otherwise take minutes for a minute of door.
  double max_steps_per_s = 1e5;
  // Fixed-step method: the step, shortened where needed to land on output times.
  double fixed_step_s = 1e-4;

  // Empty when usable, else a one-line message naming the option.
  std::string validate() const;
};

struct DoorState {
  double time_s = 0.0;
  double theta_rad = 0.0;
  double omega_rad_s = 0.0;
  double user_work_J = 0.0;  // ∫ τ_u ω dt since the start, integrated with the state
};

struct StepperStats {
  long accepted_steps = 0;
  long rejected_steps = 0;
  long torque_evaluations = 0;
  double smallest_step_s = 0.0;
  double largest_step_s = 0.0;
};

// Advances a DoorState with error control. Keeps the step size between calls so that
// advancing output interval by output interval costs no more than one long advance.
// Thread safety: one stepper per thread; the model may be shared.
class DoorStepper {
 public:
  // Keeps a reference to `model` (the constant part), which must outlive the stepper.
  DoorStepper(const DoorModel& model, const SimulationOptions& options);

  // Advances `state` to `end_time_s` under `hand`. Throws std::runtime_error when the
  // step would have to fall below min_step_s, the steps exceed max_steps_per_s, or the state
  // stops being finite; the message names the stiffest term there and every parameter
  // outside its bounds (stiffness_diagnosis).
  void advance(DoorState& state, double end_time_s, const UserForce& hand);
  const StepperStats& stats() const { return stats_; }

 private:
  struct Derivative {
    double theta, omega, work;
  };
  Derivative derivative(double time_s, double theta, double omega, const UserForce& hand);
  // One Dormand–Prince step of size h from `state` (with its derivative k1); returns
  // the scaled error norm and fills the candidate state and its derivative.
  double try_step(const DoorState& state, const Derivative& k1, double h, const UserForce& hand,
                  DoorState& candidate, Derivative& k7);

  const DoorModel& model_;
  SimulationOptions options_;
  double inertia_kg_m2_;
  double next_step_s_;
  // The derivative at the end of the last step, reused (first same as last) only when the
  // next advance starts from that very state under the same hand.
  bool have_derivative_ = false;
  Derivative k1_{};
  DoorState k1_state_{};
  const UserForce* k1_hand_ = nullptr;
  double first_time_s_ = 0.0;  // of the first advance
  bool started_ = false;
  StepperStats stats_;
};

// The simulator's output: the spec's CSV exchange columns plus every term.
struct Trajectory {
  std::vector<double> time_s, theta_rad, omega_rad_s, force_N, tau_u_Nm, tau_m_Nm;
  std::vector<std::string> term_names;
  std::vector<std::vector<double>> terms_Nm;  // [term][sample]
  std::vector<int> stroke;                    // empty unless the hand defines strokes
  double handle_radius_m = 0.0;
  double user_work_J = 0.0;
  StepperStats stats;

  std::size_t size() const { return time_s.size(); }
};

// Why the equation of `model` is stiff at (θ, ω): the term whose torque changes fastest
// with ω or θ, as a time constant with the model's inertia, and every parameter outside its
// bounds, e.g. "the stiffest term is friction (time constant 4e-08 s); parameters outside
// their bounds: d1 = 1e+06 (bounds 0 to 20)".
std::string stiffness_diagnosis(const DoorModel& model, double theta_rad, double omega_rad_s);

// Runs from `initial` (its time is the first output time) and records every output
// time, which must be strictly increasing.
Trajectory simulate(const DoorModel& model, const UserForce& hand, const DoorState& initial,
                    std::span<const double> output_times_s, const SimulationOptions& options = {});

}  // namespace doorbench
