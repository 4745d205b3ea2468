#include "haptic/simulated_hapticmaster.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "core/clock.h"

namespace doorbench::haptic {
namespace {

bool positive(double value) {
  return value > 0.0 && std::isfinite(value);
}

}  // namespace

std::string SimulatedDeviceOptions::validate() const {
  if (!positive(servo_rate_hz) || servo_rate_hz > 100000.0) {
    return "servo_rate_hz must be > 0 and <= 100000";
  }
  if (!(control_delay_s >= 0.0) || control_delay_s > 0.1) {
    return "control_delay_s must be in [0, 0.1]";
  }
  if (!(force_noise_rms >= 0.0) || !std::isfinite(force_noise_rms)) {
    return "force_noise_rms must be >= 0";
  }
  if (max_steps_per_read < 1) return "max_steps_per_read must be >= 1";
  if (!std::isfinite(start_time_s)) return "start_time_s must be finite";
  return "";
}

std::string PushOptions::validate() const {
  if (!(rate_hz >= 0.0) || !std::isfinite(rate_hz)) return "pushes rate_hz must be >= 0";
  if (!(amplitude_N >= 0.0) || !std::isfinite(amplitude_N)) {
    return "pushes amplitude_N must be >= 0";
  }
  if (!positive(duration_s)) return "pushes duration_s must be > 0";
  if (rate_hz > 0.0 && !radial && !axial && !tangential) {
    return "pushes need at least one of radial, axial, tangential";
  }
  return "";
}

std::string SimulatedHandOptions::validate() const {
  if (std::string problem = hand.validate(); !problem.empty()) return problem;
  if (!positive(handle_radius_m)) return "handle_radius_m must be > 0";
  if (!(lateral_grip_fraction >= 0.0) || lateral_grip_fraction > 10.0) {
    return "lateral_grip_fraction must be in [0, 10]";
  }
  return pushes.validate();
}

double next_push_time(double after_s, double rate_hz, double uniform01) noexcept {
  if (!(rate_hz > 0.0)) return 1e300;
  // Exponential gap; 1 - u is in (0, 1] so the log is finite.
  return after_s - std::log(1.0 - uniform01) / rate_hz;
}

// ---------------------------------------------------------------- SimulatedDevice

SimulatedDevice::SimulatedDevice(const SimulatedDeviceOptions& options)
    : options_(options), dt_s_(0.0), rng_(options.seed) {
  if (std::string problem = options.validate(); !problem.empty()) {
    throw std::invalid_argument(std::string("simulated device: ").append(problem));
  }
  dt_s_ = 1.0 / options.servo_rate_hz;
}

double SimulatedDevice::now_s() const noexcept {
  return options_.clock == SimClock::kRealTime ? monotonic_now_s() : truth_.time_s;
}

double SimulatedDevice::time_s() const noexcept {
  return truth_.time_s;
}

void SimulatedDevice::start(double inertia) {
  const DeviceLimits& limits = device_limits();
  if (limits.max_inertia > 0.0 &&
      (!std::isfinite(inertia) || inertia < limits.min_inertia || inertia > limits.max_inertia)) {
    std::ostringstream message;
    message << name() << ": inertia " << inertia << " outside what it renders ["
            << limits.min_inertia << ", " << limits.max_inertia << "]";
    throw DeviceError(message.str());
  }
  rng_.seed(options_.seed);
  normal_.reset();
  const std::uint64_t keep_sequence = sequence_;
  truth_ = SimulatedTruth{};
  sequence_ = keep_sequence;  // a restarted device keeps counting
  start_time_s_ = options_.clock == SimClock::kRealTime ? monotonic_now_s() : options_.start_time_s;
  truth_.time_s = start_time_s_;
  truth_.inertia = limits.max_inertia > 0.0 ? inertia : 0.0;
  last_inertia_ = truth_.inertia;
  last_commanded_ = Vec3::Zero();
  delay_head_ = delay_count_ = 0;
  stalled_ = false;
  stall_until_s_ = -1.0;
  link_lost_ = false;
  first_command_s_.store(kNaN, std::memory_order_release);
  lose_link_at_s_ = 1e300;
  frozen_valid_ = false;
  brake_requested_ = false;
  measured_force_ = Vec3::Zero();
  reset_state();
  clock_waiting_ = options_.clock == SimClock::kRealTime;
  started_ = true;
  ever_started_ = true;
}

void SimulatedDevice::stop() noexcept {
  started_ = false;
  delay_count_ = 0;
  last_commanded_ = Vec3::Zero();
  truth_.applied_command = Vec3::Zero();
}

void SimulatedDevice::stall_between(double from_s, double until_s) noexcept {
  stall_from_s_ = from_s;
  stall_until_s_ = until_s;
}

std::string SimulatedDevice::stop_reason() const {
  return link_lost_.load(std::memory_order_relaxed)
             ? name() + ": the link was lost (a simulated fault)"
             : std::string();
}

void SimulatedDevice::push_command(const Vec3& force, double inertia) noexcept {
  if (!started_ || link_lost_) return;
  const double t = now_s();
  if (options_.clock == SimClock::kRealTime && std::isnan(first_command_s_.load())) {
    first_command_s_.store(t + options_.control_delay_s, std::memory_order_release);
  }
  const bool in_stall = stalled_ || (t >= stall_from_s_ && t < stall_until_s_);
  if (in_stall) {
    ++truth_.dropped_commands;
    return;
  }
  if (delay_count_ == kDelayLineSize) {  // the owner commands without advancing: drop oldest
    delay_head_ = (delay_head_ + 1) % kDelayLineSize;
    --delay_count_;
    ++truth_.dropped_commands;
  }
  delay_line_[(delay_head_ + delay_count_) % kDelayLineSize] = Command{t, force, inertia};
  ++delay_count_;
}

void SimulatedDevice::command_force(const Vec3& force) noexcept {
  // A non-finite command would be a bug upstream; the device treats it as zero.
  last_commanded_ = force.allFinite() ? force : Vec3::Zero();
  push_command(last_commanded_, last_inertia_);
}

void SimulatedDevice::command_inertia(double inertia) noexcept {
  const DeviceLimits& limits = device_limits();
  if (!(limits.max_inertia > 0.0) || !std::isfinite(inertia)) return;
  last_inertia_ = std::clamp(inertia, limits.min_inertia, limits.max_inertia);
  push_command(last_commanded_, last_inertia_);
}

void SimulatedDevice::step_once() noexcept {
  const double t = truth_.time_s;
  if (t >= lose_link_at_s_) link_lost_ = true;
  // Commands whose delay has passed by the start of this step act during it.
  while (delay_count_ > 0 &&
         delay_line_[delay_head_].time_s + options_.control_delay_s <= t + 1e-9) {
    const Command& command = delay_line_[delay_head_];
    truth_.applied_command = command.force;
    truth_.inertia = command.inertia;
    delay_head_ = (delay_head_ + 1) % kDelayLineSize;
    --delay_count_;
  }
  if (brake_requested_ && !truth_.braked) {
    truth_.braked = true;
    truth_.braked_at_s = t;
  }
  if (!started_ || link_lost_ || truth_.braked) truth_.applied_command = Vec3::Zero();
  // The device's own clamp on the magnitude.
  const double max_force = device_limits().max_force;
  const double magnitude = truth_.applied_command.norm();
  if (magnitude > max_force) truth_.applied_command *= max_force / magnitude;
  integrate_step(t, dt_s_);
  ++truth_.steps;
  ++sequence_;
  truth_.time_s = start_time_s_ + static_cast<double>(truth_.steps + truth_.skipped_steps) * dt_s_;
}

void SimulatedDevice::advance_to(double time_s) noexcept {
  if (!ever_started_) return;  // idle until the first start()
  // Step while the next step's end is not past the target (a little slack for rounding).
  while (truth_.time_s + dt_s_ <= time_s + 1e-9 * dt_s_ + 1e-12) step_once();
}

DeviceSample SimulatedDevice::read() noexcept {
  if (clock_waiting_) {
    // The first read after start(): the simulated time, the hand's cycle and the pushes begin
    // now (the virtual user begins when the door is rendered, however long the start took).
    start_time_s_ = truth_.time_s = monotonic_now_s();
    reset_state();
    clock_waiting_ = false;
  }
  if (options_.clock == SimClock::kRealTime) {
    const double behind_s = monotonic_now_s() - truth_.time_s;
    if (ever_started_ && behind_s > dt_s_) {
      auto steps = static_cast<std::uint64_t>(behind_s / dt_s_);
      const auto cap = static_cast<std::uint64_t>(options_.max_steps_per_read);
      if (steps > cap) {  // fallen behind: skip the time the cap leaves (counted)
        truth_.skipped_steps += steps - cap;
        truth_.time_s =
            start_time_s_ + static_cast<double>(truth_.steps + truth_.skipped_steps) * dt_s_;
        steps = cap;
      }
      for (std::uint64_t i = 0; i < steps; ++i) step_once();
    }
  }
  if (truth_.time_s >= lose_link_at_s_) link_lost_ = true;
  const double t = truth_.time_s;
  const bool in_stall = stalled_ || (t >= stall_from_s_ && t < stall_until_s_);
  if ((in_stall || link_lost_) && frozen_valid_) {  // no new reading: the last one again
    DeviceSample sample = frozen_;
    sample.link_ok = !link_lost_;
    return sample;
  }
  DeviceSample sample = make_sample();
  sample.time_s = t;
  sample.sequence = sequence_;
  sample.link_ok = !link_lost_;
  frozen_ = sample;
  frozen_valid_ = true;
  return sample;
}

// ---------------------------------------------------------------- SimulatedHapticMaster

std::string SimulatedHapticMasterOptions::validate() const {
  if (std::string problem = device.validate(); !problem.empty()) return problem;
  if (limits.kinematics != Kinematics::kCartesian3) return "limits.kinematics must be kCartesian3";
  if (!positive(limits.max_force)) return "limits.max_force must be > 0";
  if (!positive(limits.min_inertia) || !(limits.max_inertia >= limits.min_inertia) ||
      !std::isfinite(limits.max_inertia)) {
    return "limits.min_inertia must be > 0 and <= max_inertia";
  }
  if (!limits.workspace_min.allFinite() || !limits.workspace_max.allFinite() ||
      !(limits.workspace_min.array() < limits.workspace_max.array()).all()) {
    return "limits.workspace_min must be below workspace_max on every axis";
  }
  if (!initial_position.allFinite() ||
      !(initial_position.array() >= limits.workspace_min.array()).all() ||
      !(initial_position.array() <= limits.workspace_max.array()).all()) {
    return "initial_position must be inside the workspace";
  }
  if (!(wall_stiffness_N_per_m >= 0.0) || !(wall_damping_N_s_per_m >= 0.0) ||
      !(viscous_friction_N_s_per_m >= 0.0) ||
      !std::isfinite(wall_stiffness_N_per_m + wall_damping_N_s_per_m +
                     viscous_friction_N_s_per_m)) {
    return "wall_stiffness_N_per_m, wall_damping_N_s_per_m and viscous_friction_N_s_per_m must be "
           ">= 0";
  }
  return "";
}

namespace {
const SimulatedHapticMasterOptions& checked(const SimulatedHapticMasterOptions& options) {
  if (std::string problem = options.validate(); !problem.empty()) {
    throw std::invalid_argument(std::string("sim:hapticmaster: ").append(problem));
  }
  return options;
}
}  // namespace

SimulatedHapticMaster::SimulatedHapticMaster(const SimulatedHapticMasterOptions& options)
    : SimulatedDevice(checked(options).device),
      options_(options),
      position_(options.initial_position),
      velocity_(Vec3::Zero()) {
  truth_.position = position_;
}

void SimulatedHapticMaster::set_hand(const SimulatedHandOptions& hand, const DoorMapping& mapping) {
  if (std::string problem = hand.validate(); !problem.empty()) {
    throw std::invalid_argument(std::string("sim:hapticmaster hand: ").append(problem));
  }
  if (mapping.kinematics() != Kinematics::kCartesian3) {
    throw std::invalid_argument("sim:hapticmaster hand: the door mapping must be Cartesian");
  }
  hand_options_ = hand;
  hand_ = VirtualHand(hand.hand, hand.handle_radius_m);
  mapping_ = mapping;
  // The same force per radian of angle error as the VirtualHand gives on the real handle.
  const double scale = hand.handle_radius_m / mapping.geometry().arc_radius_m;
  grip_stiffness_N_per_m_ = hand.hand.stiffness_N_per_m * scale;
  grip_damping_N_s_per_m_ = hand.hand.damping_N_s_per_m * scale;
  pushes_ = hand.pushes;
  has_hand_ = true;
}

void SimulatedHapticMaster::set_pushes(const PushOptions& pushes, const DoorMapping& mapping) {
  if (std::string problem = pushes.validate(); !problem.empty()) {
    throw std::invalid_argument(std::string("sim:hapticmaster: ").append(problem));
  }
  if (mapping.kinematics() != Kinematics::kCartesian3) {
    throw std::invalid_argument("sim:hapticmaster: the door mapping must be Cartesian");
  }
  mapping_ = mapping;
  pushes_ = pushes;
  hand_options_.pushes = pushes;
}

void SimulatedHapticMaster::reset_state() noexcept {
  position_ = options_.initial_position;
  velocity_ = Vec3::Zero();
  pushing_ = false;
  next_push_s_ = next_push_time(start_time_s(), pushes_.rate_hz, uniform());
  truth_.position = position_;
  truth_.velocity = velocity_;
}

Vec3 SimulatedHapticMaster::hand_force(double hand_time_s, const Vec3& position,
                                       const Vec3& velocity) noexcept {
  if (!has_hand_) return Vec3::Zero();
  if (hand_options_.repeat) hand_time_s = std::fmod(hand_time_s, hand_.duration_s());
  const VirtualHand::Reference ref = hand_.reference(hand_time_s);
  truth_.hand_theta_ref_rad = ref.theta_rad;
  truth_.hand_omega_ref_rad_s = ref.omega_rad_s;
  truth_.hand_grip = ref.grip;
  if (ref.grip <= 0.0) return Vec3::Zero();
  const Vec3 error = mapping_.point_at(ref.theta_rad) - position;
  const Vec3 rate_error = mapping_.velocity_at(ref.theta_rad, ref.omega_rad_s) - velocity;
  // Full grip along the arc's tangent at the reference, a fraction of it across.
  const Vec3 tangent = mapping_.tangent_at(ref.theta_rad);
  const double lateral = hand_options_.lateral_grip_fraction;
  auto split = [&](const Vec3& v) -> Vec3 {
    const Vec3 along = v.dot(tangent) * tangent;
    return along + lateral * (v - along);
  };
  Vec3 force = grip_stiffness_N_per_m_ * split(error) + grip_damping_N_s_per_m_ * split(rate_error);
  const double cap = hand_options_.hand.max_force_N;
  const double magnitude = force.norm();
  if (magnitude > cap) force *= cap / magnitude;
  return ref.grip * force;
}

Vec3 SimulatedHapticMaster::push_force(double t_s, const Vec3& position) noexcept {
  if (!(pushes_.rate_hz > 0.0)) return Vec3::Zero();
  if (!pushing_ && t_s >= next_push_s_) {
    pushing_ = true;
    push_start_s_ = t_s;
    push_sign_ = uniform() < 0.5 ? -1.0 : 1.0;
    int enabled[3];
    int count = 0;
    if (pushes_.radial) enabled[count++] = 0;
    if (pushes_.axial) enabled[count++] = 1;
    if (pushes_.tangential) enabled[count++] = 2;
    push_direction_ = enabled[std::min(count - 1, static_cast<int>(uniform() * count))];
    ++truth_.pushes;
  }
  if (!pushing_) return Vec3::Zero();
  const double phase = (t_s - push_start_s_) / pushes_.duration_s;
  if (phase >= 1.0) {
    pushing_ = false;
    next_push_s_ = next_push_time(t_s, pushes_.rate_hz, uniform());
    return Vec3::Zero();
  }
  const ArcGeometry& geometry = mapping_.geometry();
  const Vec3 axis = mapping_.geometry().hinge_axis.normalized();
  Vec3 direction = axis;
  if (push_direction_ != 1) {
    const Vec3 offset = position - geometry.hinge_point_m;
    Vec3 radial = offset - offset.dot(axis) * axis;
    radial = radial.norm() > 1e-9 ? Vec3(radial.normalized()) : geometry.closed_direction;
    direction = push_direction_ == 0 ? radial : Vec3(axis.cross(radial));
  }
  return push_sign_ * pushes_.amplitude_N * std::sin(std::numbers::pi * phase) * direction;
}

Vec3 SimulatedHapticMaster::wall_force(const Vec3& position, const Vec3& velocity) const noexcept {
  Vec3 force = Vec3::Zero();
  for (int axis = 0; axis < 3; ++axis) {
    const double below = options_.limits.workspace_min[axis] - position[axis];
    const double above = position[axis] - options_.limits.workspace_max[axis];
    if (below > 0.0) {
      force[axis] = options_.wall_stiffness_N_per_m * below -
                    options_.wall_damping_N_s_per_m * std::min(velocity[axis], 0.0);
    } else if (above > 0.0) {
      force[axis] = -options_.wall_stiffness_N_per_m * above -
                    options_.wall_damping_N_s_per_m * std::max(velocity[axis], 0.0);
    }
  }
  return force;
}

void SimulatedHapticMaster::integrate_step(double t_s, double dt_s) noexcept {
  // The forces on the end-effector at the start of the step.
  truth_.hand_force = hand_force(t_s - start_time_s(), position_, velocity_);
  truth_.push_force = push_force(t_s, position_);
  truth_.external_force = external_force(t_s, position_, velocity_);
  truth_.user_force = truth_.hand_force + truth_.push_force + truth_.external_force;
  measured_force_ = truth_.user_force + Vec3(noise(), noise(), noise());
  truth_.wall_force = wall_force(position_, velocity_);
  // Admittance: the controller moves the end-effector as a mass m under the force it
  // measures plus the command (the sensor's noise moves it, too, as on the real device).
  const Vec3 total = measured_force_ + truth_.applied_command + truth_.wall_force -
                     options_.viscous_friction_N_s_per_m * velocity_;
  if (braked()) {  // the device's brake holds the end-effector
    velocity_ = Vec3::Zero();
    truth_.position = position_;
    truth_.velocity = velocity_;
    return;
  }
  // Semi-implicit (symplectic) Euler.
  velocity_ += dt_s * total / truth_.inertia;
  position_ += dt_s * velocity_;
  truth_.position = position_;
  truth_.velocity = velocity_;
}

DeviceSample SimulatedHapticMaster::make_sample() const noexcept {
  DeviceSample sample;
  sample.position = position_;
  sample.velocity = velocity_;
  sample.measured_force = measured_force_;
  return sample;
}

}  // namespace doorbench::haptic
