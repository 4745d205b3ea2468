#pragma once
// The 1-DOF rotary device profile (Kinematics::kRotary1): a motor on the door's own axis
// (docs/haptic-devices.md). x is the angle in rad, the rate in rad/s, the torque in N*m
// (positive = opening); y and z are 0. No arc and no constraint: DoorMapping is the identity.
//
// SimulatedRotaryDevice: a rotor with a torque sensor between it and the handle, driven
// either
//  - by admittance (the default, like the HapticMaster): the drive moves the rotor as an
//    inertia J_r (start(inertia)/command_inertia, at least the rotor's own inertia) under the
//    sensed torque plus the command, so the device renders the door's inertia; or
//  - by impedance (render_inertia_by_admittance = false): the command is a motor torque on
//    the bare rotor (its own inertia only); limits() then say min/max_inertia 0 and the host
//    must render the door's inertia itself.
// The encoder is quantized (counts per revolution); the rate is the quantized angle's
// difference low-pass filtered, as a drive estimates it. The torque sensor has Gaussian
// noise. The virtual hand acts as the torque r_h·F of a VirtualHand at the real handle
// radius, with optional tangential push pulses (torque r_h·amplitude).
#include "haptic/simulated_hapticmaster.h"

namespace doorbench::haptic {

// An example profile for a plausible bench motor (a direct-drive torque motor with a
// torque sensor): 30 N*m peak, 20 N*m continuous; not a measured device.
DeviceLimits example_rotary_limits();

struct SimulatedRotaryOptions {
  SimulatedDeviceOptions device{.clock = SimClock::kManual,
                                .servo_rate_hz = 2500.0,
                                .control_delay_s = 0.001,
                                .force_noise_rms = 0.05,
                                .seed = 1,
                                .max_steps_per_read = 250,
                                .start_time_s = 0.0};
  DeviceLimits limits = example_rotary_limits();
  bool render_inertia_by_admittance = true;
  double rotor_inertia_kg_m2 = 0.02;
  double encoder_counts_per_rev = 131072.0;  // 17 bit; 0 = no quantization
  double rate_filter_hz = 300.0;             // the drive's rate estimate
  double viscous_friction_Nm_s_per_rad = 0.0;
  double initial_angle_rad = 0.0;
  double stop_stiffness_Nm_per_rad = 2000.0;  // the workspace's end stops (limits' x range)
  double stop_damping_Nm_s_per_rad = 20.0;
  std::string validate() const;
};

struct RotaryHandOptions {
  VirtualHandOptions hand;
  double handle_radius_m = 0.58;
  bool repeat = false;  // repeat the open-close cycle every hand.duration_s
  PushOptions pushes;   // only the amplitude, duration and rate count: along the arc
  std::string validate() const;
};

class SimulatedRotaryDevice final : public SimulatedDevice {
 public:
  explicit SimulatedRotaryDevice(const SimulatedRotaryOptions& options = {});

  std::string name() const override { return "sim:rotary"; }
  DeviceLimits limits() const override { return limits_; }

  void set_hand(const RotaryHandOptions& hand);  // set-up call; the hand's time starts at start()
  void clear_hand() noexcept { has_hand_ = false; }

 protected:
  void integrate_step(double t_s, double dt_s) noexcept override;
  DeviceSample make_sample() const noexcept override;
  void reset_state() noexcept override;
  const DeviceLimits& device_limits() const noexcept override { return limits_; }

 private:
  double quantize(double angle_rad) const noexcept;

  SimulatedRotaryOptions options_;
  DeviceLimits limits_;
  double angle_rad_ = 0.0, rate_rad_s_ = 0.0;
  double encoder_angle_rad_ = 0.0, estimated_rate_rad_s_ = 0.0;
  bool has_hand_ = false;
  RotaryHandOptions hand_options_;
  VirtualHand hand_{VirtualHandOptions{}, 0.58};
  double next_push_s_ = 1e300, push_start_s_ = 0.0, push_sign_ = 1.0;
  bool pushing_ = false;
};

}  // namespace doorbench::haptic
