#pragma once
// A virtual hand standing in for a person: a PD (impedance) controller on the handle
// that tracks a reference trajectory — rest, a minimum-jerk opening to a target angle,
// a pause, a minimum-jerk closing that aims a little past closed (as a person pushes a
// door shut through its latch), a short hold, and release.
#include <string>

#include "analysis/simulation/simulator.h"

namespace doorbench {

struct VirtualHandOptions {
  double target_angle_rad = 1.3963;  // 80°: short of the fully open stop
  double duration_s = 10.0;          // the whole run, split by the fractions below
  double rest_fraction = 0.1;        // before the opening, and again at the end
  double opening_fraction = 0.35;
  double pause_fraction = 0.1;          // the closing takes what is left
  double closing_overshoot_rad = 0.05;  // the closing aims this far past closed
  // After the closing the hand keeps pushing for hold_s, then lets go over release_s; both
  // shrink in proportion when they do not fit in the final rest (short runs).
  double hold_s = 0.3;
  double release_s = 0.2;
  double stiffness_N_per_m = 2000.0;  // along the handle's arc: a firm human grip
  double damping_N_s_per_m = 60.0;
  double max_force_N = 250.0;  // a person's push is limited

  // Empty when usable, else a one-line message naming the option.
  std::string validate() const;
};

// Thread safety: immutable; safe to share.
class VirtualHand final : public UserForce {
 public:
  VirtualHand(const VirtualHandOptions& options, double handle_radius_m);

  struct Reference {
    double theta_rad;
    double omega_rad_s;
    double grip;  // 1 while the hand holds the handle, falling to 0 as it lets go
  };
  Reference reference(double time_s) const { return reference(time_s, options_.target_angle_rad); }
  double force_N(double time_s, double theta_rad, double omega_rad_s) const override {
    return force_N(time_s, theta_rad, omega_rad_s, options_.target_angle_rad);
  }
  // The same with the closing planned from `closing_from_rad` instead of the target: a
  // person starts closing from where the door is (it may have run past the target).
  Reference reference(double time_s, double closing_from_rad) const;
  double force_N(double time_s, double theta_rad, double omega_rad_s,
                 double closing_from_rad) const;
  // 1 during the opening, 2 during the closing (through the hold), 0 otherwise.
  int stroke_at(double time_s) const;
  double duration_s() const { return options_.duration_s; }

 private:
  VirtualHandOptions options_;
  double handle_radius_m_;
  double hold_s_, release_s_;  // as used: shrunk to fit the final rest
  double opening_start_s_, opening_end_s_, closing_start_s_, closing_end_s_;
};

}  // namespace doorbench
