#include "analysis/simulation/virtual_hand.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace doorbench {

namespace {
constexpr double kMinimumClosingFraction = 0.05;
}  // namespace

std::string VirtualHandOptions::validate() const {
  auto finite = [](double value) { return std::isfinite(value); };
  if (!finite(target_angle_rad) || target_angle_rad <= 0) {
    return "virtual hand target_angle_rad must be > 0";
  }
  if (!finite(duration_s) || duration_s <= 0) return "virtual hand duration_s must be > 0";
  if (!(rest_fraction >= 0) || !(opening_fraction > 0) || !(pause_fraction >= 0) ||
      2 * rest_fraction + opening_fraction + pause_fraction > 1.0 - kMinimumClosingFraction) {
    return "virtual hand fractions must leave time for the closing: 2 * rest + opening + pause "
           "<= 0.95";
  }
  if (!finite(closing_overshoot_rad) || closing_overshoot_rad < 0) {
    return "virtual hand closing_overshoot_rad must be >= 0";
  }
  if (!(hold_s >= 0) || !(release_s > 0) || !std::isfinite(hold_s + release_s)) {
    return "virtual hand hold_s must be >= 0 and release_s > 0";
  }
  if (rest_fraction <= 0) return "virtual hand rest_fraction must be > 0 (the hand lets go then)";
  if (!(stiffness_N_per_m > 0) || !(damping_N_s_per_m >= 0) || !(max_force_N > 0)) {
    return "virtual hand stiffness_N_per_m and max_force_N must be > 0, damping_N_s_per_m >= 0";
  }
  return "";
}

VirtualHand::VirtualHand(const VirtualHandOptions& options, double handle_radius_m)
    : options_(options), handle_radius_m_(handle_radius_m) {
  if (std::string message = options.validate(); !message.empty()) {
    throw std::invalid_argument(message);
  }
  if (!(handle_radius_m > 0))
    throw std::invalid_argument("virtual hand: handle radius must be > 0");
  const double d = options.duration_s;
  opening_start_s_ = options.rest_fraction * d;
  opening_end_s_ = opening_start_s_ + options.opening_fraction * d;
  closing_start_s_ = opening_end_s_ + options.pause_fraction * d;
  closing_end_s_ = (1.0 - options.rest_fraction) * d;
  const double final_rest_s = options.rest_fraction * d;
  const double fit = std::min(1.0, final_rest_s / (options.hold_s + options.release_s));
  hold_s_ = options.hold_s * fit;
  release_s_ = options.release_s * fit;
}

namespace {

// Minimum-jerk move from `from` to `to` over [start, end]: position and velocity.
void minimum_jerk(double time, double start, double end, double from, double to, double& position,
                  double& velocity) {
  const double span = end - start;
  if (!(span > 0)) {  // no move: already there
    position = time < start ? from : to;
    velocity = 0.0;
    return;
  }
  const double s = std::clamp((time - start) / span, 0.0, 1.0);
  const double s3 = s * s * s;
  position = from + (to - from) * s3 * (10.0 - 15.0 * s + 6.0 * s * s);
  velocity = (to - from) / span * 30.0 * s * s * (1.0 - s) * (1.0 - s);
}

}  // namespace

VirtualHand::Reference VirtualHand::reference(double time_s, double closing_from_rad) const {
  Reference ref{0.0, 0.0, 1.0};
  const double closed = -options_.closing_overshoot_rad;
  if (time_s < closing_start_s_) {
    minimum_jerk(time_s, opening_start_s_, opening_end_s_, 0.0, options_.target_angle_rad,
                 ref.theta_rad, ref.omega_rad_s);
    return ref;
  }
  minimum_jerk(time_s, closing_start_s_, closing_end_s_, closing_from_rad, closed, ref.theta_rad,
               ref.omega_rad_s);
  const double release_start = closing_end_s_ + hold_s_;
  if (time_s > release_start) {
    const double s = std::clamp((time_s - release_start) / release_s_, 0.0, 1.0);
    ref.grip = 1.0 - s * s * (3.0 - 2.0 * s);  // smooth let-go
  }
  return ref;
}

double VirtualHand::force_N(double time_s, double theta_rad, double omega_rad_s,
                            double closing_from_rad) const {
  const Reference ref = reference(time_s, closing_from_rad);
  if (ref.grip <= 0.0) return 0.0;
  // Impedance along the handle's arc: arc length = r_h θ.
  const double arc_error_m = handle_radius_m_ * (ref.theta_rad - theta_rad);
  const double arc_rate_error_m_s = handle_radius_m_ * (ref.omega_rad_s - omega_rad_s);
  const double force =
      options_.stiffness_N_per_m * arc_error_m + options_.damping_N_s_per_m * arc_rate_error_m_s;
  return ref.grip * std::clamp(force, -options_.max_force_N, options_.max_force_N);
}

int VirtualHand::stroke_at(double time_s) const {
  if (time_s >= opening_start_s_ && time_s < opening_end_s_) return 1;
  if (time_s >= closing_start_s_ && time_s < closing_end_s_ + hold_s_) return 2;
  return 0;
}

}  // namespace doorbench
