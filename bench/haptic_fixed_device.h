#pragma once
// A device that costs nothing: it returns the end-effector moving along the handle's arc at a
// steady rate and ignores commands. What remains of a tick's time is the tick's own.
#include <cmath>

#include "haptic/device.h"
#include "haptic/door_mapping.h"

namespace doorbench::bench {

class FixedPathDevice final : public haptic::HapticDevice {
 public:
  explicit FixedPathDevice(const haptic::DoorMapping& mapping) : mapping_(mapping) {}
  std::string name() const override { return "bench:fixed-path"; }
  haptic::DeviceLimits limits() const override {
    haptic::DeviceLimits limits;
    limits.workspace_min = haptic::Vec3::Constant(-0.2);
    limits.workspace_max = haptic::Vec3::Constant(0.2);
    limits.max_velocity = 10.0;
    limits.min_inertia = 1.0;
    limits.max_inertia = 100.0;
    return limits;
  }
  void start(double) override {}
  void stop() noexcept override {}
  haptic::DeviceSample read() noexcept override {
    // Sweeps 0 … 1.4 rad and back every 4 s of ticks at 1 kHz: latch, snap and free movement.
    ++sequence_;
    const double phase = 2.0 * 3.14159265358979 * static_cast<double>(sequence_ % 4000) / 4000.0;
    const double theta = 0.7 * (1.0 - std::cos(phase));
    const double omega = 0.7 * std::sin(phase) * 2.0 * 3.14159265358979 / 4.0;
    haptic::DeviceSample sample;
    sample.time_s = static_cast<double>(sequence_) * 1e-3;
    sample.position = mapping_.point_at(theta);
    sample.velocity = mapping_.velocity_at(theta, omega);
    sample.measured_force = 10.0 * mapping_.tangent_at(theta);
    sample.sequence = sequence_;
    return sample;
  }
  void command_force(const haptic::Vec3& force) noexcept override { last_ = force; }
  void command_inertia(double) noexcept override {}
  void brake() noexcept override {}
  haptic::Vec3 last_command() const { return last_; }

 private:
  const haptic::DoorMapping& mapping_;
  std::uint64_t sequence_ = 0;
  haptic::Vec3 last_ = haptic::Vec3::Zero();
};

}  // namespace doorbench::bench
