#pragma once
// Draws the scene with OpenGL's fixed-function pipeline (a compatibility context, as the
// viewer's GLFW window gives): the static parts as they are, the door's parts turned by θ
// about the hinge, lit by one directional light. Call from the thread whose context is
// current.
#include "station/scene.h"
#include "station/view.h"

namespace doorbench::station {

struct Viewport {
  int x = 0, y = 0, width = 1, height = 1;  // framebuffer pixels, OpenGL's (y upwards)
};

// Clears the viewport to the background and draws the door at theta_rad seen by `eye`.
void draw_scene(const Scene& scene, double theta_rad, Eye eye, const Viewport& viewport);

}  // namespace doorbench::station
