#pragma once
// The few numbers a person reads off an opening-closing run.
#include <string>

#include "analysis/model/door_model.h"
#include "analysis/simulation/simulator.h"

namespace doorbench {

struct RunSummary {
  // The mechanism's largest resistance at the handle (N) near closed (θ < latch_zone_rad),
  // end stops left out: while opening (to unlatch) and while closing (to latch).
  double peak_unlatch_force_N = 0.0;
  double peak_latch_force_N = 0.0;
  // The hand's largest push in each direction (N).
  double largest_opening_hand_force_N = 0.0;
  double largest_closing_hand_force_N = 0.0;
  double largest_speed_rad_s = 0.0;
  double largest_angle_rad = 0.0;
  // Median dry + viscous friction felt at the handle (N) in free movement:
  // latch_zone_rad < θ < θ_max − 0.1 and |ω| > 0.05 rad/s: the terms named "*friction*",
  // "stribeck" and "viscous_damping".
  double free_movement_friction_N = 0.0;
  double final_angle_rad = 0.0;
};

inline constexpr double kLatchZoneRad = 0.1;

RunSummary summarize_run(const DoorModel& model, const Trajectory& run);
std::string format_summary(const RunSummary& summary);

}  // namespace doorbench
