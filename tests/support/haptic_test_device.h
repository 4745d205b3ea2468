#pragma once
// A small rotary admittance device for the render loop's tests (the real simulated devices
// are haptic/simulated_hapticmaster.* and haptic/rotary_device.*): J θ'' = τ_command + τ_hand,
// integrated in simulated time by advance_to(), with a hand that pulls the door along a
// reference angle by a spring-damper. It counts the calls the loop makes.
#include <cmath>
#include <functional>

#include "haptic/device.h"

namespace doorbench::testing {

class RotaryTestDevice final : public haptic::HapticDevice {
 public:
  std::function<double(double)> reference_angle_rad = [](double) { return 0.0; };
  double hand_stiffness_Nm_per_rad = 200.0;
  double hand_damping_Nm_s_per_rad = 5.0;

  std::string name() const override { return "test:rotary"; }
  haptic::DeviceLimits limits() const override {
    haptic::DeviceLimits limits;
    limits.kinematics = haptic::Kinematics::kRotary1;
    limits.max_force = 50.0;
    limits.max_force_rate = 1e5;
    limits.max_velocity = 20.0;
    limits.workspace_min = haptic::Vec3(-0.5, 0.0, 0.0);
    limits.workspace_max = haptic::Vec3(2.5, 0.0, 0.0);
    limits.min_inertia = 0.01;
    limits.max_inertia = 10.0;
    return limits;
  }
  void start(double inertia) override {
    inertia_ = inertia;
    started = true;
  }
  void stop() noexcept override { stopped = true; }
  haptic::DeviceSample read() noexcept override {
    haptic::DeviceSample sample;
    sample.time_s = time_s_;
    sample.position = haptic::Vec3(theta_, 0.0, 0.0);
    sample.velocity = haptic::Vec3(omega_, 0.0, 0.0);
    sample.measured_force = haptic::Vec3(hand_torque(), 0.0, 0.0);
    sample.sequence = ++sequence_;
    return sample;
  }
  void command_force(const haptic::Vec3& force) noexcept override { command_ = force.x(); }
  void command_inertia(double inertia) noexcept override {
    inertia_ = inertia;
    ++inertia_commands;
  }
  // Counts the calls and holds the rotor still from then on, as a device's brake would.
  void brake() noexcept override {
    ++brake_calls;
    braked = true;
  }

  void advance_to(double time_s) {
    constexpr double kStep = 1e-4;
    while (time_s_ + 0.5 * kStep < time_s) {
      if (braked) {
        omega_ = 0.0;
        time_s_ += kStep;
        continue;
      }
      const double acceleration = (command_ + hand_torque()) / inertia_;
      omega_ += acceleration * kStep;
      theta_ += omega_ * kStep;
      time_s_ += kStep;
    }
  }
  double inertia() const { return inertia_; }
  double command() const { return command_; }

  bool started = false, stopped = false, braked = false;
  int brake_calls = 0;
  int inertia_commands = 0;

 private:
  double hand_torque() const {
    return hand_stiffness_Nm_per_rad * (reference_angle_rad(time_s_) - theta_) -
           hand_damping_Nm_s_per_rad * omega_;
  }
  double time_s_ = 0.0, theta_ = 0.0, omega_ = 0.0, command_ = 0.0, inertia_ = 1.0;
  std::uint64_t sequence_ = 0;
};

}  // namespace doorbench::testing
