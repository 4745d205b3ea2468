#pragma once
// A robust start for the sensory model's latch, read off the force–angle curve of the
// strokes near closed (docs/fitting.md, "The start"). The latch switches are about 0.08°
// wide, so the cost is very rough in θ0…θ3 and a local solver stalls unless these start
// within about a switch width of the truth (door-models.md §6).
//
// With R = r_h F_u − J dω/dt (the torque the mechanism resists with; dω/dt from a central
// difference over ±5 ms and J from the start model):
//
// - opening: R rises as k θ below θ0 and (k + k_inf) θ − k_inf θ0 above it, then falls
//   where the latch releases. A continuous two-line (hinge) fit of R against θ over the
//   rise gives k_inf (the change of slope) and θ0 (the break); θ1 is the angle of the
//   peak, corrected for where k_inf (θ − θ0) S̄(θ; θ1, β) peaks: θ1 = θ_peak +
//   ln(2β (θ_peak − θ0) − 1) / (2β);
// - closing: the mechanism's torque −R is flat above θ3 and rises as k_lock (θ3 − θ)
//   below it, until it peaks near θ2 and falls (the snap pulls the door in). A hinge fit
//   gives k_lock and θ3; θ2 = θ_peak − ln(2β (θ3 − θ_peak) − 1) / (2β).
//
// Each stroke gives its own reading; the start is the median over strokes.
#include <optional>
#include <string>
#include <vector>

#include "analysis/model/door_model.h"
#include "analysis/preprocessing/strokes.h"

namespace doorbench {

struct LatchReadOff {
  std::optional<double> theta0_rad, theta1_rad, theta2_rad, theta3_rad;
  std::optional<double> k_inf_Nm_per_rad, k_lock_Nm_per_rad;
  int opening_strokes = 0;  // strokes that gave a reading
  int closing_strokes = 0;
  std::vector<std::string> notes;  // why a reading is missing
};

// dω/dt at every sample of a stroke: the central difference over ±half_width_s (one-sided
// at the ends and at the recording's gaps, which no difference spans: stroke_gaps). Used by the
// read-off and by the equation-error start.
std::vector<double> rate_derivative(const Stroke& stroke, double half_width_s = 0.005);

// `start` supplies J, β and θ_max (only a sensory model is read); `rate_noise_rad_s`
// decides when the door counts as moving (|ω| > 3 σ_ω).
LatchReadOff read_latch_start(const PreparedData& data, const DoorModel& start,
                              double rate_noise_rad_s);

}  // namespace doorbench
