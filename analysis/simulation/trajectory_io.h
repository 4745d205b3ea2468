#pragma once
// Between simulator runs and the CSV exchange format (door-models.md §5.1).
#include <string>

#include "acquisition/session/recording_csv.h"
#include "analysis/simulation/simulator.h"

namespace doorbench {

// A recording of the run: time_s, force_N, angle_rad, rate_rad_s, stroke (when the run
// has strokes), then tau_u_Nm (user torque), tau_Nm (τ_m) and one tau_<term>_Nm per term.
Recording to_recording(const Trajectory& run, const std::string& source_description);

// The recorded force of a recording and its first state: θ from angle_rad (else 0), ω
// from rate_rad_s (else from the first two angles, else 0).
RecordedForce recorded_force(const Recording& recording);
DoorState initial_state(const Recording& recording);

}  // namespace doorbench
