#pragma once
// The HapticMaster's figures (docs/hapticmaster.md, "limits"): the limits doorbench assumes
// before the device reports its own, and the box of the workspace that fits inside the
// cylindrical sector the device reports. Pure functions: safe from any thread.
#include "haptic/device.h"

namespace doorbench::haptic {

// The HapticMaster's figures: where each comes from is in docs/hapticmaster.md (limits).
DeviceLimits hapticmaster_limits();

// The largest box (symmetric in y) inside the cylindrical sector r ∈ [r0, r1], φ ∈ [φ0, φ1],
// z ∈ [z0, z1] about the base axis `axis_behind_origin_m` behind the origin along x, in the
// device frame (x radial at φ = 0, as the public client draws it). Scans
// the box's half width: its corners must keep r0 <= r <= r1 and |φ| <= the smaller |φ| bound.
void workspace_box(const Vec3& r_phi_z_min, const Vec3& r_phi_z_max, double axis_behind_origin_m,
                   DeviceLimits& limits);

}  // namespace doorbench::haptic
