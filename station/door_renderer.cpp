#include "station/door_renderer.h"

#include <GL/gl.h>

#include "core/units.h"

namespace doorbench::station {
namespace {

void set_light(const Scene& scene) {
  const Lighting& light = scene.lighting;
  const GLfloat ambient[4] = {GLfloat(light.ambient), GLfloat(light.ambient),
                              GLfloat(light.ambient), 1.0f};
  const GLfloat diffuse[4] = {GLfloat(light.diffuse), GLfloat(light.diffuse),
                              GLfloat(light.diffuse), 1.0f};
  const GLfloat none[4] = {0.0f, 0.0f, 0.0f, 1.0f};
  // w = 0: a direction, in the scene's frame (the view matrix is loaded).
  const GLfloat direction[4] = {GLfloat(light.direction[0]), GLfloat(light.direction[1]),
                                GLfloat(light.direction[2]), 0.0f};
  glEnable(GL_LIGHTING);
  glEnable(GL_LIGHT0);
  glLightModelfv(GL_LIGHT_MODEL_AMBIENT, ambient);
  glLightModeli(GL_LIGHT_MODEL_TWO_SIDE, GL_TRUE);
  glLightfv(GL_LIGHT0, GL_AMBIENT, none);
  glLightfv(GL_LIGHT0, GL_DIFFUSE, diffuse);
  glLightfv(GL_LIGHT0, GL_SPECULAR, none);
  glLightfv(GL_LIGHT0, GL_POSITION, direction);
  glEnable(GL_COLOR_MATERIAL);
  glColorMaterial(GL_FRONT_AND_BACK, GL_AMBIENT_AND_DIFFUSE);
  glEnable(GL_NORMALIZE);
}

void draw_part(const MeshPart& part) {
  glColor3f(part.rgb[0], part.rgb[1], part.rgb[2]);
  glVertexPointer(3, GL_FLOAT, 0, part.positions_m.data());
  glNormalPointer(GL_FLOAT, 0, part.normals.data());
  glDrawArrays(GL_TRIANGLES, 0, GLsizei(part.vertex_count()));
}

}  // namespace

void draw_scene(const Scene& scene, double theta_rad, Eye eye, const Viewport& viewport) {
  glViewport(viewport.x, viewport.y, viewport.width, viewport.height);
  glEnable(GL_SCISSOR_TEST);
  glScissor(viewport.x, viewport.y, viewport.width, viewport.height);
  const Rgb& bg = scene.colours.background;
  glClearColor(bg[0], bg[1], bg[2], 1.0f);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glDisable(GL_SCISSOR_TEST);
  const EyeView view = eye_view(scene, eye, double(viewport.width) / viewport.height);
  glMatrixMode(GL_PROJECTION);
  glLoadMatrixd(view.projection.data());
  glMatrixMode(GL_MODELVIEW);
  glLoadMatrixd(view.view.data());
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDisable(GL_CULL_FACE);
  set_light(scene);
  glEnableClientState(GL_VERTEX_ARRAY);
  glEnableClientState(GL_NORMAL_ARRAY);
  for (const MeshPart& part : scene.parts) {
    if (!part.moves_with_door) draw_part(part);
  }
  const Vec3& h = scene.hinge_point_m;
  const Vec3& axis = scene.hinge_axis;
  glPushMatrix();
  glTranslated(h[0], h[1], h[2]);
  glRotated(theta_rad * kDegPerRad, axis[0], axis[1], axis[2]);
  glTranslated(-h[0], -h[1], -h[2]);
  for (const MeshPart& part : scene.parts) {
    if (part.moves_with_door) draw_part(part);
  }
  glPopMatrix();
  glDisableClientState(GL_NORMAL_ARRAY);
  glDisableClientState(GL_VERTEX_ARRAY);
  glDisable(GL_LIGHTING);
  glDisable(GL_DEPTH_TEST);
}

}  // namespace doorbench::station
