#include "haptic/hapticmaster_limits.h"

#include <algorithm>
#include <cmath>

namespace doorbench::haptic {

DeviceLimits hapticmaster_limits() {
  DeviceLimits limits;
  limits.kinematics = Kinematics::kCartesian3;
  limits.max_force = 250.0;         // N: assumed (recalled datasheet figure, not verified here)
  limits.max_velocity = 1.0;        // m/s: assumed
  limits.max_force_rate = 20000.0;  // N/s: assumed (the interface's default)
  // A box inside the workspace a public example describes (radius 0.28..0.64 m about the
  // base axis, 0.45 m behind the origin; +-0.5 rad; z +-0.2 m), x taken as radial: derived.
  limits.workspace_min = Vec3(-0.14, -0.16, -0.2);
  limits.workspace_max = Vec3(0.16, 0.16, 0.2);
  limits.min_inertia = 2.0;    // kg: the smallest value public examples set; assumed
  limits.max_inertia = 100.0;  // kg: assumed
  return limits;
}

void workspace_box(const Vec3& r_phi_z_min, const Vec3& r_phi_z_max, double axis_behind_origin_m,
                   DeviceLimits& limits) {
  const double r0 = r_phi_z_min.x(), r1 = r_phi_z_max.x();
  const double phi = std::min(std::abs(r_phi_z_min.y()), std::abs(r_phi_z_max.y()));
  double best_area = -1.0, best_half = 0.0, best_x0 = 0.0, best_x1 = 0.0;
  for (int k = 1; k < 1000; ++k) {
    const double half = r1 * static_cast<double>(k) / 1000.0;
    if (half >= r1) break;
    const double x1 = std::sqrt(r1 * r1 - half * half);
    double x0 = std::sqrt(std::max(0.0, r0 * r0 - half * half));
    if (phi < 1.5707) x0 = std::max(x0, half / std::tan(std::max(phi, 1e-6)));
    if (!(x1 > x0)) continue;
    const double area = (x1 - x0) * 2.0 * half;
    if (area > best_area) {
      best_area = area;
      best_half = half;
      best_x0 = x0;
      best_x1 = x1;
    }
  }
  if (best_area <= 0.0) return;  // no box fits: keep the assumed one (the caller checks)
  limits.workspace_min = Vec3(best_x0 - axis_behind_origin_m, -best_half, r_phi_z_min.z());
  limits.workspace_max = Vec3(best_x1 - axis_behind_origin_m, best_half, r_phi_z_max.z());
}

}  // namespace doorbench::haptic
