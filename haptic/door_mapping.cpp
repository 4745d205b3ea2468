#include "haptic/door_mapping.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace doorbench::haptic {
namespace {

bool finite(const Vec3& v) {
  return v.allFinite();
}

}  // namespace

std::string ArcGeometry::validate() const {
  if (!finite(hinge_point_m)) return "hinge_point_m must be finite";
  if (!finite(hinge_axis) || hinge_axis.norm() < 1e-9)
    return "hinge_axis must be a non-zero vector";
  if (!finite(closed_direction) || closed_direction.norm() < 1e-9) {
    return "closed_direction must be a non-zero vector";
  }
  if (!finite(opening_direction) || opening_direction.norm() < 1e-9) {
    return "opening_direction must be a non-zero vector";
  }
  const Vec3 axis = hinge_axis.normalized();
  const Vec3 closed = closed_direction.normalized();
  const Vec3 opening = opening_direction.normalized();
  if (std::abs(axis.dot(closed)) > 1e-6)
    return "closed_direction must be perpendicular to hinge_axis";
  if (std::abs(axis.dot(opening)) > 1e-6) {
    return "opening_direction must be perpendicular to hinge_axis";
  }
  if (std::abs(closed.dot(opening)) > 1e-6) {
    return "opening_direction must be perpendicular to closed_direction";
  }
  if (!(arc_radius_m > 0.0) || !std::isfinite(arc_radius_m)) return "arc_radius_m must be > 0";
  if (!(radial_stiffness_N_per_m >= 0.0) || !std::isfinite(radial_stiffness_N_per_m)) {
    return "radial_stiffness_N_per_m must be >= 0";
  }
  if (!(radial_damping_N_s_per_m >= 0.0) || !std::isfinite(radial_damping_N_s_per_m)) {
    return "radial_damping_N_s_per_m must be >= 0";
  }
  if (!(axial_stiffness_N_per_m >= 0.0) || !std::isfinite(axial_stiffness_N_per_m)) {
    return "axial_stiffness_N_per_m must be >= 0";
  }
  if (!(axial_damping_N_s_per_m >= 0.0) || !std::isfinite(axial_damping_N_s_per_m)) {
    return "axial_damping_N_s_per_m must be >= 0";
  }
  return "";
}

DoorMapping::DoorMapping(Kinematics kinematics, const ArcGeometry& geometry, double handle_radius_m)
    : kinematics_(kinematics), geometry_(geometry), handle_radius_m_(handle_radius_m) {
  if (!(handle_radius_m > 0.0) || !std::isfinite(handle_radius_m)) {
    throw std::invalid_argument("door mapping: handle_radius_m must be > 0");
  }
  if (kinematics_ == Kinematics::kCartesian3) {
    const std::string problem = geometry_.validate();
    if (!problem.empty()) throw std::invalid_argument("door mapping: " + problem);
    geometry_.hinge_axis.normalize();
    geometry_.closed_direction.normalize();
    geometry_.opening_direction.normalize();
  }
}

Vec3 DoorMapping::point_at(double theta_rad) const noexcept {
  if (kinematics_ == Kinematics::kRotary1) return Vec3(theta_rad, 0.0, 0.0);
  return geometry_.hinge_point_m +
         geometry_.arc_radius_m * (std::cos(theta_rad) * geometry_.closed_direction +
                                   std::sin(theta_rad) * geometry_.opening_direction);
}

Vec3 DoorMapping::tangent_at(double theta_rad) const noexcept {
  if (kinematics_ == Kinematics::kRotary1) return Vec3(1.0, 0.0, 0.0);
  return -std::sin(theta_rad) * geometry_.closed_direction +
         std::cos(theta_rad) * geometry_.opening_direction;
}

Vec3 DoorMapping::velocity_at(double theta_rad, double omega_rad_s) const noexcept {
  if (kinematics_ == Kinematics::kRotary1) return Vec3(omega_rad_s, 0.0, 0.0);
  return geometry_.arc_radius_m * omega_rad_s * tangent_at(theta_rad);
}

DoorPoint DoorMapping::to_door(const DeviceSample& sample) const noexcept {
  DoorPoint point;
  if (kinematics_ == Kinematics::kRotary1) {
    point.theta_rad = sample.position.x();
    point.omega_rad_s = sample.velocity.x();
    point.user_force_N = sample.measured_force.x() / handle_radius_m_;
    return point;
  }
  const Vec3 offset = sample.position - geometry_.hinge_point_m;
  const double along_closed = offset.dot(geometry_.closed_direction);
  const double along_opening = offset.dot(geometry_.opening_direction);
  point.theta_rad = std::atan2(along_opening, along_closed);
  const double radius_m = std::hypot(along_closed, along_opening);
  point.radial_error_m = radius_m - geometry_.arc_radius_m;
  point.axial_error_m = offset.dot(geometry_.hinge_axis);
  const Vec3 tangent = tangent_at(point.theta_rad);
  // The angle's rate from the tangential speed at the end-effector's own radius: exact when it
  // is off the arc, too.
  point.omega_rad_s = radius_m > 1e-9 ? sample.velocity.dot(tangent) / radius_m : 0.0;
  point.user_force_N = sample.measured_force.dot(tangent);
  return point;
}

Vec3 DoorMapping::constraint_force(const DeviceSample& sample) const noexcept {
  if (kinematics_ == Kinematics::kRotary1) return Vec3::Zero();
  const Vec3 offset = sample.position - geometry_.hinge_point_m;
  const double axial_m = offset.dot(geometry_.hinge_axis);
  const Vec3 in_plane = offset - axial_m * geometry_.hinge_axis;
  const double radius_m = in_plane.norm();
  Vec3 force = -(geometry_.axial_stiffness_N_per_m * axial_m +
                 geometry_.axial_damping_N_s_per_m * sample.velocity.dot(geometry_.hinge_axis)) *
               geometry_.hinge_axis;
  if (radius_m > 1e-9) {
    const Vec3 radial = in_plane / radius_m;
    force -= (geometry_.radial_stiffness_N_per_m * (radius_m - geometry_.arc_radius_m) +
              geometry_.radial_damping_N_s_per_m * sample.velocity.dot(radial)) *
             radial;
  }
  return force;
}

Vec3 DoorMapping::to_device(double door_torque_Nm, const DeviceSample& sample) const noexcept {
  if (kinematics_ == Kinematics::kRotary1) return Vec3(door_torque_Nm, 0.0, 0.0);
  const DoorPoint point = to_door(sample);
  return door_torque_Nm / handle_radius_m_ * tangent_at(point.theta_rad) + constraint_force(sample);
}

Vec3 DoorMapping::torque_to_device(double door_torque_Nm,
                                   const DeviceSample& sample) const noexcept {
  if (kinematics_ == Kinematics::kRotary1) return Vec3(door_torque_Nm, 0.0, 0.0);
  return door_torque_Nm / handle_radius_m_ * tangent_at(to_door(sample).theta_rad);
}

Vec3 DoorMapping::radial_at(double theta_rad) const noexcept {
  if (kinematics_ == Kinematics::kRotary1) return Vec3(1.0, 0.0, 0.0);
  return (point_at(theta_rad) - geometry_.hinge_point_m) / geometry_.arc_radius_m;
}

double DoorMapping::inertia_on_device(double door_inertia_kg_m2) const noexcept {
  if (kinematics_ == Kinematics::kRotary1) return door_inertia_kg_m2;
  return door_inertia_kg_m2 / (handle_radius_m_ * geometry_.arc_radius_m);
}

double DoorMapping::stiffness_on_device(double door_stiffness_Nm_per_rad) const noexcept {
  if (kinematics_ == Kinematics::kRotary1) return door_stiffness_Nm_per_rad;
  return door_stiffness_Nm_per_rad / (handle_radius_m_ * geometry_.arc_radius_m);
}

std::string DoorMapping::check_workspace(const DeviceLimits& limits, double theta_min_rad,
                                         double theta_max_rad, double margin_m) const {
  constexpr int kChecks = 64;
  for (int i = 0; i <= kChecks; ++i) {
    const double theta = theta_min_rad + (theta_max_rad - theta_min_rad) * i / kChecks;
    const Vec3 point = point_at(theta);
    for (int axis = 0; axis < (kinematics_ == Kinematics::kRotary1 ? 1 : 3); ++axis) {
      if (point[axis] < limits.workspace_min[axis] + margin_m ||
          point[axis] > limits.workspace_max[axis] - margin_m) {
        std::ostringstream message;
        const char* names = "xyz";
        message << "the handle's arc leaves the device's workspace at θ = " << theta
                << " rad: " << names[axis] << " = " << point[axis] << " outside ["
                << limits.workspace_min[axis] + margin_m << ", "
                << limits.workspace_max[axis] - margin_m << "] (workspace less a margin of "
                << margin_m << ")";
        return message.str();
      }
    }
  }
  return "";
}

}  // namespace doorbench::haptic
