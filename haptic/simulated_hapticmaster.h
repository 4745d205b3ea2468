#pragma once
// Simulated haptic devices (docs/haptic-devices.md): the machinery both simulated devices
// share (the clock, the control delay, the sensor noise, the misbehaviour the safety tests
// inject) and the simulated HapticMaster, a 3-DOF admittance device with a virtual user's
// hand on its end-effector.
//
// Time has two modes:
//  - kManual (tests, the demo, benchmarks): the owner calls advance_to(time_s) between ticks;
//    read() returns the state at the current simulated time and never moves it;
//  - kRealTime: read() first advances the simulation to CLOCK_MONOTONIC now (computation
//    only, at most max_steps_per_read servo steps per call; time beyond that is skipped and
//    counted in the truth's skipped_steps). The simulated time begins at the first read()
//    after start(), not at start(): the virtual user starts when the render loop does, as
//    long as the start-up (the session file, the threads) took.
// The device integrates its own dynamics at servo_rate_hz between the owner's ticks.
//
// Thread safety: one thread makes every call (the owner's tick thread in both modes, or the
// set-up thread while no tick runs). read(), command_force(), command_inertia(),
// advance_to() and truth() never allocate, lock or do I/O.
#include <atomic>
#include <cstdint>
#include <functional>
#include <random>
#include <string>

#include "analysis/simulation/virtual_hand.h"
#include "haptic/device.h"
#include "haptic/door_mapping.h"

namespace doorbench::haptic {

enum class SimClock { kManual, kRealTime };

// Options every simulated device has.
struct SimulatedDeviceOptions {
  SimClock clock = SimClock::kManual;
  double servo_rate_hz = 2500.0;   // the HapticMaster's servo rate
  double control_delay_s = 0.001;  // a command acts this long after command_force()
  double force_noise_rms = 0.1;    // N per axis (rotary: N*m), Gaussian, on the force sensor
  std::uint64_t seed = 1;          // noise, pushes: the same seed gives the same run
  int max_steps_per_read = 250;    // real-time mode: work cap per read() (100 ms at 2500 Hz)
  double start_time_s = 0.0;       // manual mode: the simulated time at start()
  std::string validate() const;    // "" or one line naming the option
};

// What the owner (a test, the demo) can see that a real device would not tell: the truth.
struct SimulatedTruth {
  double time_s = 0.0;
  Vec3 position = Vec3::Zero();         // m (rotary: x = rad), exact (no quantization)
  Vec3 velocity = Vec3::Zero();         // m/s (rotary: rad/s), exact
  Vec3 hand_force = Vec3::Zero();       // N (rotary: N*m): the hand's grip, without pushes
  Vec3 push_force = Vec3::Zero();       // N (rotary: N*m): the current push pulse
  Vec3 external_force = Vec3::Zero();   // N (rotary: N*m): the scripted force
  Vec3 user_force = Vec3::Zero();       // their sum: what the sensor measures before noise
  Vec3 applied_command = Vec3::Zero();  // the command acting now (after delay and clamp)
  Vec3 wall_force = Vec3::Zero();       // the workspace walls (zero inside the box)
  double inertia = 0.0;                 // kg (rotary: kg*m^2), acting now
  double hand_theta_ref_rad = 0.0;      // the hand's reference (0 without a hand)
  double hand_omega_ref_rad_s = 0.0;
  double hand_grip = 0.0;
  std::uint64_t steps = 0;             // servo steps integrated
  std::uint64_t skipped_steps = 0;     // real-time mode: steps skipped by the work cap
  std::uint64_t pushes = 0;            // push pulses begun
  std::uint64_t dropped_commands = 0;  // commands lost to a full delay line or a stalled link
  bool braked = false;                 // brake() acted: zero command, the end-effector held
  double braked_at_s = -1.0;           // when (simulated time), -1 while not braked
};

// Pulses of force off the arc (or along it): a person's hand is not a perfect guide. Pulses
// begin at random (Poisson) times, each a half sine of `amplitude_N` (random sign) lasting
// `duration_s`, in a direction drawn among the enabled ones (at the end-effector's position:
// radial = away from the hinge axis, axial = along it, tangential = along the arc).
struct PushOptions {
  double rate_hz = 0.0;  // mean pulses per second; 0 = no pushes
  double amplitude_N = 20.0;
  double duration_s = 0.1;
  bool radial = true;
  bool axial = true;
  bool tangential = false;
  std::string validate() const;
};

// The virtual user's hand on the end-effector: a VirtualHand's reference (θ_ref(t), ω_ref(t),
// grip) mapped onto the arc by a DoorMapping, held by a 3-D PD grip.
struct SimulatedHandOptions {
  VirtualHandOptions hand;  // reference trajectory and the grip along the handle's arc
  double handle_radius_m = 0.58;
  // The grip's stiffness and damping along the arc are the VirtualHand's scaled by r_h/r_arc
  // (the same force per radian of angle error as on the real handle). Across the arc the grip
  // is this fraction of that: 0 = the hand goes wherever the handle goes off the arc (the
  // worst case for the arc constraint).
  double lateral_grip_fraction = 0.0;
  // Repeat the open-close cycle every hand.duration_s (a user who keeps opening and closing),
  // instead of letting go after one.
  bool repeat = false;
  PushOptions pushes;
  std::string validate() const;
};

// A scripted force on the end-effector (tests): f(time_s, position, velocity), device frame.
// Must not allocate when called.
using ExternalForce = std::function<Vec3(double, const Vec3&, const Vec3&)>;

// What both simulated devices share: clock, delay line, noise, misbehaviour, truth.
class SimulatedDevice : public HapticDevice {
 public:
  explicit SimulatedDevice(const SimulatedDeviceOptions& options);  // throws invalid_argument

  // HapticDevice.
  void start(double inertia) override;  // DeviceError when the inertia is out of range
  void stop() noexcept override;
  DeviceSample read() noexcept override;
  void command_force(const Vec3& force) noexcept override;
  void command_inertia(double inertia) noexcept override;
  // Brakes like the real device's "stop" state: from the next servo step the command is zero
  // and the end-effector stands still (velocity zero) until stop() and start().
  void brake() noexcept override { brake_requested_ = true; }
  // "NAME: the link was lost (a simulated fault)" after lose_link() acted, else "".
  std::string stop_reason() const override;
  // Real-time clock: when the first command after start() acts (its control delay passed).
  double first_command_arrival_s() const noexcept override {
    return first_command_s_.load(std::memory_order_acquire);
  }

  // Manual time: integrate up to `time_s` (no-op when it is not ahead). Also usable in
  // real-time mode to catch up explicitly; the work cap does not apply here.
  void advance_to(double time_s) noexcept;
  double time_s() const noexcept;  // the simulated time now
  const SimulatedTruth& truth() const noexcept { return truth_; }
  const SimulatedDeviceOptions& options() const noexcept { return options_; }

  // Misbehaviour for the safety tests. A stall freezes the link both ways: read() returns
  // the same sample (same sequence) and commands do not reach the device, which keeps acting
  // on the last one it got. A lost link: link_ok false from then on, and the device drops its
  // commanded force to zero (assumed: the real one goes to a safe state). start() clears all.
  void set_stalled(bool stalled) noexcept { stalled_ = stalled; }
  void stall_between(double from_s, double until_s) noexcept;
  void lose_link() noexcept { link_lost_ = true; }
  void lose_link_at(double time_s) noexcept { lose_link_at_s_ = time_s; }

  // A scripted force added to the hand's (set-up call).
  void set_external_force(ExternalForce force) { external_ = std::move(force); }

 protected:
  // One servo step from t_s to t_s + dt_s with truth_.applied_command and truth_.inertia.
  virtual void integrate_step(double t_s, double dt_s) noexcept = 0;
  // The reading after the latest step (measured force: the sensor, with noise).
  virtual DeviceSample make_sample() const noexcept = 0;
  // Back to the initial state at start() (position, hand time, pushes).
  virtual void reset_state() noexcept = 0;
  // The device's inertia range and force clamp.
  virtual const DeviceLimits& device_limits() const noexcept = 0;

  double noise() noexcept { return options_.force_noise_rms * normal_(rng_); }
  double uniform() noexcept { return uniform_(rng_); }
  Vec3 external_force(double t_s, const Vec3& position, const Vec3& velocity) const {
    return external_ ? external_(t_s, position, velocity) : Vec3::Zero();
  }
  double start_time_s() const noexcept { return start_time_s_; }
  // True once brake() has acted: integrate_step must hold the end-effector still.
  bool braked() const noexcept { return truth_.braked; }

  SimulatedTruth truth_;
  Vec3 measured_force_ = Vec3::Zero();  // the sensor's latest (with noise)

 private:
  struct Command {
    double time_s;
    Vec3 force;
    double inertia;
  };
  static constexpr int kDelayLineSize = 1024;

  double now_s() const noexcept;  // the time a command is stamped with
  void step_once() noexcept;
  void push_command(const Vec3& force, double inertia) noexcept;

  SimulatedDeviceOptions options_;
  double dt_s_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  std::uniform_real_distribution<double> uniform_{0.0, 1.0};
  ExternalForce external_;
  bool started_ = false;
  bool ever_started_ = false;
  double start_time_s_ = 0.0;
  std::uint64_t sequence_ = 0;
  Command delay_line_[kDelayLineSize];
  int delay_head_ = 0;  // oldest pending
  int delay_count_ = 0;
  Vec3 last_commanded_ = Vec3::Zero();
  double last_inertia_ = 0.0;
  bool stalled_ = false;
  double stall_from_s_ = 0.0, stall_until_s_ = -1.0;
  std::atomic<bool> link_lost_{false};  // read by stop_reason() from other threads
  std::atomic<double> first_command_s_{kNaN};
  double lose_link_at_s_ = 1e300;
  bool frozen_valid_ = false;
  DeviceSample frozen_;
  bool brake_requested_ = false;
  bool clock_waiting_ = false;  // real time: the clock begins at the first read()
};

struct SimulatedHapticMasterOptions {
  SimulatedDeviceOptions device;
  // About the HapticMaster's published figures (docs/haptic-devices.md): a box of ±0.2 m
  // stands in for its cylindrical workspace, 100 N continuous force, 1 m/s, 2 to 50 kg.
  DeviceLimits limits{.kinematics = Kinematics::kCartesian3,
                      .max_force = 100.0,
                      .max_force_rate = 20000.0,
                      .max_velocity = 1.0,
                      .workspace_min = Vec3::Constant(-0.2),
                      .workspace_max = Vec3::Constant(0.2),
                      .min_inertia = 2.0,
                      .max_inertia = 50.0};
  Vec3 initial_position{-0.075, 0.0, 0.05};  // the default arc's θ = 0 (door_mapping.h)
  double wall_stiffness_N_per_m = 20000.0;   // the workspace's end stops
  double wall_damping_N_s_per_m = 200.0;     // while in a wall
  double viscous_friction_N_s_per_m = 0.0;   // the device's own, if any
  std::string validate() const;
};

class SimulatedHapticMaster final : public SimulatedDevice {
 public:
  explicit SimulatedHapticMaster(const SimulatedHapticMasterOptions& options = {});

  std::string name() const override { return "sim:hapticmaster"; }
  DeviceLimits limits() const override { return options_.limits; }

  // The virtual user's hand (set-up calls). The hand's time starts at start().
  void set_hand(const SimulatedHandOptions& hand, const DoorMapping& mapping);
  void clear_hand() noexcept { has_hand_ = false; }
  // Pushes with no hand (a free device pushed about), or to change them (set-up call).
  void set_pushes(const PushOptions& pushes, const DoorMapping& mapping);

 protected:
  void integrate_step(double t_s, double dt_s) noexcept override;
  DeviceSample make_sample() const noexcept override;
  void reset_state() noexcept override;
  const DeviceLimits& device_limits() const noexcept override { return options_.limits; }

 private:
  Vec3 hand_force(double hand_time_s, const Vec3& position, const Vec3& velocity) noexcept;
  Vec3 push_force(double t_s, const Vec3& position) noexcept;
  Vec3 wall_force(const Vec3& position, const Vec3& velocity) const noexcept;

  SimulatedHapticMasterOptions options_;
  Vec3 position_, velocity_;
  bool has_hand_ = false;
  SimulatedHandOptions hand_options_;
  VirtualHand hand_{VirtualHandOptions{}, 0.58};
  DoorMapping mapping_{Kinematics::kCartesian3, ArcGeometry{}, 0.58};
  double grip_stiffness_N_per_m_ = 0.0, grip_damping_N_s_per_m_ = 0.0;
  PushOptions pushes_;
  double next_push_s_ = 1e300, push_start_s_ = 0.0, push_sign_ = 1.0;
  int push_direction_ = 0;  // 0 radial, 1 axial, 2 tangential
  bool pushing_ = false;
};

// Used by both devices: the next push pulse's start after `after_s` (exponential gaps).
double next_push_time(double after_s, double rate_hz, double uniform01) noexcept;

}  // namespace doorbench::haptic
