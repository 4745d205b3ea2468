#include "station/view.h"

#include <cmath>

namespace doorbench::station {
namespace {

Vec3 minus(const Vec3& a, const Vec3& b) {
  return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}
Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double dot(const Vec3& a, const Vec3& b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
Vec3 unit(const Vec3& a) {
  const double n = std::sqrt(dot(a, a));
  return n > 0.0 ? Vec3{a[0] / n, a[1] / n, a[2] / n} : a;
}

}  // namespace

Mat4 look_at(const Vec3& eye, const Vec3& target, const Vec3& up) {
  const Vec3 f = unit(minus(target, eye));
  const Vec3 s = unit(cross(f, up));
  const Vec3 u = cross(s, f);
  return {s[0], u[0], -f[0], 0.0, s[1],         u[1],         -f[1],       0.0,
          s[2], u[2], -f[2], 0.0, -dot(s, eye), -dot(u, eye), dot(f, eye), 1.0};
}

Mat4 frustum(double left, double right, double bottom, double top, double near_m, double far_m) {
  Mat4 m{};
  m[0] = 2.0 * near_m / (right - left);
  m[5] = 2.0 * near_m / (top - bottom);
  m[8] = (right + left) / (right - left);
  m[9] = (top + bottom) / (top - bottom);
  m[10] = -(far_m + near_m) / (far_m - near_m);
  m[11] = -1.0;
  m[14] = -2.0 * far_m * near_m / (far_m - near_m);
  return m;
}

Mat4 perspective(double vertical_fov_rad, double aspect, double near_m, double far_m) {
  const double top = near_m * std::tan(0.5 * vertical_fov_rad);
  return frustum(-top * aspect, top * aspect, -top, top, near_m, far_m);
}

EyeView eye_view(const Scene& scene, Eye eye, double aspect) {
  const Camera& camera = scene.camera;
  if (eye == Eye::kCentre) {
    return {look_at(camera.position_m, camera.target_m, camera.up),
            perspective(camera.vertical_fov_rad, aspect, camera.near_m, camera.far_m)};
  }
  const Stereo& stereo = scene.stereo;
  const Vec3 forward = unit(minus(camera.target_m, camera.position_m));
  const Vec3 right = unit(cross(forward, camera.up));
  const double offset = (eye == Eye::kLeft ? -0.5 : 0.5) * stereo.eye_separation_m;
  Vec3 position;
  for (int i = 0; i < 3; ++i) position[i] = camera.position_m[i] + offset * right[i];
  Vec3 target;
  for (int i = 0; i < 3; ++i) target[i] = position[i] + forward[i] * stereo.screen_distance_m;
  // The screen's half-size seen from this eye, scaled to the near plane; the screen's
  // aspect is kept whatever the viewport's (a stretched side-by-side half is the display's
  // business).
  (void)aspect;
  const double scale = camera.near_m / stereo.screen_distance_m;
  const double half_w = 0.5 * stereo.screen_width_m, half_h = 0.5 * stereo.screen_height_m;
  return {look_at(position, target, camera.up),
          frustum((-half_w - offset) * scale, (half_w - offset) * scale, -half_h * scale,
                  half_h * scale, camera.near_m, camera.far_m)};
}

}  // namespace doorbench::station
