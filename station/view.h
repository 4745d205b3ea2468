#pragma once
// Where the station's eyes are and what they see (no OpenGL here): the view and projection
// matrices of the mono camera and of each eye in stereo, column-major as OpenGL takes them.
//
// Mono: a perspective of the camera's vertical field of view. Stereo: each eye sits half the
// eye separation to the side of the camera along its right vector, looks parallel to the
// camera's axis, and sees the physical screen (its size, at its distance) through an
// off-axis frustum, so that the door appears at its true size and place in front of the
// participant.
#include <array>

#include "station/scene.h"

namespace doorbench::station {

using Mat4 = std::array<double, 16>;  // column-major

enum class Eye { kCentre, kLeft, kRight };

struct EyeView {
  Mat4 view;
  Mat4 projection;
};

// `aspect` is the viewport's width over its height (of one eye's part in side-by-side and
// top-bottom). Eye::kCentre ignores the stereo settings.
EyeView eye_view(const Scene& scene, Eye eye, double aspect);

Mat4 look_at(const Vec3& eye, const Vec3& target, const Vec3& up);
Mat4 perspective(double vertical_fov_rad, double aspect, double near_m, double far_m);
Mat4 frustum(double left, double right, double bottom, double top, double near_m, double far_m);

}  // namespace doorbench::station
