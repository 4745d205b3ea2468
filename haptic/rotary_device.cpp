#include "haptic/rotary_device.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace doorbench::haptic {

DeviceLimits example_rotary_limits() {
  DeviceLimits limits;
  limits.kinematics = Kinematics::kRotary1;
  limits.max_force = 30.0;                      // N*m peak (the safety layer's own limit is lower)
  limits.max_force_rate = 3000.0;               // N*m/s
  limits.max_velocity = 6.0;                    // rad/s: far above a door's few rad/s
  limits.workspace_min = Vec3(-0.3, 0.0, 0.0);  // rad: a little past closed ...
  limits.workspace_max = Vec3(1.9, 0.0, 0.0);   // ... and past the door's 90° stop
  limits.min_inertia = 0.02;                    // the rotor's own inertia
  limits.max_inertia = 5.0;                     // kg*m^2
  return limits;
}

std::string SimulatedRotaryOptions::validate() const {
  if (std::string problem = device.validate(); !problem.empty()) return problem;
  if (limits.kinematics != Kinematics::kRotary1) return "limits.kinematics must be kRotary1";
  if (!(limits.max_force > 0.0) || !std::isfinite(limits.max_force)) {
    return "limits.max_force must be > 0";
  }
  if (!(limits.workspace_min.x() < limits.workspace_max.x())) {
    return "limits.workspace_min.x must be below workspace_max.x";
  }
  if (!(rotor_inertia_kg_m2 > 0.0) || !std::isfinite(rotor_inertia_kg_m2)) {
    return "rotor_inertia_kg_m2 must be > 0";
  }
  if (render_inertia_by_admittance &&
      (!(limits.min_inertia >= rotor_inertia_kg_m2) ||
       !(limits.max_inertia >= limits.min_inertia) || !std::isfinite(limits.max_inertia))) {
    return "limits.min_inertia must be >= rotor_inertia_kg_m2 and <= max_inertia";
  }
  if (!(encoder_counts_per_rev >= 0.0) || !std::isfinite(encoder_counts_per_rev)) {
    return "encoder_counts_per_rev must be >= 0";
  }
  if (!(rate_filter_hz > 0.0) || !std::isfinite(rate_filter_hz))
    return "rate_filter_hz must be > 0";
  if (!(initial_angle_rad >= limits.workspace_min.x() &&
        initial_angle_rad <= limits.workspace_max.x())) {
    return "initial_angle_rad must be inside the workspace";
  }
  if (!(viscous_friction_Nm_s_per_rad >= 0.0) || !(stop_stiffness_Nm_per_rad >= 0.0) ||
      !(stop_damping_Nm_s_per_rad >= 0.0) ||
      !std::isfinite(viscous_friction_Nm_s_per_rad + stop_stiffness_Nm_per_rad +
                     stop_damping_Nm_s_per_rad)) {
    return "viscous_friction_Nm_s_per_rad, stop_stiffness_Nm_per_rad and "
           "stop_damping_Nm_s_per_rad must be >= 0";
  }
  return "";
}

std::string RotaryHandOptions::validate() const {
  if (std::string problem = hand.validate(); !problem.empty()) return problem;
  if (!(handle_radius_m > 0.0) || !std::isfinite(handle_radius_m)) {
    return "handle_radius_m must be > 0";
  }
  return pushes.validate();
}

namespace {
const SimulatedRotaryOptions& checked(const SimulatedRotaryOptions& options) {
  if (std::string problem = options.validate(); !problem.empty()) {
    throw std::invalid_argument(std::string("sim:rotary: ").append(problem));
  }
  return options;
}
}  // namespace

SimulatedRotaryDevice::SimulatedRotaryDevice(const SimulatedRotaryOptions& options)
    : SimulatedDevice(checked(options).device), options_(options), limits_(options.limits) {
  if (!options.render_inertia_by_admittance) {  // an impedance device renders no inertia
    limits_.min_inertia = 0.0;
    limits_.max_inertia = 0.0;
  }
  angle_rad_ = options.initial_angle_rad;
  encoder_angle_rad_ = quantize(angle_rad_);
  truth_.position = Vec3(angle_rad_, 0.0, 0.0);
}

void SimulatedRotaryDevice::set_hand(const RotaryHandOptions& hand) {
  if (std::string problem = hand.validate(); !problem.empty()) {
    throw std::invalid_argument(std::string("sim:rotary hand: ").append(problem));
  }
  hand_options_ = hand;
  hand_ = VirtualHand(hand.hand, hand.handle_radius_m);
  has_hand_ = true;
}

double SimulatedRotaryDevice::quantize(double angle_rad) const noexcept {
  if (!(options_.encoder_counts_per_rev > 0.0)) return angle_rad;
  const double count_rad = 2.0 * std::numbers::pi / options_.encoder_counts_per_rev;
  return std::floor(angle_rad / count_rad) * count_rad;
}

void SimulatedRotaryDevice::reset_state() noexcept {
  angle_rad_ = options_.initial_angle_rad;
  rate_rad_s_ = 0.0;
  encoder_angle_rad_ = quantize(angle_rad_);
  estimated_rate_rad_s_ = 0.0;
  pushing_ = false;
  next_push_s_ = next_push_time(start_time_s(), hand_options_.pushes.rate_hz, uniform());
  truth_.position = Vec3(angle_rad_, 0.0, 0.0);
  truth_.velocity = Vec3::Zero();
  // The impedance device: the rotor's inertia whatever start() was given.
  if (!options_.render_inertia_by_admittance) truth_.inertia = options_.rotor_inertia_kg_m2;
}

void SimulatedRotaryDevice::integrate_step(double t_s, double dt_s) noexcept {
  double hand_torque = 0.0, push_torque = 0.0;
  if (has_hand_) {
    double hand_time_s = t_s - start_time_s();
    if (hand_options_.repeat) hand_time_s = std::fmod(hand_time_s, hand_.duration_s());
    const VirtualHand::Reference ref = hand_.reference(hand_time_s);
    truth_.hand_theta_ref_rad = ref.theta_rad;
    truth_.hand_omega_ref_rad_s = ref.omega_rad_s;
    truth_.hand_grip = ref.grip;
    hand_torque =
        hand_options_.handle_radius_m * hand_.force_N(hand_time_s, angle_rad_, rate_rad_s_);
    const PushOptions& pushes = hand_options_.pushes;
    if (pushes.rate_hz > 0.0) {
      if (!pushing_ && t_s >= next_push_s_) {
        pushing_ = true;
        push_start_s_ = t_s;
        push_sign_ = uniform() < 0.5 ? -1.0 : 1.0;
        ++truth_.pushes;
      }
      if (pushing_) {
        const double phase = (t_s - push_start_s_) / pushes.duration_s;
        if (phase >= 1.0) {
          pushing_ = false;
          next_push_s_ = next_push_time(t_s, pushes.rate_hz, uniform());
        } else {
          push_torque = push_sign_ * hand_options_.handle_radius_m * pushes.amplitude_N *
                        std::sin(std::numbers::pi * phase);
        }
      }
    }
  }
  const Vec3 position(angle_rad_, 0.0, 0.0), velocity(rate_rad_s_, 0.0, 0.0);
  truth_.hand_force = Vec3(hand_torque, 0.0, 0.0);
  truth_.push_force = Vec3(push_torque, 0.0, 0.0);
  const Vec3 external = external_force(t_s, position, velocity);
  truth_.external_force = Vec3(external.x(), 0.0, 0.0);
  const double user_torque = hand_torque + push_torque + external.x();
  truth_.user_force = Vec3(user_torque, 0.0, 0.0);
  const double measured = user_torque + noise();
  measured_force_ = Vec3(measured, 0.0, 0.0);

  double stop = 0.0;
  const double below = limits_.workspace_min.x() - angle_rad_;
  const double above = angle_rad_ - limits_.workspace_max.x();
  if (below > 0.0) {
    stop = options_.stop_stiffness_Nm_per_rad * below -
           options_.stop_damping_Nm_s_per_rad * std::min(rate_rad_s_, 0.0);
  } else if (above > 0.0) {
    stop = -options_.stop_stiffness_Nm_per_rad * above -
           options_.stop_damping_Nm_s_per_rad * std::max(rate_rad_s_, 0.0);
  }
  truth_.wall_force = Vec3(stop, 0.0, 0.0);

  // Admittance: the rotor follows J_r under the sensed torque plus the command. Impedance: the
  // bare rotor under the true hand torque plus the motor's.
  if (braked()) {  // the device's brake holds the rotor
    rate_rad_s_ = 0.0;
    estimated_rate_rad_s_ = 0.0;
    truth_.position = Vec3(angle_rad_, 0.0, 0.0);
    truth_.velocity = Vec3::Zero();
    return;
  }
  const bool admittance = options_.render_inertia_by_admittance;
  const double inertia = admittance ? truth_.inertia : options_.rotor_inertia_kg_m2;
  const double drive = (admittance ? measured : user_torque) + truth_.applied_command.x() + stop -
                       options_.viscous_friction_Nm_s_per_rad * rate_rad_s_;
  rate_rad_s_ += dt_s * drive / inertia;
  angle_rad_ += dt_s * rate_rad_s_;
  truth_.position = Vec3(angle_rad_, 0.0, 0.0);
  truth_.velocity = Vec3(rate_rad_s_, 0.0, 0.0);

  // The drive's rate estimate: the encoder's difference, low-pass filtered.
  const double encoder = quantize(angle_rad_);
  const double raw_rate = (encoder - encoder_angle_rad_) / dt_s;
  encoder_angle_rad_ = encoder;
  const double alpha = 1.0 - std::exp(-2.0 * std::numbers::pi * options_.rate_filter_hz * dt_s);
  estimated_rate_rad_s_ += alpha * (raw_rate - estimated_rate_rad_s_);
}

DeviceSample SimulatedRotaryDevice::make_sample() const noexcept {
  DeviceSample sample;
  sample.position = Vec3(encoder_angle_rad_, 0.0, 0.0);
  sample.velocity = Vec3(estimated_rate_rad_s_, 0.0, 0.0);
  sample.measured_force = measured_force_;
  return sample;
}

}  // namespace doorbench::haptic
