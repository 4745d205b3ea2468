#pragma once
// The haptic device interface: what the render loop needs from any device that renders the
// door (the HapticMaster over its TCP protocol, the simulated HapticMaster, a 1-DOF rotary
// device on the door's own axis).
//
// Two kinds of call:
//  - set-up calls (start, stop, name, limits) run outside the real-time loop; they may block,
//    allocate and do I/O, and throw DeviceError with a message that names the device;
//  - real-time calls (read, command_force, command_inertia) are made by the render loop's
//    tick at 1-4 kHz. They never block, allocate, lock or do I/O: a driver that talks to
//    hardware exchanges with its own I/O thread through lock-free slots, so read() returns
//    the newest sample that thread has and command_force() leaves a value for it to send.
//
// Coordinates: a Cartesian device (kCartesian3) reports positions in m, velocities in m/s
// and forces in N in its own frame. A rotary device (kRotary1) uses only x: the angle about
// its axis in rad, the rate in rad/s and the torque in N*m (positive = the door's opening
// direction); y and z are 0.
//
// Thread safety: one thread makes the set-up calls; one thread (the tick) makes the
// real-time calls; the two may overlap only as stated on each call.
#include <Eigen/Core>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "core/numbers.h"

namespace doorbench::haptic {

using Vec3 = Eigen::Vector3d;
class DoorMapping;

class DeviceError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;  // messages start with the device's name
};

enum class Kinematics { kCartesian3, kRotary1 };

// The units of a device's own quantities (its position, velocity and force, as DeviceSample and
// DeviceLimits hold them): a Cartesian device's m, m/s and N; a rotary device's rad, rad/s and
// N*m. Sessions label their device channels with them and reports print them.
struct DeviceUnits {
  const char* position;
  const char* velocity;
  const char* force;
};
constexpr DeviceUnits device_units(Kinematics kinematics) {
  return kinematics == Kinematics::kRotary1 ? DeviceUnits{"rad", "rad/s", "N*m"}
                                            : DeviceUnits{"m", "m/s", "N"};
}

// One reading of the device.
struct DeviceSample {
  // Seconds on the host's CLOCK_MONOTONIC (or the simulated clock) when the reading was
  // taken: for a networked device, when its reply arrived.
  double time_s = 0.0;
  Vec3 position = Vec3::Zero();        // m (rotary: x = rad)
  Vec3 velocity = Vec3::Zero();        // m/s (rotary: x = rad/s)
  Vec3 measured_force = Vec3::Zero();  // N, the user's force on the end-effector (rotary: N*m)
  // Increments with every new reading; unchanged between two read() calls = stale (the
  // device or its link stalled). The watchdog counts stale ticks.
  std::uint64_t sequence = 0;
  // False once the link is lost (connection closed, error reply, timeout): the render loop
  // then ramps down and stops.
  bool link_ok = true;
};

// What the device can do; the safety layer takes the smaller of these and its own options.
struct DeviceLimits {
  Kinematics kinematics = Kinematics::kCartesian3;
  double max_force = 100.0;                   // N (rotary: N*m), continuous
  double max_force_rate = 20000.0;            // N/s (rotary: N*m/s)
  double max_velocity = 1.0;                  // m/s (rotary: rad/s)
  Vec3 workspace_min = Vec3::Constant(-0.2);  // m (rotary: x in rad)
  Vec3 workspace_max = Vec3::Constant(0.2);
  // The inertia the device can render by admittance: kg (rotary: kg*m^2). 0/0 for an
  // impedance device that renders no inertia (the host then renders it).
  double min_inertia = 0.0;
  double max_inertia = 0.0;
};

class HapticDevice {
 public:
  virtual ~HapticDevice() = default;

  // Set-up calls (not real-time).
  virtual std::string name() const = 0;  // "hapticmaster://10.0.0.5:7654", "sim:hapticmaster"
  virtual DeviceLimits limits() const = 0;
  // The slow half of the start, made before the playback builds its loop and its session:
  // connects, runs the device's own checks (homing, the workspace read back, the inertia set)
  // and readies what start() needs, without entering the force-controlled state; limits() is
  // then the device's own. start() does it by itself when it was not called. A device without
  // such a half does nothing here.
  virtual void prepare(double inertia) { (void)inertia; }
  // Connects (unless prepared), sets the inertia the device renders (kg; ignored by devices
  // whose limits give max_inertia 0), zeroes the commanded force and enters the
  // force-controlled state. After a prepare() it is quick: the playback calls it just before
  // its first tick.
  virtual void start(double inertia) = 0;
  // Zero force and leave the force-controlled state; safe to call more than once and after a
  // lost link. Never throws.
  virtual void stop() noexcept = 0;
  // Why the device ended the run by itself, as one line that starts with name(): the link lost
  // with its cause (the watchdog's figure, an error reply, a closed connection) and whether the
  // device was left stopped; "" when it did not end the run. The tick sees only
  // DeviceSample::link_ok; this is the text for the user and the session. Set-up thread, or
  // any thread other than the tick's.
  virtual std::string stop_reason() const { return ""; }
  // When (monotonic_now_s(), core/clock.h) the render loop's first command after start() took
  // effect on the device: a networked device's first exchange that carried it was answered, a
  // simulated one took it. NaN until then, and on a simulated clock. Any thread.
  virtual double first_command_arrival_s() const noexcept { return kNaN; }

  // Real-time calls (the tick): never block, allocate, lock or do I/O.
  virtual DeviceSample read() noexcept = 0;
  // The force (N; rotary: torque N*m) the device adds to the user's, in its frame. The
  // safety layer has limited it already; a device may clamp it again to its own limits.
  virtual void command_force(const Vec3& force) noexcept = 0;
  // A new inertia for an admittance device (heaviness tuned live), sent by its I/O thread.
  virtual void command_inertia(double inertia) noexcept = 0;
  // Stops the end-effector's motion at once: zero force and the device's own brake (the
  // HapticMaster: "set state stop", sent by its I/O thread with the next exchange). An
  // admittance device whose force is merely zeroed keeps a free virtual mass moving; this is
  // what the safety layer's velocity and workspace trips, and every final stop, call. The
  // device stays braked until stop() and a new start(). Real-time safe, idempotent.
  virtual void brake() noexcept = 0;

  // Stiff parts on the device (set-up call, before start()): a device that can render
  // springs and dampers at its own servo rate holds the end-effector on the door's arc
  // (`mapping`), stops it at the ends of the door's range [theta_min, theta_max] and adds a
  // permanent damper, all with its own elements, from start() on; the host then sends only the
  // door's torque (DoorMapping::torque_to_device). Returns false when the device cannot (the
  // host renders the constraint, as before). `mapping` must outlive the device's run.
  virtual bool render_stiff_parts_on_device(const DoorMapping& mapping, double theta_min_rad,
                                            double theta_max_rad) {
    (void)mapping;
    (void)theta_min_rad;
    (void)theta_max_rad;
    return false;
  }
};

}  // namespace doorbench::haptic
