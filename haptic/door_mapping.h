#pragma once
// Where the door is on the device: the handle's arc in the device's frame, and the maps
// between the device's Cartesian state and the door's (θ, ω), as the study does by
// converting to cylindrical coordinates about the hinge axis.
//
// For a 3-DOF device the handle moves on an arc of radius arc_radius_m about the hinge
// axis. The arc may be smaller than the real handle radius (the HapticMaster's workspace is
// smaller than a dishwasher door's arc); the angle and the force at the handle are kept and
// the inertia is scaled instead (see inertia_on_device and docs/haptic.md):
//   user force along the arc F_u  ->  door torque  r_h F_u
//   door torque τ                 ->  device force τ / r_h along the arc
//   door inertia J                ->  device mass  J / (r_h · r_arc)
// so that J dω/dt = r_h F_u + τ holds for the angle the hand sees.
//
// Off the arc, the end-effector is pulled back to the cylinder and the plane that contain
// the arc by springs with damping (the constraint). For a rotary device the mapping is the
// identity: θ and ω are the device's angle and rate, torques go straight through.
//
// Thread safety: immutable after construction; every method is noexcept, allocation-free and
// may run in the tick.
#include <string>

#include "haptic/device.h"

namespace doorbench::haptic {

struct ArcGeometry {
  Vec3 hinge_point_m{-0.075, 0.0, -0.1};
  Vec3 hinge_axis{0.0, 1.0, 0.0};         // unit vector; normalized by the mapping
  Vec3 closed_direction{0.0, 0.0, 1.0};   // hinge to handle at θ = 0, ⟂ the axis
  Vec3 opening_direction{1.0, 0.0, 0.0};  // where the handle moves as θ grows, ⟂ both
  double arc_radius_m = 0.15;
  // The constraint that holds the end-effector on the arc (device frame). Tuned on the
  // simulated HapticMaster (1 kHz loop, 1 ms delay, reference door): under ±20 N pushes the
  // end-effector stays within 5 mm of the arc, and it is stable from 2 to 50 kg
  // (docs/haptic-devices.md). The damping matters most: the pushes are short.
  double radial_stiffness_N_per_m = 8000.0;
  double radial_damping_N_s_per_m = 300.0;
  double axial_stiffness_N_per_m = 8000.0;
  double axial_damping_N_s_per_m = 300.0;

  // Empty when usable, else one line naming the field.
  std::string validate() const;
};

// The door's state as the device sees it.
struct DoorPoint {
  double theta_rad = 0.0;
  double omega_rad_s = 0.0;
  double user_force_N = 0.0;    // the user's force along the arc (rotary: torque / r_h)
  double radial_error_m = 0.0;  // distance from the cylinder (+ = outside); 0 for rotary
  double axial_error_m = 0.0;   // distance from the arc's plane; 0 for rotary
};

class DoorMapping {
 public:
  // Throws std::invalid_argument naming the field when the geometry or radius is unusable.
  DoorMapping(Kinematics kinematics, const ArcGeometry& geometry, double handle_radius_m);

  Kinematics kinematics() const noexcept { return kinematics_; }
  const ArcGeometry& geometry() const noexcept { return geometry_; }
  double handle_radius_m() const noexcept { return handle_radius_m_; }

  DoorPoint to_door(const DeviceSample& sample) const noexcept;
  // The device command for a door torque τ (N*m, positive = opening) at `sample`, plus the
  // constraint force that holds a Cartesian end-effector on the arc.
  Vec3 to_device(double door_torque_Nm, const DeviceSample& sample) const noexcept;
  // The constraint force alone (zero for a rotary device).
  Vec3 constraint_force(const DeviceSample& sample) const noexcept;
  // The door torque's part alone: τ / r_h along the arc's tangent (what the host sends when the
  // device holds the end-effector on the arc with its own elements).
  Vec3 torque_to_device(double door_torque_Nm, const DeviceSample& sample) const noexcept;
  // The unit vector from the hinge axis to the arc at θ (Cartesian; rotary: x).
  Vec3 radial_at(double theta_rad) const noexcept;

  // Positions on the arc (Cartesian: m; rotary: x = θ).
  Vec3 point_at(double theta_rad) const noexcept;
  Vec3 tangent_at(double theta_rad) const noexcept;  // unit, direction of opening
  Vec3 velocity_at(double theta_rad, double omega_rad_s) const noexcept;

  // The inertia the device must render for a door of inertia J (kg*m^2): J / (r_h r_arc) kg
  // for a Cartesian device, J for a rotary one.
  double inertia_on_device(double door_inertia_kg_m2) const noexcept;
  // Door torque stiffness (N*m/rad) as stiffness on the device (N/m; rotary: unchanged).
  double stiffness_on_device(double door_stiffness_Nm_per_rad) const noexcept;

  // Empty when the arc from theta_min to theta_max lies inside the device's workspace less
  // `margin` (m), else one line saying which end leaves it and where.
  std::string check_workspace(const DeviceLimits& limits, double theta_min_rad,
                              double theta_max_rad, double margin_m) const;

 private:
  Kinematics kinematics_;
  ArcGeometry geometry_;
  double handle_radius_m_;
};

}  // namespace doorbench::haptic
