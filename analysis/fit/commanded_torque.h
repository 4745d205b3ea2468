#pragma once
// The torque a haptic playback commanded (docs/inverse-design.md, "Playback recordings").
//
// A playback session (haptic/tick_recorder.h) records, at every tick, the door model's
// torque τ_m at the tick's own angle and rate. Those three channels are the played feel
// without the device in it: the recorded motion also carries the device's rendering (its
// control delay, admittance and servo), which the door model does not have, and a fit of
// the motion moves design parameters to absorb it (a 1 ms delay on the latch's snap made
// the seal stiffer by 230 % in the demo). Fitting the physical model's torque map to τ_m
// recovers what was played; the inertia, which τ_m does not contain, still comes from the
// motion.
//
//   std::optional<CommandedTorque> played = read_commanded_torque("tobe.h5");
//   // nullopt: not a playback recording (no model_torque channel)
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "analysis/model/door_model.h"
#include "analysis/fit/fitting.h"

namespace doorbench {

struct CommandedTorque {
  std::string source;  // the session
  std::vector<double> theta_rad;
  std::vector<double> omega_rad_s;
  std::vector<double> torque_Nm;  // τ_m at (θ, ω), positive = opening
  // Every `decimation`-th tick is kept (successive ticks repeat nearly the same state).
  int decimation = 1;
};

// The angle, rate and model_torque channels of a playback session, non-finite samples
// dropped, every `decimation`-th tick kept. nullopt when the session has no model_torque
// channel. Throws SessionError for a file that cannot be read and std::invalid_argument
// when the three channels differ in length (naming the session).
std::optional<CommandedTorque> read_commanded_torque(const std::filesystem::path& session_path,
                                                     int decimation = 2);

// The fit of a model's torque map to commanded torques.
struct CommandedTorqueFit {
  explicit CommandedTorqueFit(DoorModel fitted) : model(std::move(fitted)) {}
  DoorModel model;                  // start's parameters with the free ones fitted
  std::vector<double> uncertainty;  // every parameter; NaN when not free
  double rms_error_Nm = 0.0;        // of τ_m − τ_cmd over the samples
  double data_cost = 0.0;           // ½ Σ r² of the data residuals, r = error / scale
  double reduced_data_cost = 0.0;   // Σ r² / (n − p)
  int samples = 0;
  int iterations = 0;
  bool converged = false;
  std::string termination;
};

// Fits `free` (names; none of them the inertia, which τ_m does not contain) of `start` to
// the commanded torques, residuals (τ_cmd − τ_m(θ, ω)) / torque_scale_Nm, with `priors`
// (FitOptions::priors' meaning) on free parameters; bounds from `start`. Uses options'
// solver settings and threads. The uncertainties are classical, (JᵀJ)⁻¹ scaled by the
// reduced data cost. Throws std::invalid_argument for no samples, an unknown or inertia
// parameter in `free`, or a torque_scale_Nm that is not > 0. (τ_m does not depend on the
// handle radius, so any radius serves.)
CommandedTorqueFit fit_commanded_torque(const DoorModel& start,
                                        const std::vector<CommandedTorque>& data,
                                        const std::vector<std::string>& free,
                                        const std::vector<ParameterPrior>& priors,
                                        const FitOptions& options, double torque_scale_Nm);

}  // namespace doorbench
