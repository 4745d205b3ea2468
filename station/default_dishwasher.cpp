// The built-in dishwasher (station/scene.h): boxes for the cabinet, the door and its handle.
#include <cmath>

#include "core/units.h"
#include "station/scene.h"

namespace doorbench::station {
namespace {

// Appends an axis-aligned box [lo, hi] as 12 outward-facing triangles.
void append_box(MeshPart& part, const Vec3& lo, const Vec3& hi) {
  // Each face: its normal axis and sign; the corners in counter-clockwise order seen from
  // outside.
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = 0; side < 2; ++side) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      const double w = side == 0 ? lo[axis] : hi[axis];
      std::array<Vec3, 4> corners;
      const double us[4] = {lo[u], hi[u], hi[u], lo[u]};
      const double vs[4] = {lo[v], lo[v], hi[v], hi[v]};
      for (int k = 0; k < 4; ++k) {
        corners[k][axis] = w;
        corners[k][u] = us[k];
        corners[k][v] = vs[k];
      }
      if (side == 0) std::swap(corners[1], corners[3]);
      Vec3 normal{0.0, 0.0, 0.0};
      normal[axis] = side == 0 ? -1.0 : 1.0;
      for (const int k : {0, 1, 2, 0, 2, 3}) {
        for (int c = 0; c < 3; ++c) {
          part.positions_m.push_back(static_cast<float>(corners[k][c]));
          part.normals.push_back(static_cast<float>(normal[c]));
        }
      }
    }
  }
}

}  // namespace

Scene default_scene() {
  Scene scene;
  scene.source = "built-in dishwasher";
  scene.camera.vertical_fov_rad = 40.0 * kRadPerDeg;
  const auto part = [](const char* name, bool moves, const Rgb& rgb) {
    MeshPart made;
    made.name = name;
    made.moves_with_door = moves;
    made.rgb = rgb;
    return made;
  };
  MeshPart cabinet = part("cabinet", false, scene.colours.cabinet);
  append_box(cabinet, {-0.3, 0.0, -0.57}, {0.3, 0.85, -0.005});  // the body behind the door
  append_box(cabinet, {-0.3, 0.0, -0.005}, {0.3, 0.095, 0.03});  // the plinth below it
  MeshPart door = part("door", true, scene.colours.door);
  append_box(door, {-0.3, 0.1, 0.0}, {0.3, 0.82, 0.04});
  MeshPart handle = part("handle", true, scene.colours.handle);
  append_box(handle, {-0.2, 0.665, 0.04}, {0.2, 0.695, 0.075});
  scene.parts = {std::move(cabinet), std::move(door), std::move(handle)};
  return scene;
}

Vec3 door_point_at(const Scene& scene, const Vec3& closed_point_m, double theta_rad) {
  // Rodrigues' rotation of the point's offset from the hinge about the (unit) axis.
  const Vec3& k = scene.hinge_axis;
  Vec3 r;
  for (int i = 0; i < 3; ++i) r[i] = closed_point_m[i] - scene.hinge_point_m[i];
  const Vec3 k_cross_r{k[1] * r[2] - k[2] * r[1], k[2] * r[0] - k[0] * r[2],
                       k[0] * r[1] - k[1] * r[0]};
  const double k_dot_r = k[0] * r[0] + k[1] * r[1] + k[2] * r[2];
  const double c = std::cos(theta_rad), s = std::sin(theta_rad);
  Vec3 out;
  for (int i = 0; i < 3; ++i) {
    out[i] = scene.hinge_point_m[i] + r[i] * c + k_cross_r[i] * s + k[i] * k_dot_r * (1.0 - c);
  }
  return out;
}

}  // namespace doorbench::station
